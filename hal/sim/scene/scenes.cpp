// The standard scenes, placed relative to a rig's working distance D and the
// camera's field of view there, and their procedural textures.
#include "hal/sim/scene/scene.hpp"

#include <opencv2/imgproc.hpp>

#include <array>
#include <cmath>

namespace stria::hal::sim {
namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr int kTileTexels = 256;

cv::Matx33d rotX(double deg)
{
    const double c = std::cos(deg * kDeg), s = std::sin(deg * kDeg);
    return {1, 0, 0, 0, c, -s, 0, s, c};
}
cv::Matx33d rotY(double deg)
{
    const double c = std::cos(deg * kDeg), s = std::sin(deg * kDeg);
    return {c, 0, s, 0, 1, 0, -s, 0, c};
}
cv::Matx33d rotZ(double deg)
{
    const double c = std::cos(deg * kDeg), s = std::sin(deg * kDeg);
    return {c, -s, 0, s, c, 0, 0, 0, 1};
}
// Local z towards the camera (-z), local x along +x, local y along -y.
const cv::Matx33d kFacingCamera(1, 0, 0, 0, -1, 0, 0, 0, -1);

// Smooth periodic noise in [0, 1]: `cells` random values per tile side,
// interpolated bicubically with wrap-around so the tile repeats seamlessly.
cv::Mat periodicNoise(cv::RNG& rng, int cells)
{
    cv::Mat coarse(cells, cells, CV_32FC1);
    rng.fill(coarse, cv::RNG::UNIFORM, 0.0f, 1.0f);
    constexpr int pad = 3;
    cv::Mat padded;
    cv::copyMakeBorder(coarse, padded, pad, pad, pad, pad, cv::BORDER_WRAP);
    const double scale = static_cast<double>(kTileTexels) / cells;
    cv::Mat fine;
    cv::resize(padded, fine, cv::Size(), scale, scale, cv::INTER_CUBIC);
    const int offset = static_cast<int>(std::lround(pad * scale));
    cv::Mat tile = fine(cv::Rect(offset, offset, kTileTexels, kTileTexels)).clone();
    cv::normalize(tile, tile, 0, 1, cv::NORM_MINMAX);
    return tile;
}

// Flat patches of strong colours with sharp borders (a painted poster),
// shaded a little; every channel keeps at least 8% reflectance.
cv::Mat colouredTile(cv::RNG& rng)
{
    static const std::array<cv::Vec3f, 9> kPalette{{
        {0.10f, 0.10f, 0.85f}, {0.10f, 0.75f, 0.12f}, {0.85f, 0.20f, 0.10f}, {0.10f, 0.80f, 0.85f},
        {0.80f, 0.10f, 0.80f}, {0.80f, 0.75f, 0.10f}, {0.85f, 0.85f, 0.85f}, {0.08f, 0.45f, 0.90f},
        {0.20f, 0.20f, 0.20f},
    }};
    const cv::Mat region = periodicNoise(rng, 10);
    const cv::Mat choice = periodicNoise(rng, 10);
    const cv::Mat shade = periodicNoise(rng, 4);
    cv::Mat tile(kTileTexels, kTileTexels, CV_32FC3);
    for (int y = 0; y < kTileTexels; ++y)
        for (int x = 0; x < kTileTexels; ++x) {
            // Quantised noise gives patches; a second field scrambles which
            // colour each patch gets.
            const int level = static_cast<int>(region.at<float>(y, x) * 5.999f);
            const int index = (level * 3 + static_cast<int>(choice.at<float>(y, x) * 2.999f)) % kPalette.size();
            tile.at<cv::Vec3f>(y, x) = kPalette[index] * (0.75f + 0.25f * shade.at<float>(y, x));
        }
    return tile;
}

// A printed photograph: 1/f luminance over five octaves, slowly varying hue,
// and a few hard-edged darker shapes.
cv::Mat photoTile(cv::RNG& rng)
{
    cv::Mat luminance = cv::Mat::zeros(kTileTexels, kTileTexels, CV_32FC1);
    double amplitude = 1, total = 0;
    for (int cells = 4; cells <= 64; cells *= 2, amplitude *= 0.6) {
        luminance += periodicNoise(rng, cells) * amplitude;
        total += amplitude;
    }
    luminance /= total;
    cv::normalize(luminance, luminance, 0.1, 0.9, cv::NORM_MINMAX);
    const cv::Mat hueA = periodicNoise(rng, 3), hueB = periodicNoise(rng, 3), shapes = periodicNoise(rng, 6);
    cv::Mat tile(kTileTexels, kTileTexels, CV_32FC3);
    for (int y = 0; y < kTileTexels; ++y)
        for (int x = 0; x < kTileTexels; ++x) {
            const float l = luminance.at<float>(y, x) * (shapes.at<float>(y, x) > 0.7f ? 0.45f : 1.0f);
            const float a = 0.6f * (hueA.at<float>(y, x) - 0.5f), b = 0.6f * (hueB.at<float>(y, x) - 0.5f);
            const cv::Vec3f bgr(l * (1 - a - b), l * (1 + b), l * (1 + a));
            for (int c = 0; c < 3; ++c) tile.at<cv::Vec3f>(y, x)[c] = std::clamp(bgr[c], 0.03f, 0.95f);
        }
    return tile;
}

// `featureMm` sets the scale: checker squares, a texture tile is 8 features.
Texture makeTexture(Albedo albedo, const cv::Vec3f& colour, double featureMm, cv::RNG& rng)
{
    Texture t;
    t.kind = albedo;
    t.colour = colour;
    switch (albedo) {
    case Albedo::Uniform: break;
    case Albedo::Checker:
        t.colour = {0.85f, 0.85f, 0.85f};
        t.colour2 = {0.25f, 0.25f, 0.25f};
        t.cellMm = featureMm;
        break;
    case Albedo::Coloured:
        t.image = colouredTile(rng);
        t.cellMm = 8 * featureMm / kTileTexels;
        break;
    case Albedo::Photo:
        t.image = photoTile(rng);
        t.cellMm = 8 * featureMm / kTileTexels;
        break;
    }
    return t;
}

PlaneSurface plane(const cv::Vec3d& centre, const cv::Matx33d& axes, const Texture& texture,
                   cv::Vec2d halfSize = {1e9, 1e9})
{
    return PlaneSurface{centre, axes, halfSize, texture};
}

}  // namespace

