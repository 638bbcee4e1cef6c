#include "hal/sim/sim_camera.hpp"

#include "hal/clock.hpp"

#include <algorithm>

namespace stria::hal::sim {

SimCamera::SimCamera(SimWorld& world, int frameIntervalUs) :
    world_(world), renderer_(world.rig()), frameIntervalNs_(std::int64_t{std::max(frameIntervalUs, 1)} * 1000)
{
}

Status SimCamera::configure(const CameraConfig& config)
{
    const pipeline::LensModel& lens = world_.rig().rig.camera();
    if (config.width != lens.width || config.height != lens.height)
        return Status::error("camera 'sim': requested " + std::to_string(config.width) + "x" +
                             std::to_string(config.height) + " but the simulated sensor delivers " +
                             std::to_string(lens.width) + "x" + std::to_string(lens.height));
    if (!(config.exposureUs > 0) || !(config.analogueGain >= 1.0))
        return Status::error("camera 'sim': exposure must be > 0 us and gain >= 1 (got " +
                             std::to_string(config.exposureUs) + " us, gain " + std::to_string(config.analogueGain) + ")");
    stop();
    config_ = config;
    settings_ = world_.renderSettings();
    settings_.exposure *= config.exposureUs / kNominalExposureUs * config.analogueGain;
    // Buffers are allocated here, not per frame: render both looks now.
    litValid_ = darkValid_ = false;
    if (Status s = renderInto(true, lit_, litValid_); !s) return s;
    if (Status s = renderInto(false, dark_, darkValid_); !s) return s;
    configured_ = true;
    return Status::ok();
}

Status SimCamera::start()
{
    if (!configured_) return Status::error("camera 'sim': start() before configure()");
    started_ = true;
    epochNs_ = monotonicNs();
    nextFrame_ = 0;
    return Status::ok();
}

void SimCamera::stop() { started_ = false; }

Status SimCamera::renderInto(bool projectorOn, Rendering& out, bool& valid)
{
    if (valid) return Status::ok();
    RenderSettings settings = settings_;
    settings.projectorOn = projectorOn;
    if (Status s = renderer_.render(world_.scene(), settings, out); !s) return s.withContext("camera 'sim': ");
    ++renderCount_;
    valid = true;
    return Status::ok();
}

Result<CapturedFrame> SimCamera::capture(std::chrono::milliseconds timeout)
{
    if (!started_) return Status::error("camera 'sim': capture() while not streaming (call start())");
    const std::int64_t timeoutNs = std::chrono::nanoseconds(timeout).count();
    const std::int64_t now = monotonicNs();
    if (world_.takeCaptureTimeout()) {
        sleepUntilNs(now + timeoutNs);
        return Status::error("camera 'sim': no frame within " + std::to_string(timeout.count()) + " ms");
    }
    // The next frame to finish exposing: sensors stretch the frame time to
    // fit a long exposure.
    const std::int64_t exposureNs = static_cast<std::int64_t>(config_.exposureUs * 1000);
    const std::int64_t intervalNs = std::max(frameIntervalNs_, exposureNs);
    const std::int64_t sinceEpoch = now - epochNs_ - exposureNs;
    std::uint64_t frame = sinceEpoch <= 0 ? 0 : static_cast<std::uint64_t>((sinceEpoch + intervalNs - 1) / intervalNs);
    frame = std::max(frame, nextFrame_);
    const std::int64_t exposureStart = epochNs_ + static_cast<std::int64_t>(frame) * intervalNs;
    const std::int64_t delivered = exposureStart + exposureNs;
    if (delivered - now > timeoutNs) {
        sleepUntilNs(now + timeoutNs);
        return Status::error("camera 'sim': no frame within " + std::to_string(timeout.count()) + " ms");
    }
    sleepUntilNs(delivered);
    nextFrame_ = frame + 1;

    const bool lit = world_.ledOnThroughout(exposureStart, delivered);
    const Rendering& rendering = lit ? lit_ : dark_;
    CapturedFrame out;
    out.view = FrameView{rendering.image.data, rendering.image.cols, rendering.image.rows,
                         static_cast<std::ptrdiff_t>(rendering.image.step), PixelFormat::Bgr8};
    out.sequence = frame;
    out.timestampNs = exposureStart;
    out.exposureUs = config_.exposureUs;
    out.analogueGain = config_.analogueGain;
    return out;
}

}  // namespace stria::hal::sim
