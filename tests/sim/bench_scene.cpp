// Rendering speed of the simulator on the desktop rig (780x580). The
// one-sample plane is the reference the other cases compare against.
#include "hal/sim/scene/scene.hpp"

#include <benchmark/benchmark.h>

namespace stria::hal::sim {
namespace {

void renderScene(benchmark::State& state, SceneKind kind, int samplesPerPixel)
{
    const SimRig rig = desktopRig();
    const Scene scene = makeScene(kind, rig, defaultAlbedo(kind), 1);
    const SceneRenderer renderer(rig);
    RenderSettings settings;
    settings.samplesPerPixel = samplesPerPixel;
    settings.noiseSigma = 2;
    Rendering out;
    for (auto _ : state) {
        if (!renderer.render(scene, settings, out)) state.SkipWithError("render failed");
        benchmark::DoNotOptimize(out.image.data);
    }
    state.counters["pixels/s"] =
        benchmark::Counter(static_cast<double>(out.image.total()), benchmark::Counter::kIsIterationInvariantRate);
}

BENCHMARK_CAPTURE(renderScene, plane_1spp_reference, SceneKind::TiltedPlane, 1)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(renderScene, plane, SceneKind::TiltedPlane, 4)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(renderScene, sphere, SceneKind::SphereBeforeWall, 4)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(renderScene, relief, SceneKind::TexturedRelief, 4)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(renderScene, clutter, SceneKind::Clutter, 4)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(renderScene, fan, SceneKind::Fan, 4)->Unit(benchmark::kMillisecond);

void rendererSetUp(benchmark::State& state)
{
    const SimRig rig = desktopRig();
    for (auto _ : state) benchmark::DoNotOptimize(SceneRenderer(rig).rig().camera().width);
}
BENCHMARK(rendererSetUp)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace stria::hal::sim
