#include "pipeline/rig.hpp"

#include <Eigen/Eigenvalues>

#include <cmath>
#include <string>

namespace stria::pipeline {
namespace {

template <int M, int N>
bool allFinite(const cv::Matx<double, M, N>& m)
{
    for (int i = 0; i < M * N; ++i)
        if (!std::isfinite(m.val[i])) return false;
    return true;
}

}  // namespace

cv::Vec2d LensModel::distortNormalized(const cv::Vec2d& xn) const
{
    const double k1 = distortion[0], k2 = distortion[1], p1 = distortion[2], p2 = distortion[3], k3 = distortion[4];
    const double x = xn[0], y = xn[1];
    const double r2 = x * x + y * y;
    const double radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3));
    return {x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x), y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y};
}

cv::Vec2d LensModel::undistortPixel(const cv::Vec2d& pixel) const
{
    const double fx = K(0, 0), fy = K(1, 1), cx = K(0, 2), cy = K(1, 2), skew = K(0, 1);
    const double yd = (pixel[1] - cy) / fy;
    const double xd = (pixel[0] - cx - skew * yd) / fx;
    const cv::Vec2d distorted(xd, yd);
    if (distortion == cv::Vec<double, 5>::all(0)) return distorted;
    // Newton iterations on distort(x) = distorted, starting from the
    // distorted point; the Jacobian is taken numerically (well-conditioned
    // for real lenses). Converges to ~1e-15 in a handful of steps.
    cv::Vec2d x = distorted;
    for (int iter = 0; iter < 50; ++iter) {
        const cv::Vec2d f = distortNormalized(x) - distorted;
        if (std::abs(f[0]) + std::abs(f[1]) < 1e-15) break;
        const double h = 1e-7;
        const cv::Vec2d dx = (distortNormalized(x + cv::Vec2d(h, 0)) - distortNormalized(x - cv::Vec2d(h, 0))) / (2 * h);
        const cv::Vec2d dy = (distortNormalized(x + cv::Vec2d(0, h)) - distortNormalized(x - cv::Vec2d(0, h))) / (2 * h);
        const double det = dx[0] * dy[1] - dy[0] * dx[1];
        if (std::abs(det) < 1e-12) break;
        x[0] -= (dy[1] * f[0] - dy[0] * f[1]) / det;
        x[1] -= (-dx[1] * f[0] + dx[0] * f[1]) / det;
    }
    return x;
}

cv::Vec3d LensModel::rayThroughPixel(const cv::Vec2d& pixel) const
{
    const cv::Vec2d xn = undistortPixel(pixel);
    return {xn[0], xn[1], 1.0};
}

cv::Vec2d LensModel::project(const cv::Vec3d& point) const
{
    const cv::Vec2d xd = distortNormalized({point[0] / point[2], point[1] / point[2]});
    return {K(0, 0) * xd[0] + K(0, 1) * xd[1] + K(0, 2), K(1, 1) * xd[1] + K(1, 2)};
}

Status LensModel::validate(const char* prefix) const
{
    const std::string p(prefix);
    if (width <= 0 || height <= 0)
        return Status::error(p + "_width/" + p + "_height are " + std::to_string(width) + "x" + std::to_string(height) +
                             ": both must be positive");
    if (!allFinite(K)) return Status::error(p + "_matrix contains NaN or infinity");
    if (!allFinite(cv::Matx<double, 1, 5>(distortion.val)))
        return Status::error(p + "_distortion contains NaN or infinity");
    if (K(0, 0) <= 0 || K(1, 1) <= 0)
        return Status::error(p + "_matrix has focal lengths fx=" + std::to_string(K(0, 0)) +
                             " fy=" + std::to_string(K(1, 1)) + ": both must be positive (the matrix is not invertible)");
    if (K(1, 0) != 0 || K(2, 0) != 0 || K(2, 1) != 0 || K(2, 2) != 1)
        return Status::error(p + "_matrix is not of the form [fx s cx; 0 fy cy; 0 0 1]");
    return Status::ok();
}

Result<RigModel> RigModel::create(const LensModel& camera, const LensModel& projector, const cv::Matx33d& R,
                                  const cv::Vec3d& T)
{
    if (Status s = camera.validate("camera"); !s) return s;
    if (Status s = projector.validate("projector"); !s) return s;
    if (!allFinite(R)) return Status::error("R contains NaN or infinity");
    if (!allFinite(cv::Matx31d(T.val))) return Status::error("T contains NaN or infinity");
    const double orthoError = cv::norm(R.t() * R - cv::Matx33d::eye(), cv::NORM_INF);
    if (orthoError > 1e-6)
        return Status::error("R is not a rotation matrix (R^T R differs from identity by " +
                             std::to_string(orthoError) + ")");
    if (cv::determinant(R) < 0) return Status::error("R is a reflection (determinant -1), not a rotation");
    if (cv::norm(T) < 1e-9) return Status::error("T is zero: camera and projector need a baseline to triangulate");
    RigModel rig;
    rig.camera_ = camera;
    rig.projector_ = projector;
    rig.R_ = R;
    rig.T_ = T;
    return rig;
}

Plane RigModel::lightPlaneForColumn(double projectorX) const
{
    // Rays of the projector column, distortion removed. Without distortion they
    // all lie in one plane; with it, this is the least-squares plane through the
    // projector centre (smallest eigenvector of the rays' scatter matrix).
    constexpr int kSamples = 17;
    Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
    for (int i = 0; i < kSamples; ++i) {
        const double y = (projector_.height - 1) * static_cast<double>(i) / (kSamples - 1);
        const cv::Vec3d r = projector_.rayThroughPixel({projectorX, y});
        const Eigen::Vector3d v = Eigen::Vector3d(r[0], r[1], r[2]).normalized();
        scatter += v * v.transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(scatter);
    Eigen::Vector3d n = solver.eigenvectors().col(0);
    if (n.x() < 0) n = -n;  // normal points towards increasing projector x
    const cv::Vec3d np(n.x(), n.y(), n.z());
    // n_p . X_p = 0 and X_p = R X_c + T  =>  (R^T n_p) . X_c + n_p . T = 0
    Plane plane;
    plane.normal = R_.t() * np;
    plane.d = np.dot(T_);
    return plane;
}

std::optional<cv::Vec3d> RigModel::triangulate(const cv::Vec2d& pixel, const Plane& plane) const
{
    return intersectRay(camera_.rayThroughPixel(pixel), plane);
}

}  // namespace stria::pipeline
