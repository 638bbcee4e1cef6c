// Scene primitives: ray intersection, surface normals and textures.
#include "hal/sim/scene/scene.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace stria::hal::sim {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Ray in a primitive's local frame.
struct LocalRay {
    cv::Vec3d o;
    cv::Vec3d d;
};

LocalRay toLocal(const cv::Vec3d& centre, const cv::Matx33d& axes, const cv::Vec3d& origin, const cv::Vec3d& dir)
{
    return {axes.t() * (origin - centre), axes.t() * dir};
}

// Slab test of the ray against |p_i| <= half_i; [tNear, tFar] and the entry/exit axis.
bool slabs(const LocalRay& r, const cv::Vec3d& lo, const cv::Vec3d& hi, double& tNear, double& tFar, int& nearAxis,
           int& farAxis)
{
    tNear = -kInf;
    tFar = kInf;
    nearAxis = farAxis = 0;
    for (int i = 0; i < 3; ++i) {
        if (r.d[i] == 0) {
            if (r.o[i] < lo[i] || r.o[i] > hi[i]) return false;
            continue;
        }
        double t0 = (lo[i] - r.o[i]) / r.d[i];
        double t1 = (hi[i] - r.o[i]) / r.d[i];
        if (t0 > t1) std::swap(t0, t1);
        if (t0 > tNear) tNear = t0, nearAxis = i;
        if (t1 < tFar) tFar = t1, farAxis = i;
    }
    return tNear <= tFar;
}

double hitPlane(const PlaneSurface& s, const cv::Vec3d& o, const cv::Vec3d& d, double tMin, double tMax)
{
    const cv::Vec3d n(s.axes(0, 2), s.axes(1, 2), s.axes(2, 2));
    const double denom = n.dot(d);
    if (denom == 0) return kInf;
    const double t = n.dot(s.centre - o) / denom;
    if (!(t > tMin && t < tMax)) return kInf;
    const cv::Vec3d q = o + t * d - s.centre;
    const double a = q.dot(cv::Vec3d(s.axes(0, 0), s.axes(1, 0), s.axes(2, 0)));
    const double b = q.dot(cv::Vec3d(s.axes(0, 1), s.axes(1, 1), s.axes(2, 1)));
    return (std::abs(a) <= s.halfSize[0] && std::abs(b) <= s.halfSize[1]) ? t : kInf;
}

double hitSphere(const Sphere& s, const cv::Vec3d& o, const cv::Vec3d& d, double tMin, double tMax)
{
    const cv::Vec3d oc = o - s.centre;
    const double a = d.dot(d), b = oc.dot(d), c = oc.dot(oc) - s.radius * s.radius;
    const double disc = b * b - a * c;
    if (disc < 0) return kInf;
    const double root = std::sqrt(disc);
    // Numerically stable pair of roots.
    const double q = b > 0 ? -(b + root) : -(b - root);
    double t0 = q / a, t1 = q != 0 ? c / q : t0;
    if (t0 > t1) std::swap(t0, t1);
    if (t0 > tMin && t0 < tMax) return t0;
    if (t1 > tMin && t1 < tMax) return t1;
    return kInf;
}

double hitBox(const Box& s, const cv::Vec3d& o, const cv::Vec3d& d, double tMin, double tMax, int* axis)
{
    // Cheap rejection: the ray passes outside the bounding sphere.
    const cv::Vec3d oc = s.centre - o;
    const double along = oc.dot(d);
    if (oc.dot(oc) - along * along / d.dot(d) > s.halfSize.dot(s.halfSize)) return kInf;
    const LocalRay r = toLocal(s.centre, s.axes, o, d);
    double tNear, tFar;
    int nearAxis, farAxis;
    if (!slabs(r, -s.halfSize, s.halfSize, tNear, tFar, nearAxis, farAxis)) return kInf;
    if (tNear > tMin && tNear < tMax) {
        if (axis) *axis = nearAxis;
        return tNear;
    }
    if (tFar > tMin && tFar < tMax) {
        if (axis) *axis = farAxis;
        return tFar;
    }
    return kInf;
}

