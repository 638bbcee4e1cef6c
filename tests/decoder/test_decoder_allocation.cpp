// decode() performs no heap allocation after create(): every allocation in
// this process is counted (global operator new/delete and the C allocator are
// replaced in this binary only) and decoding frames 2..N must add none.
#include "tests/support/allocation_counter.hpp"
#include "hal/sim/scene/scene.hpp"
#include "pipeline/decoder.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <cstring>
#include <new>
#include <vector>

namespace stria {
namespace {

// Each test below for both segmentations: the camera's rows and row pairs
// (DecoderParams::segmentRowPairs), whose averaged frame lives in the workspace.
class DecoderAllocation : public ::testing::TestWithParam<bool> {
protected:
    static pipeline::DecoderParams params()
    {
        pipeline::DecoderParams p;
        p.segmentRowPairs = GetParam();
        return p;
    }
};

TEST_P(DecoderAllocation, DecodingFramesTwoToNAllocatesNothing)
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
    auto decoder = pipeline::Decoder::create(rig.pattern, rig.rig, params());
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

// The per-stage benchmarks time Decoder::repeatStage: a stage run again after
// the stages before it must do the work decode() did and allocate nothing.
// The stages up to each one, that one twice (it must not spoil its own
// inputs), then the later ones: the points must be the decode's, byte for
// byte.
TEST_P(DecoderAllocation, RepeatingAStageRedoesItsWorkAndAllocatesNothing)
{
    const hal::sim::SimRig rig = hal::sim::desktopRig();
    const hal::sim::Scene scene =
        hal::sim::makeScene(hal::sim::SceneKind::TexturedRelief, rig, hal::sim::Albedo::Coloured, 1);
    hal::sim::RenderSettings settings;
    settings.noiseSigma = 4;
    hal::sim::Rendering frame;
    ASSERT_TRUE(hal::sim::SceneRenderer(rig).render(scene, settings, frame));
    const cv::Mat& image = frame.image;
    const FrameView view{image.data, image.cols, image.rows, static_cast<std::ptrdiff_t>(image.step), PixelFormat::Bgr8};
    auto decoder = pipeline::Decoder::create(rig.pattern, rig.rig, params());
    ASSERT_TRUE(decoder);

    const Status early = (*decoder)->repeatStage(pipeline::DecoderStage::Graph, view);
    EXPECT_FALSE(early);
    EXPECT_EQ(early.message(), "repeatStage: no frame was decoded yet (or the last decode failed)");

    auto result = (*decoder)->decode(view);
    ASSERT_TRUE(result);
    const std::vector<pipeline::ScanPoint> expected(result->points.begin(), result->points.end());
    ASSERT_GT(expected.size(), 20000u);

    const cv::Mat other = image.clone();
    const FrameView otherView{other.data, other.cols, other.rows, static_cast<std::ptrdiff_t>(other.step),
                              PixelFormat::Bgr8};
    const Status wrongFrame = (*decoder)->repeatStage(pipeline::DecoderStage::Graph, otherView);
    EXPECT_FALSE(wrongFrame);
    EXPECT_EQ(wrongFrame.message(), "repeatStage: the frame is not the one the last decode() decoded");

    for (int first = 0; first < pipeline::kDecoderStageCount; ++first) {
        // Counted around the decoder's calls only (gtest's messages allocate).
        const long before = test::allocationCount();
        bool ok = true;
        for (int s = 0; s <= first; ++s)
            ok = ok && (*decoder)->repeatStage(static_cast<pipeline::DecoderStage>(s), view).isOk();
        for (int s = first; s < pipeline::kDecoderStageCount; ++s)
            ok = ok && (*decoder)->repeatStage(static_cast<pipeline::DecoderStage>(s), view).isOk();
        const long added = test::allocationCount() - before;
        const char* name = pipeline::decoderStageName(static_cast<pipeline::DecoderStage>(first));
        ASSERT_TRUE(ok) << name;
        if (test::kCountingAllocations) {
            EXPECT_EQ(added, 0) << name;
        }
        // The points of the last decode(), rewritten in place by the depth stage.
        ASSERT_EQ(result->points.size(), expected.size()) << name;
        EXPECT_EQ(std::memcmp(result->points.data(), expected.data(), expected.size() * sizeof(pipeline::ScanPoint)), 0)
            << name;
    }
}

TEST_P(DecoderAllocation, WorkspaceOfTheDesktopRigIsUnder34BytesPerPixel)
{
    const hal::sim::SimRig rig = hal::sim::desktopRig();
    auto decoder = pipeline::Decoder::create(rig.pattern, rig.rig, params());
    ASSERT_TRUE(decoder);
    const double pixels = static_cast<double>(rig.rig.camera().width) * rig.rig.camera().height;
    EXPECT_LT(static_cast<double>((*decoder)->workspaceBytes()) / pixels, 34.0);
    // Row pairs cost no memory: the averaged frame fits in the labels buffer past the label rows.
    auto fullRows = pipeline::Decoder::create(rig.pattern, rig.rig);
    ASSERT_TRUE(fullRows);
    EXPECT_EQ((*decoder)->workspaceBytes(), (*fullRows)->workspaceBytes());
}

INSTANTIATE_TEST_SUITE_P(Segmentation, DecoderAllocation, ::testing::Bool(),
                         [](const ::testing::TestParamInfo<bool>& info) { return info.param ? "RowPairs" : "FullRows"; });

}  // namespace
}  // namespace stria
