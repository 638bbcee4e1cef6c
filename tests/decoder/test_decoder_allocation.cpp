// decode() performs no heap allocation after create(): every allocation in
// this process is counted (global operator new/delete and the C allocator are
// replaced in this binary only) and decoding frames 2..N must add none.
#include "tests/support/allocation_counter.hpp"
#include "hal/sim/scene/scene.hpp"
#include "pipeline/decoder.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

namespace stria {
namespace {

TEST(DecoderAllocation, DecodingFramesTwoToNAllocatesNothing)
{
    if (!test::kCountingAllocations) GTEST_SKIP() << "sanitizer build: the allocator is the sanitizer's";
    const hal::sim::SimRig rig = hal::sim::desktopRig();
    const hal::sim::Scene scene = hal::sim::makeScene(hal::sim::SceneKind::TexturedRelief, rig, hal::sim::Albedo::Photo, 1);
    hal::sim::SceneRenderer renderer(rig);
    std::vector<hal::sim::Rendering> frames(4);
    for (std::size_t i = 0; i < frames.size(); ++i) {
        hal::sim::RenderSettings settings;
        settings.noiseSigma = 2.0 + 2.0 * i;  // different frames, different superpixel counts
        settings.seed = 10 + i;
        ASSERT_TRUE(renderer.render(scene, settings, frames[i]));
    }
    auto decoder = pipeline::Decoder::create(rig.pattern, rig.rig);
    ASSERT_TRUE(decoder);
    cv::Mat depth(frames[0].image.rows, frames[0].image.cols, CV_32FC1);
    auto view = [](const cv::Mat& m) {
        return FrameView{m.data, m.cols, m.rows, static_cast<std::ptrdiff_t>(m.step), PixelFormat::Bgr8};
    };
    auto first = (*decoder)->decode(view(frames[0].image));
    ASSERT_TRUE(first);
    ASSERT_GT(first->points.size(), 40000u);

    const long before = test::allocationCount();
    std::size_t points = 0;
    for (std::size_t i = 1; i < frames.size(); ++i) {
        auto result = (*decoder)->decode(view(frames[i].image));
        if (!result) break;
        points += result->points.size();
        (*decoder)->fillDepthMap(depth);
    }
    const long added = test::allocationCount() - before;
    EXPECT_EQ(added, 0);
    EXPECT_GT(points, 3u * 30000u);  // the frames were really decoded
}

TEST(DecoderAllocation, WorkspaceOfTheDesktopRigIsUnder34BytesPerPixel)
{
    const hal::sim::SimRig rig = hal::sim::desktopRig();
    auto decoder = pipeline::Decoder::create(rig.pattern, rig.rig);
    ASSERT_TRUE(decoder);
    const double pixels = static_cast<double>(rig.rig.camera().width) * rig.rig.camera().height;
    EXPECT_LT(static_cast<double>((*decoder)->workspaceBytes()) / pixels, 34.0);
}

}  // namespace
}  // namespace stria
