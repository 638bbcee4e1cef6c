// The quality targets of the decoder on simulator scenes (desktopRig 780x580,
// fixed seeds), each for both segmentations: the camera's rows (FullRows) and
// row pairs (RowPairs, DecoderParams::segmentRowPairs, the fast mode).
// Inlier: |error along the ray| <= 1% of the working distance; ideal:
// idealEdgeCrossings. Each scene is rendered once per test.
// docs/algorithm.md lists each target beside the figure measured here.
#include "tests/decoder/quality_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <set>
#include <utility>

namespace stria::test {
namespace {

using hal::sim::Albedo;
using hal::sim::SceneKind;

struct SceneRun {
    Score score;
    pipeline::DecodeResult result;
    std::vector<pipeline::ScanPoint> points;
    cv::Mat truthDepth;
};

class DecoderQuality : public ::testing::TestWithParam<bool> {};

SceneRun decodeScene(const hal::sim::SimRig& rig, SceneKind kind, Albedo albedo, hal::sim::RenderSettings settings,
                std::uint64_t sceneSeed = 1)
{
    pipeline::DecoderParams params;
    params.segmentRowPairs = DecoderQuality::GetParam();
    const hal::sim::Scene scene = hal::sim::makeScene(kind, rig, albedo, sceneSeed);
    hal::sim::Rendering truth;
    EXPECT_TRUE(hal::sim::SceneRenderer(rig).render(scene, settings, truth));
    auto decoder = pipeline::Decoder::create(rig.pattern, rig.rig, params);
    EXPECT_TRUE(decoder);
    const FrameView view{truth.image.data, truth.image.cols, truth.image.rows,
                         static_cast<std::ptrdiff_t>(truth.image.step), PixelFormat::Bgr8};
    auto result = (*decoder)->decode(view);
    EXPECT_TRUE(result);
    SceneRun run{scoreDecode(result->points, truth, rig), *result, {result->points.begin(), result->points.end()},
                 truth.depth};
    std::printf("[ measured ] %s%s/%s noise %.0f contrast %.2f ambient %.2f: %d points, ideal %d, inliers %.4f of "
                "ideal, outliers %.4f of points (%d), mean %.4f mm, std %.4f mm, %d superpixels%s\n",
                params.segmentRowPairs ? "row pairs: " : "", hal::sim::sceneName(kind), hal::sim::albedoName(albedo),
                settings.noiseSigma, settings.contrast, settings.ambient, run.score.points, run.score.ideal,
                run.score.inlierRatio(), run.score.outlierRatio(), run.score.outliers, run.score.meanError,
                run.score.stdError, result->superpixels, result->truncated ? " (truncated)" : "");
    return run;
}

hal::sim::RenderSettings noise(double sigma, std::uint64_t seed = 3)
{
    hal::sim::RenderSettings s;
    s.noiseSigma = sigma;
    s.seed = seed;
    return s;
}

TEST_P(DecoderQuality, TexturedReliefNoise2)
{
    const SceneRun run = decodeScene(hal::sim::desktopRig(), SceneKind::TexturedRelief, Albedo::Photo, noise(2));
    EXPECT_GE(run.score.inlierRatio(), 0.95);
    EXPECT_LE(run.score.outlierRatio(), 0.001);
}

TEST_P(DecoderQuality, TexturedReliefNoise8)
{
    const SceneRun run = decodeScene(hal::sim::desktopRig(), SceneKind::TexturedRelief, Albedo::Photo, noise(8));
    EXPECT_GE(run.score.inlierRatio(), 0.85);
    EXPECT_LE(run.score.outlierRatio(), 0.005);
}

TEST_P(DecoderQuality, LowContrastWithAmbientLight)
{
    hal::sim::RenderSettings s = noise(2);
    s.contrast = 0.3;
    s.ambient = 0.2;
    const SceneRun run = decodeScene(hal::sim::desktopRig(), SceneKind::TexturedRelief, Albedo::Photo, s);
    // Measured 84.5% inliers, 0.05% outliers (42.1% and 0.04% before the
    // texture's common change was removed from the symbol match).
    EXPECT_GE(run.score.inlierRatio(), 0.75);
    EXPECT_LE(run.score.outlierRatio(), 0.001);
}

TEST_P(DecoderQuality, LowContrastWithAmbientLightUniformAlbedo)
{
    hal::sim::RenderSettings s = noise(2);
    s.contrast = 0.3;
    s.ambient = 0.2;
    const SceneRun run = decodeScene(hal::sim::desktopRig(), SceneKind::TexturedRelief, Albedo::Uniform, s);
    EXPECT_GE(run.score.inlierRatio(), 0.75);
    EXPECT_LE(run.score.outlierRatio(), 0.005);
}

TEST_P(DecoderQuality, TiltedWhitePlaneIsPrecise)
{
    const SceneRun run = decodeScene(hal::sim::desktopRig(), SceneKind::TiltedPlane, Albedo::Uniform, noise(2));
    EXPECT_GE(run.score.inlierRatio(), 0.98);
    EXPECT_LE(run.score.stdError, 0.25);
    EXPECT_LE(std::abs(run.score.meanError), 0.05);
}

TEST_P(DecoderQuality, FanWithGapsHasFewOutliers)
{
    const SceneRun run = decodeScene(hal::sim::desktopRig(), SceneKind::Fan, Albedo::Uniform, noise(2));
    // The issue asks <= 0.2%: measured 0.15% (52 of 35 256 points). It was
    // 0.59% before a row kept one point per pattern edge (a projector ray
    // lights one surface point, so of two points of one edge in a row the
    // farther is in the nearer's shadow) and a weak edge along the stripes
    // to another stripe counted twice as contradiction. Inliers 75.0%
    // (76.2% before the second; 0.74 leaves room for the superpixels' drift).
    EXPECT_LE(run.score.outlierRatio(), 0.002);
    EXPECT_GE(run.score.inlierRatio(), 0.74);
    // Each pattern edge at most once per row (without the rule the fan has
    // ~150 repeated points, ~140 of them outliers).
    std::set<std::pair<int, int>> rowEdges;
    int repeated = 0;
    for (const pipeline::ScanPoint& p : run.points)
        repeated += !rowEdges.insert({static_cast<int>(std::lround(p.pixel.y)), p.edge}).second;
    EXPECT_EQ(repeated, 0);
}

TEST_P(DecoderQuality, SphereBeforeWallHasFewOutliers)
{
    const SceneRun run = decodeScene(hal::sim::desktopRig(), SceneKind::SphereBeforeWall, Albedo::Uniform, noise(2));
    EXPECT_LE(run.score.outlierRatio(), 0.002);
    EXPECT_GE(run.score.inlierRatio(), 0.9);
}

// Fingerprint ridges (0.45 mm apart, 0.05 mm deep, rings around a core) must
// show in the deviation of the points from a smooth quartic fit: that residual
// must follow the true surface's residual at the same pixels (correlation, and
// a regression slope near 1 = the ridge depth is measured, not flattened).
TEST_P(DecoderQuality, FingertipRidgesAreResolved)
{
    const hal::sim::SimRig rig = hal::sim::fingerprintRig();
    const SceneRun run = decodeScene(rig, SceneKind::Fingertip, Albedo::Uniform, noise(2));
    ASSERT_GT(run.points.size(), 20000u);

    // True points: the same rays at the true depth.
    std::vector<cv::Vec3d> measured, truth;
    for (const auto& p : run.points) {
        const int y = static_cast<int>(std::lround(p.pixel.y)), x0 = static_cast<int>(std::floor(p.pixel.x));
        const float z0 = run.truthDepth.at<float>(y, x0), z1 = run.truthDepth.at<float>(y, x0 + 1);
        if (!std::isfinite(z0) || !std::isfinite(z1)) continue;
        const double f = p.pixel.x - x0, z = z0 * (1 - f) + z1 * f;
        if (std::abs(p.position[2] - z) > 0.6) continue;  // outliers are not this test's subject
        measured.emplace_back(p.position[0], p.position[1], p.position[2]);
        truth.push_back(rig.rig.camera().rayThroughPixel({p.pixel.x, p.pixel.y}) * z);
    }
    auto residual = [](const std::vector<cv::Vec3d>& points) {
        const int n = static_cast<int>(points.size());
        cv::Mat a(n, 15, CV_64F), b(n, 1, CV_64F), coefficients;
        for (int i = 0; i < n; ++i) {
            int k = 0;
            for (int u = 0; u <= 4; ++u)
                for (int v = 0; u + v <= 4; ++v)
                    a.at<double>(i, k++) = std::pow(points[i][0] / 10, u) * std::pow(points[i][1] / 10, v);
            b.at<double>(i) = points[i][2];
        }
        cv::solve(a, b, coefficients, cv::DECOMP_SVD);
        return cv::Mat(b - a * coefficients);
    };
    const cv::Mat r = residual(measured), t = residual(truth);
    const double covariance = r.dot(t) / r.rows, varianceTruth = t.dot(t) / t.rows, varianceMeasured = r.dot(r) / r.rows;
    const double correlation = covariance / std::sqrt(varianceTruth * varianceMeasured);
    const double slope = covariance / varianceTruth;
    std::printf("[ measured ] fingertip: ridge residual RMS true %.4f mm, measured %.4f mm, correlation %.3f, slope %.3f\n",
                std::sqrt(varianceTruth), std::sqrt(varianceMeasured), correlation, slope);
    EXPECT_GT(std::sqrt(varianceTruth), 0.012);  // the ridges are there to be found (0.025 mm amplitude)
    EXPECT_GT(correlation, 0.5);
    EXPECT_NEAR(slope, 1.0, 0.25);
}

INSTANTIATE_TEST_SUITE_P(Segmentation, DecoderQuality, ::testing::Bool(),
                         [](const ::testing::TestParamInfo<bool>& info) { return info.param ? "RowPairs" : "FullRows"; });

}  // namespace
}  // namespace stria::test