// part: 0 = wall, 1 = cap
double hitCylinder(const Cylinder& s, const cv::Vec3d& o, const cv::Vec3d& d, double tMin, double tMax, int* part)
{
    const LocalRay r = toLocal(s.centre, s.axes, o, d);
    double best = kInf;
    const double a = r.d[0] * r.d[0] + r.d[1] * r.d[1];
    const double b = r.o[0] * r.d[0] + r.o[1] * r.d[1];
    const double c = r.o[0] * r.o[0] + r.o[1] * r.o[1] - s.radius * s.radius;
    const double disc = b * b - a * c;
    if (a > 0 && disc >= 0) {
        const double root = std::sqrt(disc);
        for (double t : {(-b - root) / a, (-b + root) / a}) {
            if (t > tMin && t < tMax && std::abs(r.o[2] + t * r.d[2]) <= s.halfLength) {
                best = t;
                if (part) *part = 0;
                break;
            }
        }
    }
    if (!s.inside && r.d[2] != 0) {  // a solid cylinder has caps
        for (double z : {-s.halfLength, s.halfLength}) {
            const double t = (z - r.o[2]) / r.d[2];
            const double x = r.o[0] + t * r.d[0], y = r.o[1] + t * r.d[1];
            if (t > tMin && t < tMax && t < best && x * x + y * y <= s.radius * s.radius) {
                best = t;
                if (part) *part = 1;
            }
        }
    }
    return best;
}

// Amanatides-Woo walk over a 2-D grid of square cells of `size` (cell (i, j)
// covers [i*size, (i+1)*size) x [j*size, (j+1)*size)), restricted to cells
// [i0, i1) x [j0, j1), for the ray p + t*d with t in [t0, t1]. Calls
// visit(i, j, tEnter, tExit) in ray order until it returns true.
template <typename Visit>
bool walkGrid(double size, int i0, int i1, int j0, int j1, const cv::Vec2d& p, const cv::Vec2d& d, double t0,
              double t1, Visit&& visit)
{
    if (t0 > t1) return false;
    int i = std::clamp(static_cast<int>(std::floor((p[0] + t0 * d[0]) / size)), i0, i1 - 1);
    int j = std::clamp(static_cast<int>(std::floor((p[1] + t0 * d[1]) / size)), j0, j1 - 1);
    const int stepI = d[0] > 0 ? 1 : -1, stepJ = d[1] > 0 ? 1 : -1;
    double nextI = d[0] != 0 ? ((i + (d[0] > 0)) * size - p[0]) / d[0] : kInf;
    double nextJ = d[1] != 0 ? ((j + (d[1] > 0)) * size - p[1]) / d[1] : kInf;
    const double deltaI = d[0] != 0 ? size / std::abs(d[0]) : kInf;
    const double deltaJ = d[1] != 0 ? size / std::abs(d[1]) : kInf;
    double t = t0;
    for (;;) {
        const double tExit = std::min({nextI, nextJ, t1});
        if (tExit >= t && visit(i, j, t, tExit)) return true;
        if (tExit >= t1) return false;
        if (nextI < nextJ) {
            i += stepI;
            t = nextI;
            nextI += deltaI;
            if (i < i0 || i >= i1) return false;
        } else {
            j += stepJ;
            t = nextJ;
            nextJ += deltaJ;
            if (j < j0 || j >= j1) return false;
        }
    }
}

// The ray's height z(t) = oz + t*dz over [t0, t1] overlaps [lo, hi].
bool spansHeights(double oz, double dz, double t0, double t1, const cv::Vec2d& range)
{
    const double z0 = oz + t0 * dz, z1 = oz + t1 * dz;
    return std::min(z0, z1) <= range[1] && std::max(z0, z1) >= range[0];
}

