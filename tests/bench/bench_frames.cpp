#include "tests/bench/bench_frames.hpp"

#include "hal/sim/replay_camera.hpp"
#include "hal/sim/sim_camera.hpp"

#include <opencv2/imgproc.hpp>

#include <cstdio>
#include <map>
#include <memory>

namespace stria::bench {
namespace {

constexpr double kNoiseSigma = 4;

hal::sim::RenderSettings renderSettings(std::uint64_t seed)
{
    hal::sim::RenderSettings settings;
    settings.noiseSigma = kNoiseSigma;
    settings.seed = seed;
    return settings;
}

hal::sim::SimRig rigOf(FrameSize size)
{
    return size == FrameSize::Small ? hal::sim::desktopRig() : hal::sim::desktopRigLarge();
}

hal::sim::Scene sceneOf(const hal::sim::SimRig& rig)
{
    return hal::sim::makeScene(hal::sim::SceneKind::TexturedRelief, rig, hal::sim::Albedo::Coloured, 1);
}

}  // namespace

const BenchFrame* benchFrame(FrameSize size)
{
    static std::map<FrameSize, std::unique_ptr<BenchFrame>> cache;
    if (auto it = cache.find(size); it != cache.end()) return it->second.get();
    auto frame = std::make_unique<BenchFrame>(BenchFrame{rigOf(size), {}, {}});
    const hal::sim::SceneRenderer renderer(frame->rig);
    if (Status s = renderer.render(sceneOf(frame->rig), renderSettings(1), frame->rendering); !s) {
        std::fprintf(stderr, "bench: rendering the relief failed: %s\n", s.message().c_str());
        frame.reset();
    } else {
        cv::cvtColor(frame->rendering.image, frame->grey, cv::COLOR_BGR2GRAY);
    }
    return (cache[size] = std::move(frame)).get();
}

const std::vector<cv::Mat>& replayFrames(int count)
{
    static std::map<int, std::vector<cv::Mat>> cache;
    std::vector<cv::Mat>& frames = cache[count];
    if (!frames.empty()) return frames;
    hal::sim::SimRig rig = rigOf(FrameSize::Small);
    hal::sim::Scene scene = sceneOf(rig);
    const hal::sim::SimWorld world(std::move(rig), std::move(scene), renderSettings(1));
    auto rendered = hal::sim::renderReplayFrames(world, count, hal::sim::SimCamera::kNominalExposureUs, 1.0);
    if (!rendered)
        std::fprintf(stderr, "bench: rendering the replay frames failed: %s\n", rendered.message().c_str());
    else
        frames = std::move(*rendered);
    return frames;
}

FrameView viewOf(const cv::Mat& image)
{
    return {image.data, image.cols, image.rows, static_cast<std::ptrdiff_t>(image.step), PixelFormat::Bgr8};
}

}  // namespace stria::bench
