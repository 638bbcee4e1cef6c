// The renderer: per camera pixel, n x n supersampled ray casts lit through
// the projector's (defocused) slide, then camera blur, noise, quantisation and
// optionally a Bayer mosaic. Ground truth is taken at the pixel centre.
#include "hal/sim/scene/scene.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace stria::hal::sim {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// Blurred slide table: transmittance of the slide for blur sigmas
// 0, kSigmaStep, ..., kMaxSigma (projector px), sampled every 1/kSubsteps
// projector px across the projector image. Four values per sample: the
// pattern-area mask m and the red, green and blue "on" indicators b_c; a
// channel transmits off * m + (1 - off) * b_c, so contrast needs no new table.
constexpr double kSigmaStep = 0.25;
constexpr double kMaxSigma = 8.0;
constexpr int kSigmaLevels = static_cast<int>(kMaxSigma / kSigmaStep) + 1;
constexpr int kSubsteps = 8;

int slideSamples(const pipeline::RigModel& rig) { return rig.projector().width * kSubsteps + 1; }

// Gaussian cumulative distribution; a step at sigma = 0.
double blurredStep(double x, double sigma)
{
    if (sigma <= 0) return x > 0 ? 1.0 : (x < 0 ? 0.0 : 0.5);
    return 0.5 * std::erfc(-x / (sigma * M_SQRT2));
}

std::vector<float> buildSlideTable(const pipeline::RigModel& rig, const pipeline::StripePattern& pattern)
{
    const int samples = slideSamples(rig);
    const int w = pattern.stripeWidth();
    std::vector<float> table(static_cast<std::size_t>(kSigmaLevels) * samples * 4);
    for (int level = 0; level < kSigmaLevels; ++level) {
        const double sigma = level * kSigmaStep;
        const double reach = 6 * sigma + 1;
        for (int k = 0; k < samples; ++k) {
            const double x = -0.5 + static_cast<double>(k) / kSubsteps;
            double v[4] = {0, 0, 0, 0};
            const int first = std::max(0, static_cast<int>(std::floor((x - reach + 0.5) / w)));
            const int last = std::min(pattern.stripeCount() - 1, static_cast<int>(std::floor((x + reach + 0.5) / w)));
            for (int i = first; i <= last; ++i) {
                const double left = i * w - 0.5;
                const double inside = blurredStep(x - left, sigma) - blurredStep(x - left - w, sigma);
                v[0] += inside;
                for (int ch = 0; ch < 3; ++ch) v[1 + ch] += pipeline::colorChannel(pattern.color(i), ch) * inside;
            }
            float* out = &table[(static_cast<std::size_t>(level) * samples + k) * 4];
            for (int c = 0; c < 4; ++c) out[c] = static_cast<float>(v[c]);
        }
    }
    return table;
}

// Newton's method with the analytic Jacobian of OpenCV's distortion model,
// warm-started from the neighbouring pixel's solution.
cv::Vec2d undistort(const pipeline::LensModel& lens, const cv::Vec2d& pixel, cv::Vec2d x)
{
    const double fx = lens.K(0, 0), fy = lens.K(1, 1), cx = lens.K(0, 2), cy = lens.K(1, 2), skew = lens.K(0, 1);
    const double yd = (pixel[1] - cy) / fy;
    const cv::Vec2d target((pixel[0] - cx - skew * yd) / fx, yd);
    const double k1 = lens.distortion[0], k2 = lens.distortion[1], p1 = lens.distortion[2], p2 = lens.distortion[3],
                 k3 = lens.distortion[4];
    for (int iter = 0; iter < 30; ++iter) {
        const cv::Vec2d f = lens.distortNormalized(x) - target;
        if (std::abs(f[0]) + std::abs(f[1]) < 1e-15) break;
        const double r2 = x[0] * x[0] + x[1] * x[1];
        const double radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3));
        const double dRadial = k1 + r2 * (2 * k2 + 3 * k3 * r2);  // d radial / d r2
        const double a = radial + 2 * x[0] * x[0] * dRadial + 2 * p1 * x[1] + 6 * p2 * x[0];
        const double b = 2 * x[0] * x[1] * dRadial + 2 * p1 * x[0] + 2 * p2 * x[1];
        const double d = radial + 2 * x[1] * x[1] * dRadial + 6 * p1 * x[1] + 2 * p2 * x[0];
        const double det = a * d - b * b;
        if (std::abs(det) < 1e-12) break;
        x[0] -= (d * f[0] - b * f[1]) / det;
        x[1] -= (a * f[1] - b * f[0]) / det;
    }
    return x;
}