// Smallest t in [lo, hi] with a*t^2 + b*t + c = 0, or infinity.
double firstRoot(double a, double b, double c, double lo, double hi)
{
    double r0 = kInf, r1 = kInf;
    if (std::abs(a) < 1e-14 * (std::abs(b) + std::abs(c))) {
        if (b != 0) r0 = -c / b;
    } else {
        const double disc = b * b - 4 * a * c;
        if (disc < 0) return kInf;
        const double q = -0.5 * (b + std::copysign(std::sqrt(disc), b));
        r0 = q / a;
        r1 = q != 0 ? c / q : r0;
        if (r0 > r1) std::swap(r0, r1);
    }
    if (r0 >= lo && r0 <= hi) return r0;
    if (r1 >= lo && r1 <= hi) return r1;
    return kInf;
}

double hitHeightField(const HeightField& s, const cv::Vec3d& o, const cv::Vec3d& d, double tMin, double tMax)
{
    const LocalRay r = toLocal(s.centre, s.axes, o, d);
    double tNear, tFar;
    int nearAxis, farAxis;
    const cv::Vec3d lo(-s.halfSize[0], -s.halfSize[1], s.heightMin), hi(s.halfSize[0], s.halfSize[1], s.heightMax);
    if (!slabs(r, lo, hi, tNear, tFar, nearAxis, farAxis)) return kInf;
    const double t0 = std::max(tNear, tMin), t1 = std::min(tFar, tMax);
    if (t0 > t1) return kInf;
    // Grid coordinates in mm from the grid's corner.
    const cv::Vec2d p(r.o[0] + s.halfSize[0], r.o[1] + s.halfSize[1]), dir(r.d[0], r.d[1]);
    const int cellsX = s.heights.cols - 1, cellsY = s.heights.rows - 1;
    const double h = s.spacingMm;
    double best = kInf;
    auto visitCell = [&](int i, int j, double c0, double c1) {
        if (!spansHeights(r.o[2], r.d[2], c0, c1, s.cellRange.at<cv::Vec2d>(j, i))) return false;
        const double* row0 = s.heights.ptr<double>(j);
        const double* row1 = s.heights.ptr<double>(j + 1);
        const double h00 = row0[i], h10 = row0[i + 1], h01 = row1[i], h11 = row1[i + 1];
        const double u0 = p[0] / h - i, v0 = p[1] / h - j, du = dir[0] / h, dv = dir[1] / h;
        const double ea = h10 - h00, eb = h01 - h00, e = h00 - h10 - h01 + h11;
        // z(t) - bilinear(u(t), v(t)) as a quadratic in t.
        const double a = -e * du * dv;
        const double b = r.d[2] - (ea * du + eb * dv + e * (u0 * dv + v0 * du));
        const double c = r.o[2] - (h00 + ea * u0 + eb * v0 + e * u0 * v0);
        best = firstRoot(a, b, c, std::max(c0, tMin), std::min(c1, tMax));
        return best < kInf;
    };
    const int blocksX = s.blockRange.cols, blocksY = s.blockRange.rows;
    const double blockSize = HeightField::kBlock * h;
    walkGrid(blockSize, 0, blocksX, 0, blocksY, p, dir, t0, t1, [&](int bi, int bj, double b0, double b1) {
        if (!spansHeights(r.o[2], r.d[2], b0, b1, s.blockRange.at<cv::Vec2d>(bj, bi))) return false;
        return walkGrid(h, bi * HeightField::kBlock, std::min(cellsX, (bi + 1) * HeightField::kBlock),
                        bj * HeightField::kBlock, std::min(cellsY, (bj + 1) * HeightField::kBlock), p, dir, b0, b1,
                        visitCell);
    });
    return best;
}

cv::Vec3d axis(const cv::Matx33d& axes, int i) { return {axes(0, i), axes(1, i), axes(2, i)}; }

