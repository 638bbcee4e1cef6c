#pragma once
// The scene simulator: analytic scenes lit by the stripe projector and seen by
// the camera of a RigModel, rendered with the physics that matter to the
// decoder (lens distortion on both devices, shadows, projector defocus,
// camera blur, albedo, ambient light, colour crosstalk, noise, Bayer mosaic)
// and with per-pixel ground truth (depth, projector column, lit).
//
// Everything is in the camera frame (OpenCV: x right, y down, z forward, mm).
// Reflectances and light levels are linear, 1.0 = 255 digits for a white
// surface under full projector light at the rig's working distance.
// See docs/simulator.md for the model and the scenes.

#include "pipeline/pattern.hpp"
#include "pipeline/rig.hpp"
#include "pipeline/status.hpp"

#include <opencv2/core.hpp>

#include <cstdint>
#include <functional>
#include <optional>
#include <string_view>
#include <vector>

namespace stria::hal::sim {

// Standard rigs: a RigModel and the pattern designed for it.
struct SimRig {
    pipeline::RigModel rig;
    pipeline::StripePattern pattern;
    double workingDistanceMm;
};

// Camera 780x580, projector 1024x768, objects ~1000 mm away, ~7 camera px per
// stripe, pattern 128 stripes x 8 px with window 4, ~19 deg triangulation angle.
SimRig desktopRig();
// Camera 1388x1038 (the paper's camera), same geometry and field of view.
SimRig desktopRigLarge();
// Fingerprint head: object at ~60 mm, camera 1280x960.
SimRig fingerprintRig();
// Endoscope head: tube wall at 10-30 mm, wide-angle camera 640x480.
SimRig endoscopeRig();

enum class SceneKind { TiltedPlane, SphereBeforeWall, TexturedRelief, Clutter, Fan, Fingertip, Tube };
enum class Albedo { Uniform, Checker, Coloured /* strongly coloured procedural */, Photo /* printed-photo-like */ };

// "plane", "sphere", "relief", "clutter", "fan", "fingertip", "tube"
const char* sceneName(SceneKind kind);
std::optional<SceneKind> sceneFromName(std::string_view name);
// "uniform", "checker", "coloured", "photo"
const char* albedoName(Albedo albedo);
// The albedo a scene is shown with unless one is asked for (relief: photo).
Albedo defaultAlbedo(SceneKind kind);
std::optional<Albedo> albedoFromName(std::string_view name);

// Surface reflectance as a function of 2-D surface coordinates in mm.
struct Texture {
    Albedo kind = Albedo::Uniform;
    cv::Vec3f colour{0.8f, 0.8f, 0.8f};  // B G R reflectance (Uniform; light squares of Checker)
    cv::Vec3f colour2{0.2f, 0.2f, 0.2f};  // dark squares of Checker
    double cellMm = 10;                   // Checker square size; Coloured/Photo: mm per texel
    cv::Mat image;                        // Coloured/Photo: CV_32FC3 tile (B G R), repeated

    cv::Vec3f reflectance(const cv::Vec2d& uvMm) const;
};

// Primitives. `axes` columns are the primitive's local x, y, z axes in the
// camera frame (a rotation); `centre` its origin in the camera frame.
struct PlaneSurface {  // local z is the normal; bounded by |x| <= halfSize[0], |y| <= halfSize[1]
    cv::Vec3d centre;
    cv::Matx33d axes = cv::Matx33d::eye();
    cv::Vec2d halfSize{1e9, 1e9};
    Texture texture;
};
struct Sphere {
    cv::Vec3d centre;
    double radius = 1;
    Texture texture;
};
struct Box {  // |local x,y,z| <= halfSize
    cv::Vec3d centre;
    cv::Matx33d axes = cv::Matx33d::eye();
    cv::Vec3d halfSize{1, 1, 1};
    Texture texture;
};
struct Cylinder {  // axis = local z, |local z| <= halfLength; inside = seen from within (a tube wall)
    cv::Vec3d centre;
    cv::Matx33d axes = cv::Matx33d::eye();
    double radius = 1;
    double halfLength = 1;
    bool inside = false;
    Texture texture;
};
// Surface centre + a*x + b*y + height(a, b)*z over a grid of heights
// (bilinear between samples), |a| <= halfSize[0], |b| <= halfSize[1].
// Rays walk the grid cell by cell (skipping blocks whose height range they
// miss) and meet each bilinear cell exactly (a quadratic in t).
struct HeightField {
    static constexpr int kBlock = 8;  // cells per block side
    cv::Vec3d centre;
    cv::Matx33d axes = cv::Matx33d::eye();
    cv::Mat heights;         // CV_64FC1, row j at b = -halfSize[1] + j * spacingMm, column i likewise in a
    double spacingMm = 1;
    cv::Vec2d halfSize{0, 0};
    double heightMin = 0;
    double heightMax = 0;
    cv::Mat cellRange;       // CV_64FC2: (min, max) height of each cell (rows-1 x cols-1)
    cv::Mat blockRange;      // CV_64FC2: (min, max) height of each block of kBlock x kBlock cells
    Texture texture;