Status validateSettings(const RenderSettings& s)
{
    auto bad = [](const char* name, double value, const char* rule) {
        return Status::error(std::string("render setting ") + name + " is " + std::to_string(value) + ": " + rule);
    };
    if (!(s.contrast >= 0 && s.contrast <= 1)) return bad("contrast", s.contrast, "it must be in [0, 1]");
    if (!(s.ambient >= 0 && s.ambient < 1e3)) return bad("ambient", s.ambient, "it must be >= 0");
    if (!(s.exposure >= 0 && s.exposure < 1e3)) return bad("exposure", s.exposure, "it must be >= 0");
    if (!(s.noiseSigma >= 0 && s.noiseSigma < 1e4)) return bad("noiseSigma", s.noiseSigma, "it must be >= 0");
    if (!(s.shotNoise >= 0 && s.shotNoise < 1e4)) return bad("shotNoise", s.shotNoise, "it must be >= 0");
    if (!(s.readNoise >= 0 && s.readNoise < 1e4)) return bad("readNoise", s.readNoise, "it must be >= 0");
    if (s.samplesPerPixel < 1 || s.samplesPerPixel > 64)
        return bad("samplesPerPixel", s.samplesPerPixel, "it must be between 1 and 64");
    if (!(s.projectorFocusMm >= 0 && std::isfinite(s.projectorFocusMm)))
        return bad("projectorFocusMm", s.projectorFocusMm, "it must be >= 0 (0 = the working distance)");
    if (!(s.projectorBlurPx >= 0 && s.projectorBlurPx <= kMaxSigma))
        return bad("projectorBlurPx", s.projectorBlurPx, "it must be in [0, 8]");
    if (!(s.projectorDefocusPx >= 0 && s.projectorDefocusPx < 1e3))
        return bad("projectorDefocusPx", s.projectorDefocusPx, "it must be >= 0");
    if (!(s.cameraBlurPx >= 0 && s.cameraBlurPx <= 20)) return bad("cameraBlurPx", s.cameraBlurPx, "it must be in [0, 20]");
    for (int i = 0; i < 9; ++i)
        if (!std::isfinite(s.crosstalk.val[i])) return Status::error("render setting crosstalk contains NaN or infinity");
    return Status::ok();
}

// Depth along the camera's axis where the projector's axis passes closest.
double convergenceDistance(const pipeline::RigModel& rig)
{
    const cv::Vec3d centre = rig.projectorCentreInCamera();
    const cv::Vec3d axis = rig.R().t() * cv::Vec3d(0, 0, 1);
    // Closest points of (0, 0, s) and centre + u * axis.
    const double a = axis[2], denom = 1 - a * a;
    if (denom < 1e-12) return 1000;
    const double u = (a * centre[2] - centre.dot(axis)) / denom;
    const double s = centre[2] + u * a;
    return s > 0 ? s : 1000;
}

}  // namespace

SceneRenderer::SceneRenderer(const pipeline::RigModel& rig, const pipeline::StripePattern& pattern)
    : SceneRenderer(rig, pattern, convergenceDistance(rig))
{
}