cv::Vec3f bilinearWrap(const cv::Mat& image, double x, double y)
{
    const double fx = std::floor(x), fy = std::floor(y);
    const double u = x - fx, v = y - fy;
    auto wrap = [](long i, int n) { return static_cast<int>(((i % n) + n) % n); };
    const int x0 = wrap(static_cast<long>(fx), image.cols), x1 = wrap(static_cast<long>(fx) + 1, image.cols);
    const int y0 = wrap(static_cast<long>(fy), image.rows), y1 = wrap(static_cast<long>(fy) + 1, image.rows);
    const auto* r0 = image.ptr<cv::Vec3f>(y0);
    const auto* r1 = image.ptr<cv::Vec3f>(y1);
    const cv::Vec3f top = r0[x0] * static_cast<float>(1 - u) + r0[x1] * static_cast<float>(u);
    const cv::Vec3f bottom = r1[x0] * static_cast<float>(1 - u) + r1[x1] * static_cast<float>(u);
    return top * static_cast<float>(1 - v) + bottom * static_cast<float>(v);
}

}  // namespace

const char* sceneName(SceneKind kind)
{
    switch (kind) {
    case SceneKind::TiltedPlane: return "plane";
    case SceneKind::SphereBeforeWall: return "sphere";
    case SceneKind::TexturedRelief: return "relief";
    case SceneKind::Clutter: return "clutter";
    case SceneKind::Fan: return "fan";
    case SceneKind::Fingertip: return "fingertip";
    case SceneKind::Tube: return "tube";
    }
    return "?";
}

std::optional<SceneKind> sceneFromName(std::string_view name)
{
    for (SceneKind k : {SceneKind::TiltedPlane, SceneKind::SphereBeforeWall, SceneKind::TexturedRelief,
                        SceneKind::Clutter, SceneKind::Fan, SceneKind::Fingertip, SceneKind::Tube})
        if (name == sceneName(k)) return k;
    return std::nullopt;
}

const char* albedoName(Albedo albedo)
{
    switch (albedo) {
    case Albedo::Uniform: return "uniform";
    case Albedo::Checker: return "checker";
    case Albedo::Coloured: return "coloured";
    case Albedo::Photo: return "photo";
    }
    return "?";
}

std::optional<Albedo> albedoFromName(std::string_view name)
{
    for (Albedo a : {Albedo::Uniform, Albedo::Checker, Albedo::Coloured, Albedo::Photo})
        if (name == albedoName(a)) return a;
    return std::nullopt;
}

Albedo defaultAlbedo(SceneKind kind) { return kind == SceneKind::TexturedRelief ? Albedo::Photo : Albedo::Uniform; }

cv::Vec3f Texture::reflectance(const cv::Vec2d& uvMm) const
{
    switch (kind) {
    case Albedo::Uniform: return colour;
    case Albedo::Checker: {
        const auto parity = static_cast<long>(std::floor(uvMm[0] / cellMm)) + static_cast<long>(std::floor(uvMm[1] / cellMm));
        return (parity & 1) ? colour2 : colour;
    }
    case Albedo::Coloured:
    case Albedo::Photo: return bilinearWrap(image, uvMm[0] / cellMm, uvMm[1] / cellMm);
    }
    return colour;
}