    // Samples `height` on a grid of `spacingMm` covering |a| <= halfSize[0], |b| <= halfSize[1].
    static HeightField sample(const cv::Vec3d& centre, const cv::Matx33d& axes, const cv::Vec2d& halfSize,
                              double spacingMm, const std::function<double(double a, double b)>& height,
                              const Texture& texture);
    // Bilinear height at (a, b); (a, b) must lie inside the grid.
    double heightAt(double a, double b) const;
};

struct Hit {
    double t = 0;            // ray parameter: point = origin + t * direction
    cv::Vec3d point;         // camera frame, mm
    cv::Vec3d normal;        // unit, facing the ray origin
    cv::Vec3f reflectance;   // B G R
};

struct Scene {
    std::vector<PlaneSurface> planes;
    std::vector<Sphere> spheres;
    std::vector<Box> boxes;
    std::vector<Cylinder> cylinders;
    std::vector<HeightField> heightFields;

    // Nearest hit with tMin < t < tMax along origin + t * direction.
    std::optional<Hit> intersect(const cv::Vec3d& origin, const cv::Vec3d& direction, double tMin = 1e-9,
                                 double tMax = 1e30) const;
    // True if anything lies strictly between `from` and `to` (shadow rays).
    bool blocked(const cv::Vec3d& from, const cv::Vec3d& to) const;
};

// The scene of that kind, placed for the rig's working distance and field of
// view. `albedo` textures the objects; deterministic for a seed.
Scene makeScene(SceneKind kind, const SimRig& rig, Albedo albedo, std::uint64_t seed);

struct RenderSettings {
    double contrast = 1.0;          // pattern contrast: off level = (1 - contrast) * on level
    double ambient = 0.05;          // ambient light, fraction of projector white
    double exposure = 1.0;          // scale before noise/quantisation
    double noiseSigma = 0.0;        // additive white Gaussian noise, in 8-bit digits (the paper's noise)
    double shotNoise = 0.0;         // photon noise: variance = shotNoise * signal (digits)
    double readNoise = 0.0;         // digits
    cv::Matx33d crosstalk = cv::Matx33d::eye();  // camera colour crosstalk (rows: sensor R,G,B; cols: light R,G,B)
    bool bayer = false;             // RGGB mosaic + bilinear demosaic
    int samplesPerPixel = 4;        // anti-aliasing (supersampling grid n x n with n = sqrt)
    double projectorFocusMm = 0;    // sharp projector depth; 0 = that of (0, 0, D); defocus grows away from it
    double projectorBlurPx = 0.5;   // blur sigma (in projector px) at the focus distance
    // Thin-lens defocus: sigma = projectorBlurPx + projectorDefocusPx * |focus / z - 1|
    // (z = depth along the projector axis); projectorDefocusPx = aperture * f / (4 * focus).
    double projectorDefocusPx = 3.0;
    double cameraBlurPx = 0.5;      // camera blur sigma, camera px
    bool projectorOn = true;        // LED off -> ambient light only, no stripes
    std::uint64_t seed = 1;         // noise seed: deterministic for a seed
};

struct Rendering {
    cv::Mat image;            // CV_8UC3, BGR, camera size
    cv::Mat depth;            // CV_32FC1, z in mm of the surface seen at each pixel centre, NaN = nothing
    cv::Mat projectorColumn;  // CV_32FC1, projector x (OpenCV px) that lights that surface point, NaN if none
    cv::Mat lit;              // CV_8UC1, 1 = the projector sees that point (not in shadow), 0 otherwise
    cv::Mat radiance;         // CV_32FC3, B G R noise-free sensor signal in digits, after camera blur (reused)
    cv::Mat raw;              // CV_8UC1, the RGGB mosaic when RenderSettings::bayer (reused)
};

class SceneRenderer {
public:
    // The working distance D sets the light level (a white surface facing
    // the projector at (0, 0, D) receives full light) and the focus unless
    // RenderSettings::projectorFocusMm says otherwise. Without it, D is the
    // depth where the projector's axis passes closest to the camera's (1000
    // mm if they are parallel), which is exactly D for the built-in rigs.
    SceneRenderer(const pipeline::RigModel& rig, const pipeline::StripePattern& pattern);
    SceneRenderer(const pipeline::RigModel& rig, const pipeline::StripePattern& pattern, double workingDistanceMm);
    explicit SceneRenderer(const SimRig& rig) : SceneRenderer(rig.rig, rig.pattern, rig.workingDistanceMm) {}

    // Renders into `out`, reusing its buffers when the size matches (no reallocation per frame).
    Status render(const Scene& scene, const RenderSettings& settings, Rendering& out) const;

    const pipeline::RigModel& rig() const { return rig_; }
    const pipeline::StripePattern& pattern() const { return pattern_; }

private:
    pipeline::RigModel rig_;
    pipeline::StripePattern pattern_;
    double workingDistanceMm_;
    cv::Mat rays_;  // CV_64FC2: undistorted normalised camera ray (x/z, y/z) per pixel centre
    std::vector<float> slide_;  // blurred slide transmittance per blur level (scene_renderer.cpp)
};

// Number of (row, pattern edge) crossings a perfect decoder could find: for
// each row y and each pair of horizontally adjacent pixels (x, x+1) that are
// both lit, whose depths differ by at most 2% of their mean depth and whose
// projector columns pc(x), pc(x+1) straddle a pattern edge column e
// (min(pc) < e <= max(pc)), one crossing per edge column in that interval.
int idealEdgeCrossings(const Rendering& rendering, const pipeline::StripePattern& pattern);

}  // namespace stria::hal::sim
