// The quality targets of the decoder on simulator scenes (desktopRig 780x580,
// fixed seeds). Inlier: |error along the ray| <= 1% of the working distance;
// ideal: idealEdgeCrossings. Each scene is rendered once per test.
// docs/algorithm.md lists each target beside the figure measured here.
#include "tests/decoder/quality_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace stria::test {
namespace {

using hal::sim::Albedo;
using hal::sim::SceneKind;

struct SceneRun {
    Score score;
    pipeline::DecodeResult result;
    std::vector<pipeline::ScanPoint> points;
};

SceneRun decodeScene(const hal::sim::SimRig& rig, SceneKind kind, Albedo albedo, hal::sim::RenderSettings settings,
                std::uint64_t sceneSeed = 1)
{
    const hal::sim::Scene scene = hal::sim::makeScene(kind, rig, albedo, sceneSeed);
    hal::sim::Rendering truth;
    EXPECT_TRUE(hal::sim::SceneRenderer(rig).render(scene, settings, truth));
    auto decoder = pipeline::Decoder::create(rig.pattern, rig.rig);
    EXPECT_TRUE(decoder);
    const FrameView view{truth.image.data, truth.image.cols, truth.image.rows,
                         static_cast<std::ptrdiff_t>(truth.image.step), PixelFormat::Bgr8};
    auto result = (*decoder)->decode(view);
    EXPECT_TRUE(result);
    SceneRun run{scoreDecode(result->points, truth, rig), *result, {result->points.begin(), result->points.end()}};
    std::printf("[ measured ] %s/%s noise %.0f contrast %.2f ambient %.2f: %d points, ideal %d, inliers %.4f of "
                "ideal, outliers %.4f of points, mean %.4f mm, std %.4f mm, %d superpixels%s\n",
                hal::sim::sceneName(kind), hal::sim::albedoName(albedo), settings.noiseSigma, settings.contrast,
                settings.ambient, run.score.points, run.score.ideal, run.score.inlierRatio(), run.score.outlierRatio(),
                run.score.meanError, run.score.stdError, result->superpixels, result->truncated ? " (truncated)" : "");
    return run;
}

hal::sim::RenderSettings noise(double sigma, std::uint64_t seed = 3)
{
    hal::sim::RenderSettings s;
    s.noiseSigma = sigma;
    s.seed = seed;
    return s;
}

TEST(DecoderQuality, TexturedReliefNoise2)
{
    const SceneRun run = decodeScene(hal::sim::desktopRig(), SceneKind::TexturedRelief, Albedo::Photo, noise(2));
    EXPECT_GE(run.score.inlierRatio(), 0.95);
    EXPECT_LE(run.score.outlierRatio(), 0.001);
}

TEST(DecoderQuality, TexturedReliefNoise8)
{
    const SceneRun run = decodeScene(hal::sim::desktopRig(), SceneKind::TexturedRelief, Albedo::Photo, noise(8));
    EXPECT_GE(run.score.inlierRatio(), 0.85);
    EXPECT_LE(run.score.outlierRatio(), 0.005);
}

TEST(DecoderQuality, LowContrastWithAmbientLight)
{
    hal::sim::RenderSettings s = noise(2);
    s.contrast = 0.3;
    s.ambient = 0.2;
    const SceneRun run = decodeScene(hal::sim::desktopRig(), SceneKind::TexturedRelief, Albedo::Photo, s);
    EXPECT_GE(run.score.inlierRatio(), 0.75);
}

TEST(DecoderQuality, TiltedWhitePlaneIsPrecise)
{
    const SceneRun run = decodeScene(hal::sim::desktopRig(), SceneKind::TiltedPlane, Albedo::Uniform, noise(2));
    EXPECT_GE(run.score.inlierRatio(), 0.98);
    EXPECT_LE(run.score.stdError, 0.25);
    EXPECT_LE(std::abs(run.score.meanError), 0.05);
}

TEST(DecoderQuality, FanWithGapsHasFewOutliers)
{
    const SceneRun run = decodeScene(hal::sim::desktopRig(), SceneKind::Fan, Albedo::Uniform, noise(2));
    EXPECT_LE(run.score.outlierRatio(), 0.002);
    EXPECT_GE(run.score.inlierRatio(), 0.5);
}

TEST(DecoderQuality, SphereBeforeWallHasFewOutliers)
{
    const SceneRun run = decodeScene(hal::sim::desktopRig(), SceneKind::SphereBeforeWall, Albedo::Uniform, noise(2));
    EXPECT_LE(run.score.outlierRatio(), 0.002);
    EXPECT_GE(run.score.inlierRatio(), 0.9);
}

// Fingerprint ridges (0.45 mm apart, 0.05 mm deep, rings around a core) must
// show in the deviation of the points from a smooth quartic fit: its RMS is
// about the ridge amplitude and its dominant period along image rows near the
// middle is the ridge spacing.
TEST(DecoderQuality, FingertipRidgesAreResolved)
{
    const hal::sim::SimRig rig = hal::sim::fingerprintRig();
    const SceneRun run = decodeScene(rig, SceneKind::Fingertip, Albedo::Uniform, noise(2));
    ASSERT_GT(run.points.size(), 20000u);

    auto terms = [](double x, double y) {
        cv::Mat row(1, 15, CV_64F);
        int k = 0;
        for (int i = 0; i <= 4; ++i)
            for (int j = 0; i + j <= 4; ++j) row.at<double>(0, k++) = std::pow(x / 10, i) * std::pow(y / 10, j);
        return row;
    };
    cv::Mat a(static_cast<int>(run.points.size()), 15, CV_64F), b(static_cast<int>(run.points.size()), 1, CV_64F);
    for (std::size_t i = 0; i < run.points.size(); ++i) {
        const auto& p = run.points[i].position;
        terms(p[0], p[1]).copyTo(a.row(static_cast<int>(i)));
        b.at<double>(static_cast<int>(i)) = p[2];
    }
    cv::Mat coefficients;
    ASSERT_TRUE(cv::solve(a, b, coefficients, cv::DECOMP_SVD));
    const cv::Mat residual = b - a * coefficients;
    double sum2 = 0;
    for (int i = 0; i < residual.rows; ++i) sum2 += residual.at<double>(i) * residual.at<double>(i);
    const double rms = std::sqrt(sum2 / residual.rows);

    // Residual profile along x for the middle rows, in 0.02 mm bins, on the
    // part right of the centre (rings there cross rows nearly at right angles).
    const double cy = (rig.rig.camera().height - 1) / 2.0, bin = 0.02, x0 = 3.0, x1 = 9.0;
    const int bins = static_cast<int>((x1 - x0) / bin);
    std::vector<double> sum(bins, 0), count(bins, 0);
    for (std::size_t i = 0; i < run.points.size(); ++i) {
        const auto& p = run.points[i];
        if (std::abs(p.pixel.y - cy) > 25) continue;
        const int k = static_cast<int>((p.position[0] - x0) / bin);
        if (k < 0 || k >= bins) continue;
        sum[k] += residual.at<double>(static_cast<int>(i));
        count[k] += 1;
    }
    std::vector<double> profile(bins, 0);
    for (int k = 0; k < bins; ++k) profile[k] = count[k] > 0 ? sum[k] / count[k] : 0;
    auto autocorrelation = [&](int lag) {
        double s = 0;
        for (int k = 0; k + lag < bins; ++k) s += profile[k] * profile[k + lag];
        return s;
    };
    int bestLag = 0;
    double best = -1e30;
    for (int lag = static_cast<int>(0.3 / bin); lag <= static_cast<int>(0.7 / bin); ++lag)
        if (autocorrelation(lag) > best) {
            best = autocorrelation(lag);
            bestLag = lag;
        }
    const double period = bestLag * bin;
    std::printf("[ measured ] fingertip: residual RMS %.4f mm, dominant period %.3f mm\n", rms, period);
    EXPECT_GT(rms, 0.010);
    EXPECT_LT(rms, 0.035);
    EXPECT_NEAR(period, 0.47, 0.07);
}

}  // namespace
}  // namespace stria::test