HeightField HeightField::sample(const cv::Vec3d& centre, const cv::Matx33d& axes, const cv::Vec2d& halfSize,
                                double spacingMm, const std::function<double(double, double)>& height,
                                const Texture& texture)
{
    HeightField f;
    f.centre = centre;
    f.axes = axes;
    f.spacingMm = spacingMm;
    const int cols = static_cast<int>(std::ceil(2 * halfSize[0] / spacingMm)) + 1;
    const int rows = static_cast<int>(std::ceil(2 * halfSize[1] / spacingMm)) + 1;
    f.halfSize = {(cols - 1) * spacingMm / 2, (rows - 1) * spacingMm / 2};
    f.heights.create(rows, cols, CV_64FC1);
    for (int j = 0; j < rows; ++j) {
        auto* row = f.heights.ptr<double>(j);
        for (int i = 0; i < cols; ++i) row[i] = height(-f.halfSize[0] + i * spacingMm, -f.halfSize[1] + j * spacingMm);
    }
    cv::minMaxLoc(f.heights, &f.heightMin, &f.heightMax);
    // A bilinear cell lies within the range of its four corner heights.
    f.cellRange.create(rows - 1, cols - 1, CV_64FC2);
    const int blocksX = (cols - 2) / kBlock + 1, blocksY = (rows - 2) / kBlock + 1;
    f.blockRange = cv::Mat(blocksY, blocksX, CV_64FC2, cv::Scalar(std::numeric_limits<double>::infinity(),
                                                                  -std::numeric_limits<double>::infinity()));
    for (int j = 0; j + 1 < rows; ++j)
        for (int i = 0; i + 1 < cols; ++i) {
            const double c[4] = {f.heights.at<double>(j, i), f.heights.at<double>(j, i + 1),
                                 f.heights.at<double>(j + 1, i), f.heights.at<double>(j + 1, i + 1)};
            const cv::Vec2d range(*std::min_element(c, c + 4), *std::max_element(c, c + 4));
            f.cellRange.at<cv::Vec2d>(j, i) = range;
            cv::Vec2d& block = f.blockRange.at<cv::Vec2d>(j / kBlock, i / kBlock);
            block = {std::min(block[0], range[0]), std::max(block[1], range[1])};
        }
    f.texture = texture;
    return f;
}

double HeightField::heightAt(double a, double b) const
{
    const double x = (a + halfSize[0]) / spacingMm, y = (b + halfSize[1]) / spacingMm;
    const int i = std::clamp(static_cast<int>(x), 0, heights.cols - 2);
    const int j = std::clamp(static_cast<int>(y), 0, heights.rows - 2);
    const double u = x - i, v = y - j;
    const double* r0 = heights.ptr<double>(j);
    const double* r1 = heights.ptr<double>(j + 1);
    return (r0[i] * (1 - u) + r0[i + 1] * u) * (1 - v) + (r1[i] * (1 - u) + r1[i + 1] * u) * v;
}