SceneRenderer::SceneRenderer(const pipeline::RigModel& rig, const pipeline::StripePattern& pattern,
                             double workingDistanceMm)
    : rig_(rig), pattern_(pattern), workingDistanceMm_(workingDistanceMm)
{
    const pipeline::LensModel& camera = rig_.camera();
    rays_.create(camera.height, camera.width, CV_64FC2);
    for (int y = 0; y < camera.height; ++y) {
        auto* row = rays_.ptr<cv::Vec2d>(y);
        cv::Vec2d guess = y > 0 ? rays_.at<cv::Vec2d>(y - 1, 0) : cv::Vec2d(0, 0);
        for (int x = 0; x < camera.width; ++x) guess = row[x] = undistort(camera, {double(x), double(y)}, guess);
    }
    slide_ = buildSlideTable(rig_, pattern_);
}

Status SceneRenderer::render(const Scene& scene, const RenderSettings& settings, Rendering& out) const
{
    if (Status s = validateSettings(settings); !s) return s;
    const pipeline::LensModel& camera = rig_.camera();
    const pipeline::LensModel& projector = rig_.projector();
    const int width = camera.width, height = camera.height;
    out.image.create(height, width, CV_8UC3);
    out.depth.create(height, width, CV_32FC1);
    out.projectorColumn.create(height, width, CV_32FC1);
    out.lit.create(height, width, CV_8UC1);
    out.radiance.create(height, width, CV_32FC3);

    const cv::Vec3d projectorCentre = rig_.projectorCentreInCamera();
    const cv::Vec3d aimPoint(0, 0, workingDistanceMm_);
    // A white surface facing the projector at the aim point receives 1.0.
    const double referenceDistance2 = cv::norm(aimPoint - projectorCentre, cv::NORM_L2SQR);
    const double focus = settings.projectorFocusMm > 0 ? settings.projectorFocusMm : rig_.cameraToProjector(aimPoint)[2];
    const double off = 1 - settings.contrast;
    const int samples = slideSamples(rig_);
    const double xMax = projector.width - 0.5, yMax = projector.height - 0.5;

    // Light from the projector reaching `hit` (R, G, B, fraction of white);
    // not lit when the projector cannot see the point. `shadow`: 0 = cast a
    // shadow ray, 1 = known to be in shadow, -1 = known to be unshadowed.
    struct Light {
        bool lit = false;
        double projectorX = 0;
        cv::Vec3d rgb{0, 0, 0};
    };
    auto illuminate = [&](const Hit& hit, int shadow) {
        Light light;
        if (!settings.projectorOn || shadow > 0) return light;
        const cv::Vec3d pp = rig_.cameraToProjector(hit.point);
        if (pp[2] <= 0) return light;
        const cv::Vec2d uv = projector.project(pp);
        if (!(uv[0] >= -0.5 && uv[0] <= xMax && uv[1] >= -0.5 && uv[1] <= yMax)) return light;
        const cv::Vec3d toProjector = projectorCentre - hit.point;
        const double distance2 = toProjector.dot(toProjector);
        const double cosine = hit.normal.dot(toProjector) / std::sqrt(distance2);
        if (cosine <= 0) return light;
        const double offset = 1e-7 * std::sqrt(hit.point.dot(hit.point)) + 1e-9;
        if (shadow == 0 && scene.blocked(hit.point + hit.normal * offset, projectorCentre)) return light;
        light.lit = true;
        light.projectorX = uv[0];

        const double sigma = std::min(kMaxSigma, settings.projectorBlurPx +
                                                     settings.projectorDefocusPx * std::abs(focus / pp[2] - 1));
        const double levelPos = sigma / kSigmaStep;
        const int level = std::min(static_cast<int>(levelPos), kSigmaLevels - 2);
        const double fl = levelPos - level;
        const double samplePos = (uv[0] + 0.5) * kSubsteps;
        const int k = std::min(static_cast<int>(samplePos), samples - 2);
        const double fk = samplePos - k;
        const float* a = &slide_[(static_cast<std::size_t>(level) * samples + k) * 4];
        const float* b = a + static_cast<std::size_t>(samples) * 4;
        double t[4];
        for (int c = 0; c < 4; ++c)
            t[c] = (1 - fl) * ((1 - fk) * a[c] + fk * a[c + 4]) + fl * ((1 - fk) * b[c] + fk * b[c + 4]);
        const double irradiance = cosine * referenceDistance2 / distance2;
        for (int c = 0; c < 3; ++c) light.rgb[c] = irradiance * (off * t[0] + (1 - off) * t[1 + c]);
        return light;
    };

    // Pass 1: ground truth at the pixel centres.
    const cv::Vec3d origin(0, 0, 0);
    for (int y = 0; y < height; ++y) {
        const auto* rays = rays_.ptr<cv::Vec2d>(y);
        auto* depth = out.depth.ptr<float>(y);
        auto* column = out.projectorColumn.ptr<float>(y);
        auto* lit = out.lit.ptr<std::uint8_t>(y);
        for (int x = 0; x < width; ++x) {
            const auto hit = scene.intersect(origin, cv::Vec3d(rays[x][0], rays[x][1], 1.0));
            depth[x] = kNaN;
            column[x] = kNaN;
            lit[x] = 0;
            if (!hit) continue;
            depth[x] = static_cast<float>(hit->point[2]);
            const Light light = illuminate(*hit, 0);
            if (light.lit) {
                lit[x] = 1;
                column[x] = static_cast<float>(light.projectorX);
            }
        }
    }

    // Pass 2: supersampled shading. Sub-pixel rays come from the local
    // Jacobian of the (undistorted) ray map. Shadow rays are cast only where
    // the lit state of the 3 x 3 pixel centres around is mixed; elsewhere the
    // samples share it (a shadow smaller than a pixel between centres is lost).
    const int n = std::max(1, static_cast<int>(std::lround(std::sqrt(settings.samplesPerPixel))));
    const double gain = 255.0 * settings.exposure / (n * n);
    for (int y = 0; y < height; ++y) {
        const int yUp = std::max(0, y - 1), yDown = std::min(height - 1, y + 1);
        const auto* rays = rays_.ptr<cv::Vec2d>(y);
        const auto* raysUp = rays_.ptr<cv::Vec2d>(yUp);
        const auto* raysDown = rays_.ptr<cv::Vec2d>(yDown);
        const double dyScale = 1.0 / std::max(1, yDown - yUp);
        const std::uint8_t* litRows[3] = {out.lit.ptr<std::uint8_t>(yUp), out.lit.ptr<std::uint8_t>(y),
                                          out.lit.ptr<std::uint8_t>(yDown)};
        auto* radiance = out.radiance.ptr<cv::Vec3f>(y);
        for (int x = 0; x < width; ++x) {
            const int xl = std::max(0, x - 1), xr = std::min(width - 1, x + 1);
            int litCount = 0;
            for (const std::uint8_t* row : litRows) litCount += row[xl] + row[x] + row[xr];
            const int shadow = litCount == 9 ? -1 : (litCount == 0 ? 1 : 0);
            const cv::Vec2d dRdx = (rays[xr] - rays[xl]) * (1.0 / std::max(1, xr - xl));
            const cv::Vec2d dRdy = (raysDown[x] - raysUp[x]) * dyScale;
            cv::Vec3d sum(0, 0, 0);  // R G B
            for (int j = 0; j < n; ++j) {
                for (int i = 0; i < n; ++i) {
                    const double dx = (i + 0.5) / n - 0.5, dy = (j + 0.5) / n - 0.5;
                    const cv::Vec2d r = rays[x] + dRdx * dx + dRdy * dy;
                    const auto hit = scene.intersect(origin, cv::Vec3d(r[0], r[1], 1.0));
                    if (!hit) continue;
                    const Light light = illuminate(*hit, shadow);
                    for (int c = 0; c < 3; ++c)
                        sum[c] += hit->reflectance[2 - c] * (light.rgb[c] + settings.ambient);
                }
            }
            const cv::Vec3d sensor = settings.crosstalk * sum * gain;
            radiance[x] = cv::Vec3f(static_cast<float>(sensor[2]), static_cast<float>(sensor[1]),
                                    static_cast<float>(sensor[0]));
        }
    }

    if (settings.cameraBlurPx > 0)
        cv::GaussianBlur(out.radiance, out.radiance, cv::Size(0, 0), settings.cameraBlurPx, settings.cameraBlurPx,
                         cv::BORDER_REPLICATE);

    // Noise and 8-bit quantisation, per sensor sample.
    cv::RNG rng(settings.seed);
    const double constantVariance = settings.noiseSigma * settings.noiseSigma + settings.readNoise * settings.readNoise;
    const bool noisy = constantVariance > 0 || settings.shotNoise > 0;
    auto digitise = [&](float signal) {
        double v = signal;
        if (noisy) {
            const double variance = constantVariance + settings.shotNoise * std::max(0.0, v);
            v += rng.gaussian(std::sqrt(variance));
        }
        return static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L));
    };
    if (settings.bayer) {
        // RGGB: R at even rows and columns, B at odd rows and columns.
        out.raw.create(height, width, CV_8UC1);
        for (int y = 0; y < height; ++y) {
            const auto* radiance = out.radiance.ptr<cv::Vec3f>(y);
            auto* raw = out.raw.ptr<std::uint8_t>(y);
            for (int x = 0; x < width; ++x) {
                const int bgrChannel = (y % 2 == 0) ? (x % 2 == 0 ? 2 : 1) : (x % 2 == 0 ? 1 : 0);
                raw[x] = digitise(radiance[x][bgrChannel]);
            }
        }
        // OpenCV names Bayer layouts after the second row's second and third
        // pixels: an RGGB sensor is its "BG" pattern.
        cv::cvtColor(out.raw, out.image, cv::COLOR_BayerBG2BGR);
    } else {
        for (int y = 0; y < height; ++y) {
            const auto* radiance = out.radiance.ptr<cv::Vec3f>(y);
            auto* image = out.image.ptr<cv::Vec3b>(y);
            for (int x = 0; x < width; ++x)
                for (int c = 0; c < 3; ++c) image[x][c] = digitise(radiance[x][c]);
        }
    }
    return Status::ok();
}

