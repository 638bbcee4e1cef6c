#pragma once
// Geometry of the camera-projector rig (OpenCV conventions: x right, y down,
// z forward, millimetres, pixel centres on integer coordinates):
//   X_projector = R * X_camera + T.
// Both devices are pinholes with OpenCV's 5-coefficient distortion
// (k1 k2 p1 p2 k3).

#include "pipeline/status.hpp"

#include <opencv2/core.hpp>

#include <cmath>
#include <optional>

namespace stria::pipeline {

struct LensModel {
    int width = 0;
    int height = 0;
    cv::Matx33d K = cv::Matx33d::eye();
    cv::Vec<double, 5> distortion{0, 0, 0, 0, 0};  // k1 k2 p1 p2 k3

    // Normalised image coordinates (x/z, y/z) -> distorted normalised coordinates.
    cv::Vec2d distortNormalized(const cv::Vec2d& xn) const;
    // Pixel -> undistorted normalised coordinates (iterative inverse of distortion).
    cv::Vec2d undistortPixel(const cv::Vec2d& pixel) const;
    // Unit-free ray (x, y, 1) through a pixel, distortion removed.
    cv::Vec3d rayThroughPixel(const cv::Vec2d& pixel) const;
    // Point in this device's frame -> pixel (with distortion). z must be > 0.
    cv::Vec2d project(const cv::Vec3d& point) const;

    Status validate(const char* prefix) const;
};

// n . X + d = 0 with |n| = 1, in the camera frame.
struct Plane {
    cv::Vec3d normal{0, 0, 1};
    double d = 0;
    double signedDistance(const cv::Vec3d& p) const { return normal.dot(p) + d; }
};

class RigModel {
public:
    // Validates (finite values, invertible intrinsics, rotation matrix, sizes).
    static Result<RigModel> create(const LensModel& camera, const LensModel& projector, const cv::Matx33d& R,
                                   const cv::Vec3d& T);

    const LensModel& camera() const { return camera_; }
    const LensModel& projector() const { return projector_; }
    const cv::Matx33d& R() const { return R_; }
    const cv::Vec3d& T() const { return T_; }

    cv::Vec3d cameraToProjector(const cv::Vec3d& pc) const { return R_ * pc + T_; }
    cv::Vec3d projectorToCamera(const cv::Vec3d& pp) const { return R_.t() * (pp - T_); }
    cv::Vec3d projectorCentreInCamera() const { return -(R_.t() * T_); }

    // The plane of light through the projector centre and projector column x
    // (distortion removed: the best plane through the rays of that column).
    Plane lightPlaneForColumn(double projectorX) const;

    // Point where the camera ray through `pixel` meets `plane`; empty when the
    // ray is parallel to the plane or the point lies behind the camera.
    std::optional<cv::Vec3d> triangulate(const cv::Vec2d& pixel, const Plane& plane) const;
    // The depth stage (depth.cpp, step 5) computes the same, bit for bit,
    // for two points at a time in double lanes: change both together.
    static std::optional<cv::Vec3d> intersectRay(const cv::Vec3d& ray, const Plane& plane)
    {
        const double denom = plane.normal.dot(ray);
        if (std::abs(denom) < 1e-12) return std::nullopt;
        const double t = -plane.d / denom;
        if (!(t > 0)) return std::nullopt;
        return ray * t;
    }

private:
    LensModel camera_;
    LensModel projector_;
    cv::Matx33d R_ = cv::Matx33d::eye();
    cv::Vec3d T_{0, 0, 0};
};

}  // namespace stria::pipeline