std::optional<Hit> Scene::intersect(const cv::Vec3d& origin, const cv::Vec3d& direction, double tMin,
                                    double tMax) const
{
    enum class Kind { None, Plane, Sphere, Box, Cylinder, HeightField } kind = Kind::None;
    std::size_t index = 0;
    int part = 0;
    double best = tMax;
    auto consider = [&](double t, Kind k, std::size_t i) {
        if (t < best) best = t, kind = k, index = i;
    };
    for (std::size_t i = 0; i < planes.size(); ++i) consider(hitPlane(planes[i], origin, direction, tMin, best), Kind::Plane, i);
    for (std::size_t i = 0; i < spheres.size(); ++i)
        consider(hitSphere(spheres[i], origin, direction, tMin, best), Kind::Sphere, i);
    for (std::size_t i = 0; i < boxes.size(); ++i) {
        int a = 0;
        const double t = hitBox(boxes[i], origin, direction, tMin, best, &a);
        if (t < best) part = a;
        consider(t, Kind::Box, i);
    }
    for (std::size_t i = 0; i < cylinders.size(); ++i) {
        int p = 0;
        const double t = hitCylinder(cylinders[i], origin, direction, tMin, best, &p);
        if (t < best) part = p;
        consider(t, Kind::Cylinder, i);
    }
    for (std::size_t i = 0; i < heightFields.size(); ++i)
        consider(hitHeightField(heightFields[i], origin, direction, tMin, best), Kind::HeightField, i);
    if (kind == Kind::None) return std::nullopt;

    Hit hit;
    hit.t = best;
    hit.point = origin + best * direction;
    cv::Vec2d uv;
    const Texture* texture = nullptr;
    switch (kind) {
    case Kind::Plane: {
        const PlaneSurface& s = planes[index];
        const cv::Vec3d q = hit.point - s.centre;
        hit.normal = axis(s.axes, 2);
        uv = {q.dot(axis(s.axes, 0)), q.dot(axis(s.axes, 1))};
        texture = &s.texture;
        break;
    }
    case Kind::Sphere: {
        const Sphere& s = spheres[index];
        const cv::Vec3d q = hit.point - s.centre;
        hit.normal = q / s.radius;
        uv = {q[0], q[1]};  // projected along the camera axis, like a decal
        texture = &s.texture;
        break;
    }
    case Kind::Box: {
        const Box& s = boxes[index];
        const cv::Vec3d q = s.axes.t() * (hit.point - s.centre);
        hit.normal = axis(s.axes, part);
        uv = {q[(part + 1) % 3], q[(part + 2) % 3]};
        texture = &s.texture;
        break;
    }
    case Kind::Cylinder: {
        const Cylinder& s = cylinders[index];
        const cv::Vec3d q = s.axes.t() * (hit.point - s.centre);
        hit.normal = part == 0 ? s.axes * cv::Vec3d(q[0], q[1], 0) * (1.0 / s.radius) : axis(s.axes, 2);
        uv = part == 0 ? cv::Vec2d(s.radius * std::atan2(q[1], q[0]), q[2]) : cv::Vec2d(q[0], q[1]);
        texture = &s.texture;
        break;
    }
    case Kind::HeightField: {
        const HeightField& s = heightFields[index];
        const cv::Vec3d q = s.axes.t() * (hit.point - s.centre);
        // Shading normal: the grid's central-difference slopes at the four
        // corners of the cell, blended bilinearly, so shading is continuous
        // across cells (the facets' own normals would print the grid).
        const double x = (std::clamp(q[0], -s.halfSize[0], s.halfSize[0]) + s.halfSize[0]) / s.spacingMm;
        const double y = (std::clamp(q[1], -s.halfSize[1], s.halfSize[1]) + s.halfSize[1]) / s.spacingMm;
        const int i = std::clamp(static_cast<int>(x), 0, s.heights.cols - 2);
        const int j = std::clamp(static_cast<int>(y), 0, s.heights.rows - 2);
        const double u = x - i, v = y - j;
        auto slope = [&](int ci, int cj) {
            const int il = std::max(ci - 1, 0), ir = std::min(ci + 1, s.heights.cols - 1);
            const int jl = std::max(cj - 1, 0), jr = std::min(cj + 1, s.heights.rows - 1);
            return cv::Vec2d((s.heights.at<double>(cj, ir) - s.heights.at<double>(cj, il)) / ((ir - il) * s.spacingMm),
                             (s.heights.at<double>(jr, ci) - s.heights.at<double>(jl, ci)) / ((jr - jl) * s.spacingMm));
        };
        const cv::Vec2d g = (slope(i, j) * (1 - u) + slope(i + 1, j) * u) * (1 - v) +
                            (slope(i, j + 1) * (1 - u) + slope(i + 1, j + 1) * u) * v;
        const double da = g[0], db = g[1];
        hit.normal = cv::normalize(s.axes * cv::Vec3d(-da, -db, 1));
        uv = {q[0], q[1]};
        texture = &s.texture;
        break;
    }
    case Kind::None: break;
    }
    if (hit.normal.dot(direction) > 0) hit.normal = -hit.normal;
    hit.reflectance = texture->reflectance(uv);
    return hit;
}

bool Scene::blocked(const cv::Vec3d& from, const cv::Vec3d& to) const
{
    const cv::Vec3d d = to - from;
    constexpr double tMin = 1e-9, tMax = 1 - 1e-9;
    for (const auto& s : planes)
        if (hitPlane(s, from, d, tMin, tMax) < kInf) return true;
    for (const auto& s : spheres)
        if (hitSphere(s, from, d, tMin, tMax) < kInf) return true;
    for (const auto& s : boxes)
        if (hitBox(s, from, d, tMin, tMax, nullptr) < kInf) return true;
    for (const auto& s : cylinders)
        if (hitCylinder(s, from, d, tMin, tMax, nullptr) < kInf) return true;
    for (const auto& s : heightFields)
        if (hitHeightField(s, from, d, tMin, tMax) < kInf) return true;
    return false;
}

}  // namespace stria::hal::sim
