#include "hal/sim/replay_camera.hpp"

#include "hal/clock.hpp"
#include "hal/sim/sim_camera.hpp"

#include <algorithm>
#include <string>

namespace stria::hal::sim {
namespace {

std::string sizeName(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

}  // namespace

Result<std::unique_ptr<ReplayCamera>> ReplayCamera::create(std::vector<cv::Mat> frames, std::int64_t frameIntervalNs)
{
    if (frames.empty()) return Status::error("camera 'replay': no frames to replay");
    if (frameIntervalNs < 0)
        return Status::error("camera 'replay': frame interval " + std::to_string(frameIntervalNs) + " ns is negative");
    for (std::size_t i = 0; i < frames.size(); ++i) {
        const cv::Mat& f = frames[i];
        if (f.type() != CV_8UC3)
            return Status::error("camera 'replay': frame " + std::to_string(i) + " is not 8-bit BGR (CV_8UC3)");
        if (f.size() != frames[0].size())
            return Status::error("camera 'replay': frame " + std::to_string(i) + " is " + sizeName(f.cols, f.rows) +
                                 " but frame 0 is " + sizeName(frames[0].cols, frames[0].rows));
    }
    return std::unique_ptr<ReplayCamera>(new ReplayCamera(std::move(frames), frameIntervalNs));
}

Status ReplayCamera::configure(const CameraConfig& config)
{
    const cv::Mat& first = frames_.front();
    if (config.width != first.cols || config.height != first.rows)
        return Status::error("camera 'replay': requested " + sizeName(config.width, config.height) +
                             " but the replayed frames are " + sizeName(first.cols, first.rows));
    stop();
    config_ = config;
    configured_ = true;
    return Status::ok();
}

Status ReplayCamera::start()
{
    if (!configured_) return Status::error("camera 'replay': start() before configure()");
    started_ = true;
    epochNs_ = monotonicNs();
    nextFrame_ = 0;
    return Status::ok();
}

void ReplayCamera::stop() { started_ = false; }

Result<CapturedFrame> ReplayCamera::capture(std::chrono::milliseconds timeout)
{
    if (!started_) return Status::error("camera 'replay': capture() while not streaming (call start())");
    const std::int64_t now = monotonicNs();
    std::uint64_t frame = nextFrame_;
    if (frameIntervalNs_ > 0) {
        // The newest frame whose time has come; the ones before it were missed.
        const std::int64_t since = now - epochNs_;
        frame = std::max(frame, static_cast<std::uint64_t>(since / frameIntervalNs_));
        const std::int64_t due = epochNs_ + static_cast<std::int64_t>(frame) * frameIntervalNs_;
        const std::int64_t timeoutNs = std::chrono::nanoseconds(timeout).count();
        if (due - now > timeoutNs) {
            sleepUntilNs(now + timeoutNs);
            return Status::error("camera 'replay': no frame within " + std::to_string(timeout.count()) + " ms");
        }
        sleepUntilNs(due);
    }
    nextFrame_ = frame + 1;

    const cv::Mat& image = frames_[frame % frames_.size()];
    CapturedFrame out;
    out.view = FrameView{image.data, image.cols, image.rows, static_cast<std::ptrdiff_t>(image.step), PixelFormat::Bgr8};
    out.sequence = frame;
    out.timestampNs = frameIntervalNs_ > 0 ? epochNs_ + static_cast<std::int64_t>(frame) * frameIntervalNs_ : now;
    out.exposureUs = config_.exposureUs;
    out.analogueGain = config_.analogueGain;
    return out;
}

Result<std::vector<cv::Mat>> renderReplayFrames(const SimWorld& world, int count, double exposureUs,
                                                double analogueGain)
{
    if (count < 1) return Status::error("replay: the frame count must be at least 1 (got " + std::to_string(count) + ")");
    const SceneRenderer renderer(world.rig());
    RenderSettings settings = world.renderSettings();
    settings.exposure *= exposureUs / SimCamera::kNominalExposureUs * analogueGain;
    settings.projectorOn = true;
    std::vector<cv::Mat> frames;
    frames.reserve(count);
    Rendering rendering;
    for (int i = 0; i < count; ++i) {
        settings.seed = world.renderSettings().seed + static_cast<std::uint64_t>(i);
        if (Status s = renderer.render(world.scene(), settings, rendering); !s) return s.withContext("replay: ");
        frames.push_back(rendering.image.clone());
    }
    return frames;
}

}  // namespace stria::hal::sim
