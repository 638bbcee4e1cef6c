// Decoding speed on simulator frames. The reference in the same run is one
// copy of the frame (the least any decoder must touch), so "x reference"
// compares machines fairly; frames/s is the number the paper quotes (15 Hz at
// 780x580 on a 3 GHz machine).
#include "hal/sim/scene/scene.hpp"
#include "pipeline/decoder.hpp"

#include <benchmark/benchmark.h>

namespace stria {
namespace {

using hal::sim::Albedo;
using hal::sim::SceneKind;

cv::Mat renderFrame(const hal::sim::SimRig& rig, SceneKind kind, Albedo albedo, double noise)
{
    hal::sim::RenderSettings settings;
    settings.noiseSigma = noise;
    hal::sim::Rendering out;
    if (!hal::sim::SceneRenderer(rig).render(hal::sim::makeScene(kind, rig, albedo, 1), settings, out)) return {};
    return out.image;
}

void frameCopyReference(benchmark::State& state)
{
    const cv::Mat frame = renderFrame(hal::sim::desktopRig(), SceneKind::TexturedRelief, Albedo::Photo, 2);
    cv::Mat copy(frame.size(), frame.type());
    for (auto _ : state) {
        frame.copyTo(copy);
        benchmark::DoNotOptimize(copy.data);
    }
}
BENCHMARK(frameCopyReference)->Unit(benchmark::kMillisecond);

void decode(benchmark::State& state, hal::sim::SimRig (*makeRig)(), SceneKind kind, Albedo albedo, double noise)
{
    const hal::sim::SimRig rig = makeRig();
    const cv::Mat frame = renderFrame(rig, kind, albedo, noise);
    auto decoder = pipeline::Decoder::create(rig.pattern, rig.rig);
    if (frame.empty() || !decoder) {
        state.SkipWithError("set-up failed");
        return;
    }
    const FrameView view{frame.data, frame.cols, frame.rows, static_cast<std::ptrdiff_t>(frame.step),
                         PixelFormat::Bgr8};
    std::size_t points = 0;
    for (auto _ : state) {
        auto result = (*decoder)->decode(view);
        if (!result) state.SkipWithError(result.message().c_str());
        points = result->points.size();
    }
    state.counters["frames/s"] = benchmark::Counter(1, benchmark::Counter::kIsIterationInvariantRate);
    state.counters["points"] = static_cast<double>(points);
}
BENCHMARK_CAPTURE(decode, plane, hal::sim::desktopRig, SceneKind::TiltedPlane, Albedo::Uniform, 2)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(decode, relief_noise2, hal::sim::desktopRig, SceneKind::TexturedRelief, Albedo::Photo, 2)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(decode, relief_noise8, hal::sim::desktopRig, SceneKind::TexturedRelief, Albedo::Photo, 8)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(decode, fan, hal::sim::desktopRig, SceneKind::Fan, Albedo::Uniform, 2)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(decode, relief_1388x1038, hal::sim::desktopRigLarge, SceneKind::TexturedRelief, Albedo::Photo, 2)
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace stria
