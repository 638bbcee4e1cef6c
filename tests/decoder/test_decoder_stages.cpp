// The decoder's stages on synthetic frames whose answer is known exactly: the
// slide itself seen 1:1 (tests/decoder/synthetic_rig.hpp).
#include "pipeline/decoder.hpp"
#include "pipeline/decoder/workspace.hpp"
#include "tests/decoder/synthetic_rig.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

namespace stria::pipeline {
namespace {

FrameView viewOf(const cv::Mat& image, PixelFormat format = PixelFormat::Bgr8)
{
    return {image.data, image.cols, image.rows, static_cast<std::ptrdiff_t>(image.step), format};
}

struct SlideCase {
    StripePattern pattern = test::slidePattern();
    RigModel rig = test::slideRig(pattern, 48);
    cv::Mat slide = pattern.renderSlide(pattern.projectorColumnsUsed(), 48);
};

TEST(DecoderEquations, MatchErrorFollowsEquations5And6)
{
    const float t = 1.0f / 3.0f;
    // A perfect R+G- change has no error; a channel at the threshold costs 1.
    EXPECT_FLOAT_EQ(matchError({1, -1, 0}, makeSymbol(1, -1, 0), t), 0.0f);
    EXPECT_FLOAT_EQ(matchError({1, -1, t}, makeSymbol(1, -1, 0), t), 1.0f);
    // (0.5, -1, 0) against R+G-: red (1 - 0.5) / (2/3) = 0.75.
    EXPECT_NEAR(matchError({0.5f, -1, 0}, makeSymbol(1, -1, 0), t), 0.75f, 1e-6);
    // Both off-symbols: sqrt(0.75^2 + 1.5^2).
    EXPECT_NEAR(matchError({0.5f, -1, 0.5f}, makeSymbol(1, -1, 0), t), std::sqrt(0.5625f + 2.25f), 1e-6);
}

TEST(DecoderEquations, OptimalSymbolThresholdsAtT)
{
    const float t = 1.0f / 3.0f;
    EXPECT_EQ(optimalSymbol({0.2f, -1, 0.5f}, t), makeSymbol(0, -1, 1));
    EXPECT_EQ(optimalSymbol({-0.34f, 1, 0.33f}, t), makeSymbol(-1, 1, 0));
}

TEST(DecoderEquations, SymbolErrorRemovesATexturesCommonChangeWithinBounds)
{
    const float t = 1.0f / 3.0f;
    // A stripe edge R+G- (relative steps +-0.25) on a texture 5% brighter on
    // the far side: (0.30, -0.20, 0.05), i.e. (1, -2/3, 1/6) normalised. The
    // constant blue channel shows the common change, which is removed.
    const EqualizedChange rising{{1, -2.0f / 3, 1.0f / 6}, 10, 0.3f};
    EXPECT_NEAR(matchError(rising.c, makeSymbol(1, -1, 0), t), std::sqrt(0.5f), 1e-5);
    EXPECT_NEAR(symbolError(rising, makeSymbol(1, -1, 0), t), 0.0f, 1e-5);
    // R-G+B+ at contrast 0.3 (steps 0.29) on a texture 10% darker: no
    // constant channel; the midpoint of the falling and rising ones.
    const EqualizedChange darker{{-1, 0.19f / 0.39f, 0.19f / 0.39f}, 10, 0.39f};
    EXPECT_GT(matchError(darker.c, makeSymbol(-1, 1, 1), t), 1.0f);
    EXPECT_NEAR(symbolError(darker, makeSymbol(-1, 1, 1), t), 0.0f, 1e-5);
    // R+ is G-B- plus a common rise of the whole step: beyond both bounds
    // (0.3 of the largest change; a 15% brightness change at full contrast),
    // so it does not fit, at low contrast or high.
    for (float relative : {0.3f, 1.8f}) {
        const EqualizedChange redRises{{1, 0, 0}, 10, relative};
        EXPECT_FLOAT_EQ(symbolError(redRises, makeSymbol(1, 0, 0), t), 0.0f);
        EXPECT_GT(symbolError(redRises, makeSymbol(0, -1, -1), t), 3.0f) << relative;
    }
}

TEST(DecoderStages, CleanSlideGivesOneSuperpixelPerStripeAndEveryStripeDecoded)
{
    SlideCase c;
    auto decoder = Decoder::create(c.pattern, c.rig);
    ASSERT_TRUE(decoder) << decoder.message();
    auto result = (*decoder)->decode(viewOf(c.slide));
    ASSERT_TRUE(result) << result.message();
    EXPECT_EQ(result->superpixels, c.pattern.stripeCount());
    EXPECT_EQ(result->graphEdges, c.pattern.edgeCount());
    EXPECT_EQ(result->decodedRegions, c.pattern.stripeCount());
    EXPECT_FALSE(result->truncated);
    const cv::Mat labels = (*decoder)->labels();
    int wrong = 0;
    for (int y = 0; y < labels.rows; ++y)
        for (int x = 0; x < labels.cols; ++x)
            wrong += (*decoder)->regionStripe(labels.at<int>(y, x)) != x / c.pattern.stripeWidth();
    EXPECT_EQ(wrong, 0);
    // One point per row and edge, exactly on the edge column.
    ASSERT_EQ(result->points.size(), static_cast<std::size_t>(c.pattern.edgeCount() * c.slide.rows));
    double worst = 0, worstDepth = 0;
    for (const ScanPoint& p : result->points) {
        worst = std::max(worst, std::abs(p.pixel.x - c.pattern.edgeColumn(p.edge)));
        worstDepth = std::max(worstDepth, std::abs(p.position[2] - 1000.0));
    }
    EXPECT_LT(worst, 1e-4);
    EXPECT_LT(worstDepth, 1e-3);  // mm: the plane the slide rig sees
}

// Row pairs (DecoderParams::segmentRowPairs): the labels have half the rows
// (rounded up: an odd last row is a pair of its own), the points every camera
// row, on the same exact columns; a strided view gives the same points.
TEST(DecoderStages, RowPairsSegmentHalfTheRowsAndLocateEveryRow)
{
    for (const int rows : {48, 47}) {
        const StripePattern pattern = test::slidePattern();
        const RigModel rig = test::slideRig(pattern, rows);
        const cv::Mat slide = pattern.renderSlide(pattern.projectorColumnsUsed(), rows);
        DecoderParams params;
        params.segmentRowPairs = true;
        auto decoder = Decoder::create(pattern, rig, params);
        ASSERT_TRUE(decoder) << decoder.message();
        auto result = (*decoder)->decode(viewOf(slide));
        ASSERT_TRUE(result) << result.message();
        EXPECT_EQ(result->superpixels, pattern.stripeCount()) << rows;
        EXPECT_EQ(result->decodedRegions, pattern.stripeCount()) << rows;
        const cv::Mat labels = (*decoder)->labels();
        EXPECT_EQ(labels.rows, (rows + 1) / 2);
        EXPECT_EQ(labels.cols, slide.cols);
        ASSERT_EQ(result->points.size(), static_cast<std::size_t>(pattern.edgeCount() * rows)) << rows;
        std::vector<int> perRow(static_cast<std::size_t>(rows), 0);
        double worst = 0;
        for (const ScanPoint& p : result->points) {
            worst = std::max(worst, std::abs(p.pixel.x - pattern.edgeColumn(p.edge)));
            ++perRow[static_cast<std::size_t>(std::lround(p.pixel.y))];
        }
        EXPECT_LT(worst, 1e-4) << rows;
        EXPECT_EQ(*std::min_element(perRow.begin(), perRow.end()), pattern.edgeCount()) << rows;
        const std::vector<ScanPoint> expected(result->points.begin(), result->points.end());

        cv::Mat wide(slide.rows, slide.cols + 37, CV_8UC3, cv::Scalar(0, 0, 255));
        slide.copyTo(wide.colRange(0, slide.cols));
        auto strided = (*decoder)->decode(viewOf(wide.colRange(0, slide.cols)));
        ASSERT_TRUE(strided);
        ASSERT_EQ(strided->points.size(), expected.size());
        for (std::size_t i = 0; i < expected.size(); ++i) EXPECT_EQ(strided->points[i].pixel, expected[i].pixel);
    }
}

TEST(DecoderStages, RgbFramesDecodeLikeBgr)
{
    SlideCase c;
    cv::Mat rgb;
    cv::cvtColor(c.slide, rgb, cv::COLOR_BGR2RGB);
    auto decoder = Decoder::create(c.pattern, c.rig);
    auto result = (*decoder)->decode(viewOf(rgb, PixelFormat::Rgb8));
    ASSERT_TRUE(result);
    EXPECT_EQ(result->decodedRegions, c.pattern.stripeCount());
}

TEST(DecoderStages, StridedViewDecodesLikeAContiguousFrame)
{
    SlideCase c;
    // The frame as a window into a wider buffer: stride != 3 * width.
    cv::Mat wide(c.slide.rows, c.slide.cols + 37, CV_8UC3, cv::Scalar(0, 0, 255));
    c.slide.copyTo(wide.colRange(0, c.slide.cols));
    const cv::Mat window = wide.colRange(0, c.slide.cols);
    auto decoder = Decoder::create(c.pattern, c.rig);
    auto contiguous = (*decoder)->decode(viewOf(c.slide));
    ASSERT_TRUE(contiguous);
    const std::vector<ScanPoint> expected(contiguous->points.begin(), contiguous->points.end());
    auto strided = (*decoder)->decode(viewOf(window));
    ASSERT_TRUE(strided);
    ASSERT_EQ(strided->points.size(), expected.size());
    for (std::size_t i = 0; i < expected.size(); ++i) {
        EXPECT_EQ(strided->points[i].pixel, expected[i].pixel);
        EXPECT_EQ(strided->points[i].edge, expected[i].edge);
    }
}

TEST(DecoderStages, SubPixelEdgesOnBlurredNoisySlideWithinATenthOfAPixel)
{
    SlideCase c;
    cv::Mat blurred, noisy;
    cv::GaussianBlur(c.slide, blurred, {0, 0}, 1.2, 0.01);
    cv::Mat noise(blurred.size(), CV_16SC3);
    cv::RNG rng(5);
    rng.fill(noise, cv::RNG::NORMAL, 0, 2);
    cv::Mat sum;
    cv::add(blurred, noise, sum, cv::noArray(), CV_16SC3);
    sum.convertTo(noisy, CV_8UC3);
    auto decoder = Decoder::create(c.pattern, c.rig);
    auto result = (*decoder)->decode(viewOf(noisy));
    ASSERT_TRUE(result);
    ASSERT_GT(result->points.size(), 0.95 * c.pattern.edgeCount() * c.slide.rows);
    double sum2 = 0;
    int wrongEdge = 0;
    for (const ScanPoint& p : result->points) {
        const double d = p.pixel.x - c.pattern.edgeColumn(p.edge);
        wrongEdge += std::abs(d) > 2;
        sum2 += d * d;
    }
    EXPECT_EQ(wrongEdge, 0);
    EXPECT_LT(std::sqrt(sum2 / result->points.size()), 0.1);
}

TEST(DecoderStages, CrosstalkIsCorrected)
{
    SlideCase c;
    // Strong mixing: each sensor channel sees 35% of its neighbours' light.
    const cv::Matx33f mixing(1.0f, 0.35f, 0.0f, 0.35f, 1.0f, 0.35f, 0.0f, 0.35f, 1.0f);
    cv::Mat mixed(c.slide.size(), CV_8UC3);
    for (int y = 0; y < c.slide.rows; ++y)
        for (int x = 0; x < c.slide.cols; ++x) {
            const cv::Vec3b bgr = c.slide.at<cv::Vec3b>(y, x);
            const cv::Vec3f rgb = mixing * cv::Vec3f(bgr[2], bgr[1], bgr[0]) * (1.0f / 1.7f);
            mixed.at<cv::Vec3b>(y, x) = cv::Vec3b(cv::saturate_cast<uchar>(rgb[2]), cv::saturate_cast<uchar>(rgb[1]),
                                                  cv::saturate_cast<uchar>(rgb[0]));
        }
    DecoderParams params;
    params.crosstalk = mixing;
    auto decoder = Decoder::create(c.pattern, c.rig, params);
    ASSERT_TRUE(decoder) << decoder.message();
    auto result = (*decoder)->decode(viewOf(mixed));
    ASSERT_TRUE(result);
    EXPECT_EQ(result->decodedRegions, c.pattern.stripeCount());
}

TEST(DecoderStages, NoiseWithTinyCapacitiesIsTruncatedNotOverflowed)
{
    SlideCase c;
    cv::Mat noise(c.slide.size(), CV_8UC3);
    cv::RNG rng(9);
    rng.fill(noise, cv::RNG::UNIFORM, 0, 256);
    DecoderParams params;
    params.maxSuperpixels = 50;
    params.maxGraphEdges = 60;
    params.maxPoints = 10;
    auto decoder = Decoder::create(c.pattern, c.rig, params);
    ASSERT_TRUE(decoder);
    for (const cv::Mat& frame : {noise, c.slide}) {
        auto result = (*decoder)->decode(viewOf(frame));
        ASSERT_TRUE(result);
        EXPECT_TRUE(result->truncated);
        EXPECT_LE(result->superpixels, 50);
        EXPECT_LE(result->graphEdges, 60);
        EXPECT_LE(result->points.size(), 10u);
    }
}

TEST(DecoderErrors, WrongFrameSizeNamesBothSizes)
{
    SlideCase c;
    auto decoder = Decoder::create(c.pattern, c.rig);
    const cv::Mat small(40, 100, CV_8UC3, cv::Scalar::all(0));
    auto result = (*decoder)->decode(viewOf(small));
    ASSERT_FALSE(result);
    EXPECT_EQ(result.message(), "decode: the frame is 100x40 but the camera is calibrated for 320x48");
}

TEST(DecoderErrors, WrongPixelFormatIsNamed)
{
    SlideCase c;
    auto decoder = Decoder::create(c.pattern, c.rig);
    auto result = (*decoder)->decode(viewOf(c.slide, PixelFormat::Yuyv));
    ASSERT_FALSE(result);
    EXPECT_NE(result.message().find("the decoder needs BGR8 or RGB8"), std::string::npos) << result.message();
}

TEST(DecoderErrors, PatternWiderThanProjectorSingularCrosstalkAndTooWideCameraAreRefused)
{
    const StripePattern wide = test::slidePattern(60);  // 480 columns
    const RigModel rig = test::slideRig(test::slidePattern(40), 48);  // projector 320 wide
    auto tooWide = Decoder::create(wide, rig);
    ASSERT_FALSE(tooWide);
    EXPECT_EQ(tooWide.message(), "the pattern needs 480 projector columns but the calibrated projector is only 320 wide");

    DecoderParams params;
    params.crosstalk = cv::Matx33f(1, 1, 0, 1, 1, 0, 0, 0, 1);
    auto singular = Decoder::create(test::slidePattern(40), rig, params);
    ASSERT_FALSE(singular);
    EXPECT_NE(singular.message().find("crosstalk matrix is singular"), std::string::npos);

    // The label rows' border lists hold 16-bit columns: a wider camera is
    // refused before any workspace is allocated.
    LensModel camera = rig.camera();
    camera.width = 65537;
    camera.K(0, 2) = (camera.width - 1) / 2.0;
    const RigModel wideRig = RigModel::create(camera, rig.projector(), rig.R(), rig.T()).value();
    auto wideCamera = Decoder::create(test::slidePattern(40), wideRig);
    ASSERT_FALSE(wideCamera);
    EXPECT_EQ(wideCamera.message(),
              "the camera is 65537 pixels wide: the decoder supports at most 65536 (16-bit border columns)");
}

TEST(DecoderErrors, RowPairsNeedStripesAlongTheColumns)
{
    // The projector above the camera: the stripes run along the image rows,
    // which pairs of rows would blur together.
    const StripePattern pattern = test::slidePattern();
    const RigModel horizontal = test::slideRig(pattern, 48);
    const RigModel vertical =
        RigModel::create(horizontal.camera(), horizontal.projector(), cv::Matx33d::eye(), cv::Vec3d(0, -100, 0)).value();
    DecoderParams params;
    params.segmentRowPairs = true;
    auto refused = Decoder::create(pattern, vertical, params);
    ASSERT_FALSE(refused);
    EXPECT_EQ(refused.message(), "decoder: segmentation on row pairs needs stripes along the image columns, but this "
                                 "rig's stripes run along the rows (its baseline is closer to the image's y axis)");
    EXPECT_TRUE(Decoder::create(pattern, vertical));  // the camera's rows segment either way
    EXPECT_TRUE(Decoder::create(pattern, horizontal, params));
}

TEST(DecoderMemory, WorkspaceStaysUnder34BytesPerPixel)
{
    SlideCase c;
    auto decoder = Decoder::create(c.pattern, c.rig);
    const double perPixel = static_cast<double>((*decoder)->workspaceBytes()) / (c.slide.cols * c.slide.rows);
    EXPECT_LT(perPixel, 34.0);
    EXPECT_GT(perPixel, 13.0);  // at least gradient + labels + two index buffers
}

}  // namespace
}  // namespace stria::pipeline