int idealEdgeCrossings(const Rendering& rendering, const pipeline::StripePattern& pattern)
{
    const int w = pattern.stripeWidth();
    const int edges = pattern.edgeCount();
    int count = 0;
    for (int y = 0; y < rendering.depth.rows; ++y) {
        const auto* depth = rendering.depth.ptr<float>(y);
        const auto* column = rendering.projectorColumn.ptr<float>(y);
        const auto* lit = rendering.lit.ptr<std::uint8_t>(y);
        for (int x = 0; x + 1 < rendering.depth.cols; ++x) {
            if (!lit[x] || !lit[x + 1]) continue;
            const double z0 = depth[x], z1 = depth[x + 1];
            if (!(std::abs(z0 - z1) <= 0.02 * 0.5 * (z0 + z1))) continue;
            const double lo = std::min(column[x], column[x + 1]), hi = std::max(column[x], column[x + 1]);
            // Edges k with lo < (k + 1) * w - 0.5 <= hi.
            const int first = std::max(0, static_cast<int>(std::floor((lo + 0.5) / w - 1)) + 1);
            const int last = std::min(edges - 1, static_cast<int>(std::floor((hi + 0.5) / w - 1)));
            if (last >= first) count += last - first + 1;
        }
    }
    return count;
}

}  // namespace stria::hal::sim
