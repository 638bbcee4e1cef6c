// The scene simulator against closed-form geometry, and its light, noise,
// determinism and ground-truth counting.
#include "firmware/formats/calibration_file.hpp"
#include "firmware/formats/pattern_file.hpp"
#include "hal/sim/scene/scene.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace stria::hal::sim {
namespace {

// The desktop rig with clearly visible distortion on both devices.
SimRig distortedRig()
{
    SimRig rig = desktopRig();
    pipeline::LensModel camera = rig.rig.camera(), projector = rig.rig.projector();
    camera.distortion = {-0.2, 0.1, 0.001, -0.0008, 0.01};
    projector.distortion = {0.05, -0.02, 0.0005, 0.0003, 0};
    rig.rig = *pipeline::RigModel::create(camera, projector, rig.rig.R(), rig.rig.T());
    return rig;
}

TEST(SceneRenderer, PlaneDepthAndProjectorColumnMatchClosedForm)
{
    const SimRig rig = distortedRig();
    const Scene scene = makeScene(SceneKind::TiltedPlane, rig, Albedo::Uniform, 1);
    ASSERT_EQ(scene.planes.size(), 1u);
    const PlaneSurface& plane = scene.planes[0];
    const cv::Vec3d normal(plane.axes(0, 2), plane.axes(1, 2), plane.axes(2, 2));

    Rendering out;
    ASSERT_TRUE(SceneRenderer(rig).render(scene, RenderSettings{}, out));
    double maxDepthError = 0, maxColumnError = 0;
    int compared = 0, litMismatches = 0;
    for (int y = 0; y < out.depth.rows; y += 3) {
        for (int x = 0; x < out.depth.cols; x += 3) {
            // Closed form: the camera ray (distortion removed by the rig
            // model) meets the plane; the point projects into the projector.
            const cv::Vec3d ray = rig.rig.camera().rayThroughPixel({double(x), double(y)});
            const cv::Vec3d point = ray * (normal.dot(plane.centre) / normal.dot(ray));
            const cv::Vec2d projected = rig.rig.projector().project(rig.rig.cameraToProjector(point));
            const bool inside = projected[0] >= -0.5 && projected[0] <= 1023.5 && projected[1] >= -0.5 &&
                                projected[1] <= 767.5;
            maxDepthError = std::max(maxDepthError, std::abs(out.depth.at<float>(y, x) - point[2]));
            if (inside != (out.lit.at<std::uint8_t>(y, x) == 1)) ++litMismatches;
            if (!inside) continue;
            maxColumnError = std::max(maxColumnError, std::abs(out.projectorColumn.at<float>(y, x) - projected[0]));
            ++compared;
        }
    }
    EXPECT_GT(compared, 40000);
    EXPECT_EQ(litMismatches, 0);
    EXPECT_LT(maxDepthError, 1e-3);   // mm (float storage: ~6e-5 mm at 1 m)
    EXPECT_LT(maxColumnError, 1e-3);  // projector px
}

// Whether the segment p -> q passes through the sphere.
bool segmentHitsSphere(const cv::Vec3d& p, const cv::Vec3d& q, const Sphere& s)
{
    const cv::Vec3d d = q - p;
    const double t = std::clamp((s.centre - p).dot(d) / d.dot(d), 0.0, 1.0);
    return cv::norm(p + t * d - s.centre) < s.radius;
}

TEST(SceneRenderer, SphereCastsTheShadowClosedFormPredicts)
{
    const SimRig rig = desktopRig();
    const Scene scene = makeScene(SceneKind::SphereBeforeWall, rig, Albedo::Uniform, 1);
    ASSERT_EQ(scene.spheres.size(), 1u);
    const Sphere& sphere = scene.spheres[0];
    const double wallZ = scene.planes[0].centre[2];
    const cv::Vec3d projector = rig.rig.projectorCentreInCamera();

    Rendering out;
    ASSERT_TRUE(SceneRenderer(rig).render(scene, RenderSettings{}, out));
    int wallShadow = 0, sphereShadow = 0, mismatches = 0;
    for (int y = 0; y < out.depth.rows; ++y) {
        for (int x = 0; x < out.depth.cols; ++x) {
            const cv::Vec3d ray = rig.rig.camera().rayThroughPixel({double(x), double(y)});
            // Nearest of sphere and wall along the ray.
            const double b = ray.dot(sphere.centre), a = ray.dot(ray);
            const double disc = b * b - a * (sphere.centre.dot(sphere.centre) - sphere.radius * sphere.radius);
            const bool onSphere = disc >= 0;
            const cv::Vec3d point = onSphere ? ray * ((b - std::sqrt(disc)) / a) : ray * wallZ;
            const cv::Vec2d uv = rig.rig.projector().project(rig.rig.cameraToProjector(point));
            const bool inside = uv[0] >= -0.5 && uv[0] <= 1023.5 && uv[1] >= -0.5 && uv[1] <= 767.5;
            bool shadow;
            if (onSphere) {
                shadow = (point - sphere.centre).dot(projector - point) <= 0;  // faces away from the projector
                sphereShadow += shadow && inside;
            } else {
                shadow = segmentHitsSphere(point, projector, sphere);
                wallShadow += shadow && inside;
            }
            const bool lit = inside && !shadow;
            mismatches += lit != (out.lit.at<std::uint8_t>(y, x) == 1);
        }
    }
    EXPECT_GT(wallShadow, 30000);   // the sphere's shadow on the wall, left of the sphere
    EXPECT_GT(sphereShadow, 2000);  // the crescent of the sphere turned away from the projector
    EXPECT_LE(mismatches, 2);       // boundary pixels within rounding of the closed form
    // Shadowed pixels are dark: only ambient light reaches them.
    const cv::Mat shadowMask = (out.lit == 0) & (out.depth == out.depth);
    const cv::Mat litMask = out.lit == 1;
    EXPECT_LT(cv::mean(out.image, shadowMask)[1], 15.0);
    EXPECT_GT(cv::mean(out.image, litMask)[1], 60.0);
}

// Mean absolute difference between horizontally adjacent pixels.
double horizontalVariation(const cv::Mat& image)
{
    cv::Mat diff;
    cv::absdiff(image.colRange(1, image.cols), image.colRange(0, image.cols - 1), diff);
    const cv::Scalar m = cv::mean(diff);
    return (m[0] + m[1] + m[2]) / 3;
}

TEST(SceneRenderer, LedOffLeavesOnlyAmbientLightAndNoStripes)
{
    const SimRig rig = desktopRig();
    const Scene scene = makeScene(SceneKind::TiltedPlane, rig, Albedo::Uniform, 1);
    const SceneRenderer renderer(rig);
    RenderSettings settings;
    settings.ambient = 0.3;
    Rendering on, off;
    ASSERT_TRUE(renderer.render(scene, settings, on));
    settings.projectorOn = false;
    ASSERT_TRUE(renderer.render(scene, settings, off));
    EXPECT_GT(horizontalVariation(on.image), 10.0);
    EXPECT_LT(horizontalVariation(off.image), 0.5);
    EXPECT_EQ(cv::countNonZero(off.lit), 0);
    EXPECT_EQ(cv::countNonZero(off.projectorColumn == off.projectorColumn), 0);  // all NaN
    EXPECT_EQ(idealEdgeCrossings(off, rig.pattern), 0);
    // Ambient only: 0.8 reflectance * 0.3 * 255 = 61 digits everywhere.
    EXPECT_NEAR(cv::mean(off.image)[1], 61.2, 1.0);
}

// Standard deviation of (noisy - clean) over pixels well away from clipping.
double noiseSigma(const Rendering& clean, const Rendering& noisy)
{
    double sum = 0, sum2 = 0;
    long n = 0;
    for (int y = 0; y < clean.image.rows; ++y)
        for (int x = 0; x < clean.image.cols; ++x)
            for (int c = 0; c < 3; ++c) {
                const int v = clean.image.at<cv::Vec3b>(y, x)[c];
                if (v < 50 || v > 205) continue;
                const double d = noisy.image.at<cv::Vec3b>(y, x)[c] - v;
                sum += d;
                sum2 += d * d;
                ++n;
            }
    return std::sqrt(sum2 / n - (sum / n) * (sum / n));
}

TEST(SceneRenderer, NoiseHasTheRequestedSigma)
{
    const SimRig rig = desktopRig();
    const Scene scene = makeScene(SceneKind::TiltedPlane, rig, Albedo::Uniform, 1);
    const SceneRenderer renderer(rig);
    RenderSettings settings;
    settings.contrast = 0.5;
    settings.ambient = 0.3;
    Rendering clean, noisy;
    ASSERT_TRUE(renderer.render(scene, settings, clean));
    for (double sigma : {2.0, 8.0, 16.0}) {
        settings.noiseSigma = sigma;
        ASSERT_TRUE(renderer.render(scene, settings, noisy));
        // The clean image is quantised too: (noisy - clean) has sigma^2 + 2/12.
        EXPECT_NEAR(noiseSigma(clean, noisy), std::sqrt(sigma * sigma + 1.0 / 6), 0.1 * sigma) << "sigma " << sigma;
    }
}

TEST(SceneRenderer, ShotNoiseVarianceFollowsTheSignal)
{
    const SimRig rig = desktopRig();
    const Scene scene = makeScene(SceneKind::TiltedPlane, rig, Albedo::Uniform, 1);
    const SceneRenderer renderer(rig);
    RenderSettings settings;
    settings.ambient = 0.3;
    settings.contrast = 0.5;
    Rendering clean, noisy;
    ASSERT_TRUE(renderer.render(scene, settings, clean));
    settings.shotNoise = 0.5;
    ASSERT_TRUE(renderer.render(scene, settings, noisy));
    double measured = 0, predicted = 0;
    long n = 0;
    for (int y = 0; y < clean.image.rows; ++y)
        for (int x = 0; x < clean.image.cols; ++x) {
            const int v = clean.image.at<cv::Vec3b>(y, x)[1];
            if (v < 50 || v > 205) continue;
            const double d = noisy.image.at<cv::Vec3b>(y, x)[1] - v;
            measured += d * d;
            predicted += 0.5 * v + 1.0 / 6;
            ++n;
        }
    ASSERT_GT(n, 10000);
    EXPECT_NEAR(measured / predicted, 1.0, 0.1);
}

TEST(SceneRenderer, DeterministicForASeed)
{
    const SimRig rig = desktopRig();
    const Scene a = makeScene(SceneKind::Clutter, rig, Albedo::Photo, 7);
    const Scene b = makeScene(SceneKind::Clutter, rig, Albedo::Photo, 7);
    const SceneRenderer renderer(rig);
    RenderSettings settings;
    settings.noiseSigma = 4;
    settings.seed = 11;
    Rendering first, second, otherSeed;
    ASSERT_TRUE(renderer.render(a, settings, first));
    ASSERT_TRUE(renderer.render(b, settings, second));
    EXPECT_EQ(cv::norm(first.image, second.image, cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::countNonZero(first.depth != second.depth), cv::countNonZero(first.depth != first.depth));  // NaNs only
    settings.seed = 12;
    ASSERT_TRUE(renderer.render(a, settings, otherSeed));
    const cv::Mat differs = (first.image != otherSeed.image);
    EXPECT_GT(cv::countNonZero(differs.reshape(1)), 0.5 * differs.total() * 3);
    // The scene seed moves the objects.
    const Scene moved = makeScene(SceneKind::Clutter, rig, Albedo::Photo, 8);
    EXPECT_NE(moved.spheres[0].centre, a.spheres[0].centre);
}

TEST(SceneRenderer, ReusesTheOutputBuffers)
{
    const SimRig rig = desktopRig();
    const Scene scene = makeScene(SceneKind::TiltedPlane, rig, Albedo::Checker, 1);
    const SceneRenderer renderer(rig);
    Rendering out;
    ASSERT_TRUE(renderer.render(scene, RenderSettings{}, out));
    const void* image = out.image.data;
    const void* depth = out.depth.data;
    ASSERT_TRUE(renderer.render(scene, RenderSettings{}, out));
    EXPECT_EQ(out.image.data, image);
    EXPECT_EQ(out.depth.data, depth);
}

TEST(SceneRenderer, BayerMosaicDemosaicsToTheSameColours)
{
    const SimRig rig = desktopRig();
    const Scene scene = makeScene(SceneKind::TiltedPlane, rig, Albedo::Uniform, 1);
    const SceneRenderer renderer(rig);
    RenderSettings settings;
    settings.projectorOn = false;  // smooth colour: demosaicing is exact up to rounding
    settings.ambient = 0.5;
    settings.crosstalk = cv::Matx33d(1.0, 0, 0, 0, 0.5, 0, 0, 0, 0.2);  // R, G, B sensors differ
    Rendering plain, bayer;
    ASSERT_TRUE(renderer.render(scene, settings, plain));
    settings.bayer = true;
    ASSERT_TRUE(renderer.render(scene, settings, bayer));
    const cv::Rect inner(2, 2, plain.image.cols - 4, plain.image.rows - 4);
    const cv::Scalar p = cv::mean(plain.image(inner)), q = cv::mean(bayer.image(inner));
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(q[c], p[c], 1.0) << "channel " << c;
    EXPECT_NEAR(p[2], 102, 1.5);  // red: 0.8 * 0.5 * 255
    EXPECT_NEAR(p[0], 20.4, 1.5); // blue sensor at 0.2
}

// Sharpness of the stripes in the noise-free green signal: mean squared
// horizontal difference over the squared mean, over lit pixels. Blurring a
// step of height h with sigma s leaves a squared-difference sum ~ h^2 / s.
double stripeSharpness(const Rendering& r)
{
    double energy = 0, sum = 0;
    long n = 0;
    for (int y = 0; y < r.radiance.rows; y += 8)
        for (int x = 0; x + 1 < r.radiance.cols; ++x) {
            if (!r.lit.at<std::uint8_t>(y, x) || !r.lit.at<std::uint8_t>(y, x + 1)) continue;
            const double a = r.radiance.at<cv::Vec3f>(y, x)[1], b = r.radiance.at<cv::Vec3f>(y, x + 1)[1];
            energy += (b - a) * (b - a);
            sum += a;
            ++n;
        }
    const double mean = sum / n;
    return energy / n / (mean * mean);
}

TEST(SceneRenderer, ProjectorDefocusGrowsAwayFromTheFocusDistance)
{
    const SimRig rig = desktopRig();
    const SceneRenderer renderer(rig);
    // Walls square to the projector's axis: one projector depth each.
    const cv::Vec3d axis(rig.rig.R()(2, 0), rig.rig.R()(2, 1), rig.rig.R()(2, 2));
    const double focus = rig.rig.cameraToProjector({0, 0, rig.workingDistanceMm})[2];
    auto wallAt = [&](double projectorDepth) {
        Scene scene;
        scene.planes.push_back({rig.rig.projectorCentreInCamera() + axis * projectorDepth, rig.rig.R().t(), {1e9, 1e9}, {}});
        return scene;
    };
    RenderSettings sharp;
    sharp.cameraBlurPx = 0;
    sharp.ambient = 0;
    sharp.projectorDefocusPx = 0;
    RenderSettings defocused = sharp;
    defocused.projectorDefocusPx = 3;
    Rendering a, b;
    // At the focus distance the defocus term vanishes.
    ASSERT_TRUE(renderer.render(wallAt(focus), sharp, a));
    ASSERT_TRUE(renderer.render(wallAt(focus), defocused, b));
    EXPECT_NEAR(stripeSharpness(b) / stripeSharpness(a), 1.0, 0.02);
    // At 0.6 of it sigma grows from 0.5 by 3 px * (1/0.6 - 1) = 2 projector
    // px: stripe edges are much softer.
    ASSERT_TRUE(renderer.render(wallAt(0.6 * focus), sharp, a));
    ASSERT_TRUE(renderer.render(wallAt(0.6 * focus), defocused, b));
    EXPECT_LT(stripeSharpness(b) / stripeSharpness(a), 0.5);
    // ... and so they are behind the focus, at 1.6 times it (+3 * 0.375 px).
    ASSERT_TRUE(renderer.render(wallAt(1.6 * focus), sharp, a));
    ASSERT_TRUE(renderer.render(wallAt(1.6 * focus), defocused, b));
    EXPECT_LT(stripeSharpness(b) / stripeSharpness(a), 0.8);
}

TEST(Textures, AlbedosHaveTheirCharacter)
{
    const SimRig rig = desktopRig();
    const SceneRenderer renderer(rig);
    RenderSettings settings;
    settings.projectorOn = false;  // ambient only: the image is the albedo
    settings.ambient = 1.0;
    for (Albedo albedo : {Albedo::Uniform, Albedo::Checker, Albedo::Coloured, Albedo::Photo}) {
        Rendering out;
        ASSERT_TRUE(renderer.render(makeScene(SceneKind::TiltedPlane, rig, albedo, 3), settings, out));
        double chroma = 0;
        std::vector<double> luminance;
        for (int y = 0; y < out.radiance.rows; y += 4)
            for (int x = 0; x < out.radiance.cols; x += 4) {
                const cv::Vec3f v = out.radiance.at<cv::Vec3f>(y, x);
                const double hi = std::max({v[0], v[1], v[2]}), lo = std::min({v[0], v[1], v[2]});
                chroma += (hi - lo) / hi;
                luminance.push_back(v[0] + v[1] + v[2]);
            }
        chroma /= luminance.size();
        std::sort(luminance.begin(), luminance.end());
        const double spread = luminance[luminance.size() * 9 / 10] / luminance[luminance.size() / 10];
        switch (albedo) {
        case Albedo::Uniform:
            EXPECT_LT(chroma, 1e-3);
            EXPECT_NEAR(spread, 1.0, 1e-3);
            break;
        case Albedo::Checker:  // grey squares of 0.85 and 0.25
            EXPECT_LT(chroma, 1e-3);
            EXPECT_NEAR(spread, 0.85 / 0.25, 0.1);
            break;
        case Albedo::Coloured:  // strongly saturated patches
            EXPECT_GT(chroma, 0.6);
            break;
        case Albedo::Photo:  // broad range of brightness, moderate colour
            EXPECT_GT(spread, 2.0);
            EXPECT_GT(chroma, 0.1);
            EXPECT_LT(chroma, 0.6);
            break;
        }
    }
}

TEST(SceneRenderer, RejectsBadSettingsWithTheirName)
{
    const SimRig rig = desktopRig();
    const SceneRenderer renderer(rig);
    RenderSettings settings;
    settings.contrast = 1.5;
    Rendering out;
    const Status s = renderer.render(makeScene(SceneKind::TiltedPlane, rig, Albedo::Uniform, 1), settings, out);
    EXPECT_FALSE(s);
    EXPECT_EQ(s.message(), "render setting contrast is 1.500000: it must be in [0, 1]");
}

// One row: projector columns 3.05, 3.95, ..., 92.15, depth 1000 mm, all lit.
Rendering syntheticRow()
{
    constexpr int kWidth = 100;
    Rendering r;
    r.depth = cv::Mat(1, kWidth, CV_32FC1, cv::Scalar(1000));
    r.projectorColumn.create(1, kWidth, CV_32FC1);
    for (int x = 0; x < kWidth; ++x) r.projectorColumn.at<float>(0, x) = static_cast<float>(3.05 + 0.9 * x);
    r.lit = cv::Mat(1, kWidth, CV_8UC1, cv::Scalar(1));
    return r;
}

TEST(IdealEdgeCrossings, CountsPatternEdgesBetweenLitContinuousNeighbours)
{
    const SimRig rig = desktopRig();  // stripes of 8 px: edges at 7.5, 15.5, ..., 87.5 in this row
    Rendering r = syntheticRow();
    EXPECT_EQ(idealEdgeCrossings(r, rig.pattern), 11);
    r.lit.at<std::uint8_t>(0, 4) = 0;  // pixels 4 (6.65) and 5 (7.55) straddle edge 7.5
    EXPECT_EQ(idealEdgeCrossings(r, rig.pattern), 10);
    r = syntheticRow();
    r.depth.colRange(50, 100).setTo(1030);  // 3% step between 49 (47.15) and 50 (48.05), across edge 47.5
    EXPECT_EQ(idealEdgeCrossings(r, rig.pattern), 10);
    r.depth.colRange(50, 100).setTo(1015);  // 1.5%: still one continuous surface
    EXPECT_EQ(idealEdgeCrossings(r, rig.pattern), 11);
}

// The simulated boards' files are exactly the simulator's rigs, so the
// simulated camera and the decoder agree on the geometry.
TEST(BoardSim, CalibrationAndPatternFilesAreTheSimulatorsRigs)
{
    const std::pair<const char*, SimRig> boards[] = {{"sim", fingerprintRig()}, {"sim-desktop", desktopRig()}};
    for (const auto& [name, rig] : boards) {
        SCOPED_TRACE(name);
        const std::string folder = std::string(STRIA_SOURCE_DIR) + "/board/" + name;
        const auto loaded = firmware::loadCalibrationFile(folder + "/calibration.yaml");
        ASSERT_TRUE(loaded) << loaded.message();
        EXPECT_EQ(loaded->camera().width, rig.rig.camera().width);
        EXPECT_EQ(loaded->camera().height, rig.rig.camera().height);
        EXPECT_EQ(loaded->projector().width, rig.rig.projector().width);
        EXPECT_LT(cv::norm(loaded->camera().K, rig.rig.camera().K, cv::NORM_INF), 1e-9);
        EXPECT_LT(cv::norm(loaded->projector().K, rig.rig.projector().K, cv::NORM_INF), 1e-9);
        EXPECT_LT(cv::norm(loaded->camera().distortion, rig.rig.camera().distortion, cv::NORM_INF), 1e-12);
        EXPECT_LT(cv::norm(loaded->projector().distortion, rig.rig.projector().distortion, cv::NORM_INF), 1e-12);
        EXPECT_LT(cv::norm(loaded->R(), rig.rig.R(), cv::NORM_INF), 1e-12);
        EXPECT_LT(cv::norm(loaded->T(), rig.rig.T(), cv::NORM_INF), 1e-9);
        const auto pattern = firmware::loadPatternFile(folder + "/pattern.yaml");
        ASSERT_TRUE(pattern) << pattern.message();
        EXPECT_EQ(pattern->colorLetters(), rig.pattern.colorLetters());
        EXPECT_EQ(pattern->stripeWidth(), rig.pattern.stripeWidth());
        EXPECT_EQ(pattern->window(), rig.pattern.window());
    }
}

TEST(SimRigs, RendererFindsTheWorkingDistanceFromTheGeometry)
{
    // Built from a RigModel alone, the renderer lights a scene like the one
    // told the working distance.
    for (const SimRig& rig : {desktopRig(), fingerprintRig(), endoscopeRig()}) {
        const Scene scene = makeScene(SceneKind::TiltedPlane, rig, Albedo::Uniform, 1);
        Rendering told, derived;
        ASSERT_TRUE(SceneRenderer(rig).render(scene, RenderSettings{}, told));
        ASSERT_TRUE(SceneRenderer(rig.rig, rig.pattern).render(scene, RenderSettings{}, derived));
        EXPECT_LE(cv::norm(told.image, derived.image, cv::NORM_INF), 1.0) << rig.workingDistanceMm;
        EXPECT_GT(cv::mean(told.image)[1], 40.0);  // neither black nor saturated
        EXPECT_LT(cv::mean(told.image)[1], 200.0);
    }
}

TEST(SimRigs, StripesAreAboutSevenCameraPixelsWideAtTheWorkingDistance)
{
    for (const SimRig& rig : {desktopRig(), fingerprintRig(), endoscopeRig()}) {
        // A surface facing the camera at the working distance: distance in
        // camera px between the points lit by two edges 16 stripes apart.
        Scene scene;
        scene.planes.push_back({{0, 0, rig.workingDistanceMm}, cv::Matx33d::eye(), {1e9, 1e9}, {}});
        Rendering out;
        RenderSettings settings;
        settings.samplesPerPixel = 1;
        ASSERT_TRUE(SceneRenderer(rig).render(scene, settings, out));
        const int y = out.depth.rows / 2, x = out.depth.cols / 2;
        const float* column = out.projectorColumn.ptr<float>(y);
        const double slope = (column[x + 8] - column[x - 8]) / 16.0;  // projector px per camera px
        EXPECT_NEAR(rig.pattern.stripeWidth() / slope, 7.0, 0.5) << rig.rig.camera().width;
    }
}

}  // namespace
}  // namespace stria::hal::sim