Scene makeScene(SceneKind kind, const SimRig& simRig, Albedo albedo, std::uint64_t seed)
{
    const double D = simRig.workingDistanceMm;
    const pipeline::LensModel& camera = simRig.rig.camera();
    // Half the field of view at distance z.
    auto halfWidth = [&](double z) { return z * camera.width / 2 / camera.K(0, 0); };
    auto halfHeight = [&](double z) { return z * camera.height / 2 / camera.K(1, 1); };
    cv::RNG rng(seed * 0x9E3779B97F4A7C15ull + static_cast<std::uint64_t>(kind) + 1);
    auto uniform = [&](double lo, double hi) { return rng.uniform(lo, hi); };
    const cv::Vec3f white(0.8f, 0.8f, 0.8f);
    auto texture = [&](const cv::Vec3f& colour, double featureMm) { return makeTexture(albedo, colour, featureMm, rng); };

    Scene scene;
    switch (kind) {
    case SceneKind::TiltedPlane:
        scene.planes.push_back(plane({0, 0, D}, rotY(25) * rotX(10), texture(white, 0.04 * D)));
        break;

    case SceneKind::SphereBeforeWall:
        scene.planes.push_back(plane({0, 0, 1.2 * D}, cv::Matx33d::eye(), texture(white, 0.04 * D)));
        scene.spheres.push_back({{-0.05 * D, 0.02 * D, 0.95 * D}, 0.15 * D, texture(white, 0.04 * D)});
        break;

    case SceneKind::TexturedRelief: {
        // Gaussian hills and hollows on a gentle wave, slopes below ~1; a
        // 2 mm grid is within 0.02 mm of the smooth surface.
        struct Bump {
            double a, b, height, radius;
        };
        std::vector<Bump> bumps;
        for (int i = 0; i < 7; ++i)
            bumps.push_back({uniform(-0.3, 0.3) * D, uniform(-0.22, 0.22) * D,
                             uniform(0.02, 0.07) * D * (i % 3 == 2 ? -1 : 1), uniform(0.05, 0.12) * D});
        const double wave = uniform(0, 2 * M_PI);
        auto height = [bumps, wave, D](double a, double b) {
            double h = 0.01 * D * std::sin(2 * M_PI * a / (0.2 * D) + wave) * std::cos(2 * M_PI * b / (0.25 * D));
            for (const Bump& bump : bumps) {
                const double r2 = (a - bump.a) * (a - bump.a) + (b - bump.b) * (b - bump.b);
                h += bump.height * std::exp(-r2 / (2 * bump.radius * bump.radius));
            }
            return h;
        };
        const double z = 1.05 * D;
        scene.heightFields.push_back(HeightField::sample({0, 0, z}, kFacingCamera,
                                                         {1.25 * halfWidth(z), 1.25 * halfHeight(z)}, 0.002 * D,
                                                         height, texture(white, 0.05 * D)));
        break;
    }

    case SceneKind::Clutter: {
        const double floorY = 0.18 * D;
        scene.planes.push_back(plane({0, 0, 1.25 * D}, cv::Matx33d::eye(), texture(white, 0.04 * D)));
        const cv::Matx33d floorAxes(1, 0, 0, 0, 0, -1, 0, 1, 0);  // normal up (-y)
        scene.planes.push_back(plane({0, floorY, 0.925 * D}, floorAxes, texture({0.6f, 0.65f, 0.7f}, 0.04 * D),
                                     {0.6 * D, 0.325 * D}));
        auto tint = [&] {
            return cv::Vec3f(static_cast<float>(uniform(0.4, 0.9)), static_cast<float>(uniform(0.4, 0.9)),
                             static_cast<float>(uniform(0.4, 0.9)));
        };
        for (int i = 0; i < 3; ++i) {
            const cv::Vec3d half(uniform(0.03, 0.07) * D, uniform(0.04, 0.1) * D, uniform(0.03, 0.06) * D);
            scene.boxes.push_back({{uniform(-0.28, 0.28) * D, floorY - half[1], uniform(0.8, 1.15) * D},
                                   rotY(uniform(-50, 50)), half, texture(tint(), 0.03 * D)});
        }
        for (int i = 0; i < 3; ++i) {
            const double radius = uniform(0.04, 0.08) * D;
            scene.spheres.push_back(
                {{uniform(-0.28, 0.28) * D, floorY - radius, uniform(0.8, 1.15) * D}, radius, texture(tint(), 0.03 * D)});
        }
        const double halfLength = uniform(0.06, 0.1) * D;
        scene.cylinders.push_back({{uniform(-0.25, 0.25) * D, floorY - halfLength, uniform(0.85, 1.1) * D},
                                   rotX(90), uniform(0.03, 0.05) * D, halfLength, false, texture(tint(), 0.03 * D)});
        break;
    }

    case SceneKind::Fan: {
        // Thin slats radiating from a hub below the image, alternately nearer
        // and farther and twisted, with the wall visible through the gaps.
        scene.planes.push_back(plane({0, 0, 1.2 * D}, cv::Matx33d::eye(), texture(white, 0.04 * D)));
        const cv::Vec3d hub(0, 0.32 * D, 0.95 * D);
        for (int i = 0; i < 9; ++i) {
            const double angle = -48 + 12 * i;
            const cv::Matx33d axes = rotZ(angle) * rotY(i % 2 ? 20 : -15);
            cv::Vec3d centre = hub + rotZ(angle) * cv::Vec3d(0, -0.34 * D, 0);
            centre[2] += (i % 2 ? -0.05 : 0.02) * D;
            scene.boxes.push_back({centre, axes, {0.012 * D, 0.3 * D, 0.002 * D}, texture(white, 0.02 * D)});
        }
        break;
    }

    case SceneKind::Fingertip: {
        // A finger pad (paraboloid, 4 mm high) seen from the front with
        // ridges 0.45 mm apart and 0.05 mm deep in loops around a core.
        // Designed for D = 60 mm; other rigs get it scaled by D / 60. The
        // 0.05 mm grid has 9 samples per ridge (bilinear: 3% of the depth).
        const double scale = D / 60;
        const cv::Vec2d core(uniform(-2, 2) * scale, uniform(-3, 1) * scale);
        auto height = [core, scale](double a, double b) {
            const double u = a / (9 * scale), v = b / (14 * scale);
            const double dome = 4 * scale * (1 - u * u - v * v);
            const double r = std::hypot(a - core[0], b - core[1]);
            return dome + 0.025 * scale * std::cos(2 * M_PI * r / (0.45 * scale));
        };
        const double z = D + 2 * scale;
        const cv::Vec3f skin(0.45f, 0.55f, 0.75f);
        scene.heightFields.push_back(HeightField::sample({0, 0, z}, kFacingCamera,
                                                         {1.1 * halfWidth(z), 1.15 * halfHeight(z)}, 0.05 * scale, height,
                                                         texture(skin, 2 * scale)));
        break;
    }

    case SceneKind::Tube: {
        // The inside of a 9 mm radius tube from behind the lens to 1.5 D,
        // closed there, with a polyp on the wall.
        const double radius = 0.45 * D, length = 1.5 * D, behind = 0.25 * D;
        const cv::Vec3f mucosa(0.45f, 0.5f, 0.75f);
        scene.cylinders.push_back({rotX(4) * cv::Vec3d(0, 0, (length - behind) / 2), rotX(4), radius,
                                   (length + behind) / 2, true, texture(mucosa, 0.1 * D)});
        scene.planes.push_back(plane(rotX(4) * cv::Vec3d(0, 0, length), rotX(4), texture(mucosa, 0.1 * D),
                                     {radius * 1.1, radius * 1.1}));
        const double polypAngle = uniform(150, 210) * kDeg;
        const cv::Vec3d onWall(radius * std::cos(polypAngle), radius * std::sin(polypAngle), 0.9 * D);
        scene.spheres.push_back({rotX(4) * onWall, 0.13 * D, texture({0.4f, 0.45f, 0.8f}, 0.1 * D)});
        break;
    }
    }
    return scene;
}

}  // namespace stria::hal::sim
