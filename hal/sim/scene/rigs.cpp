// The standard simulated rigs. Each is built from a few physical choices
// (image sizes, field of view, baseline, convergence) so that a stripe of the
// common pattern is about 7 camera pixels wide on a surface facing the camera
// at the working distance: stripe_px = 8 * fx_camera / (fx_projector * cos^2 angle).
#include "hal/sim/scene/scene.hpp"

#include <cmath>
#include <cstdlib>
#include <cstdio>

namespace stria::hal::sim {
namespace {

// `stria pattern generate --stripes 128 --window 4 --seed 1` (the full
// alphabet); also in board/sim/pattern.yaml.
constexpr const char* kPatternColors =
    "MCKWCRMCGMBYRBYMGWRKWGRCRCGRBWYBCYBCRKCYMCYMCGRCWRBWKGMBGRWGMCGRBCRBCYMCKRWCRKWKRCYKWGRMGBYCBYCKRCWKYCKYBRWKBWYKWBYGMKGWRGBWKBWR";
constexpr int kStripeWidth = 8;
constexpr int kWindow = 4;

pipeline::LensModel lens(int width, int height, double f, cv::Vec2d principalOffset, cv::Vec<double, 5> distortion)
{
    pipeline::LensModel m;
    m.width = width;
    m.height = height;
    m.K = cv::Matx33d(f, 0, (width - 1) / 2.0 + principalOffset[0], 0, f, (height - 1) / 2.0 + principalOffset[1], 0, 0,
                      1);
    m.distortion = distortion;
    return m;
}

// Projector at (baseline, 0, 0) in the camera frame, its optical axis turned
// towards the camera's axis at `convergeMm`.
SimRig makeRig(const pipeline::LensModel& camera, const pipeline::LensModel& projector, double baselineMm,
               double convergeMm, double workingDistanceMm)
{
    const cv::Vec3d centre(baselineMm, 0, 0);
    const cv::Vec3d zAxis = cv::normalize(cv::Vec3d(0, 0, convergeMm) - centre);
    const cv::Vec3d yAxis(0, 1, 0);
    const cv::Vec3d xAxis = yAxis.cross(zAxis);
    const cv::Matx33d R(xAxis[0], xAxis[1], xAxis[2], yAxis[0], yAxis[1], yAxis[2], zAxis[0], zAxis[1], zAxis[2]);
    auto rig = pipeline::RigModel::create(camera, projector, R, -(R * centre));
    auto pattern = pipeline::StripePattern::create(kStripeWidth, kPatternColors, kWindow);
    if (!rig || !pattern) {
        // Built from constants: a failure is a programming error.
        std::fprintf(stderr, "stria: invalid built-in rig: %s%s\n", rig.message().c_str(), pattern.message().c_str());
        std::abort();
    }
    return SimRig{*rig, *pattern, workingDistanceMm};
}

}  // namespace

// 19.3 deg triangulation angle and 350 mm baseline, close to the paper's
// 19.2 deg / 366 mm; small barrel distortion on the camera, nearly none on the
// projector (its distortion bends the light sheets, see docs/simulator.md).
SimRig desktopRig()
{
    return makeRig(lens(780, 580, 1252, {3.0, -2.0}, {-0.10, 0.08, 0.0005, -0.0003, 0}),
                   lens(1024, 768, 1600, {0, 0}, {0.002, 0, 0, 0, 0}), 350, 1000, 1000);
}

SimRig desktopRigLarge()
{
    const double scale = 1388.0 / 780.0;
    return makeRig(lens(1388, 1038, 1252 * scale, {3.0 * scale, -2.0 * scale}, {-0.10, 0.08, 0.0005, -0.0003, 0}),
                   lens(1024, 768, 1600, {0, 0}, {0.002, 0, 0, 0, 0}), 350, 1000, 1000);
}

// 20 mm x 15 mm field at 60 mm (0.026 mm per pixel, a 0.45 mm ridge period is
// 17 px); 20 deg triangulation: a 0.05 mm ridge moves a stripe edge ~0.7 px.
SimRig fingerprintRig()
{
    return makeRig(lens(780, 580, 2340, {0, 0}, {-0.04, 0, 0, 0, 0}), lens(1024, 768, 3030, {0, 0}, {0.002, 0, 0, 0, 0}),
                   21.8, 60, 60);
}

// Wide-angle (90 deg) camera with strong barrel distortion and a projector
// 4 mm beside it, converging at 20 mm (11 deg).
SimRig endoscopeRig()
{
    return makeRig(lens(640, 480, 320, {0, 0}, {-0.25, 0.06, 0, 0, 0}), lens(1024, 768, 381, {0, 0}, {-0.02, 0, 0, 0, 0}),
                   4.0, 20, 20);
}

}  // namespace stria::hal::sim
