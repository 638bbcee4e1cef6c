#include "pipeline/rig.hpp"

#include <gtest/gtest.h>

#include <random>

using namespace stria::pipeline;

namespace {

LensModel lens(int w, int h, double f, cv::Vec<double, 5> dist = {0, 0, 0, 0, 0})
{
    LensModel l;
    l.width = w;
    l.height = h;
    l.K = cv::Matx33d(f, 0, (w - 1) / 2.0 + 3.2, 0, f * 1.01, (h - 1) / 2.0 - 2.1, 0, 0, 1);
    l.distortion = dist;
    return l;
}

cv::Matx33d rotationY(double degrees)
{
    const double a = degrees * CV_PI / 180.0;
    return {std::cos(a), 0, std::sin(a), 0, 1, 0, -std::sin(a), 0, std::cos(a)};
}

RigModel makeRig(cv::Vec<double, 5> cameraDist, cv::Vec<double, 5> projectorDist)
{
    auto rig = RigModel::create(lens(780, 580, 1400, cameraDist), lens(1024, 768, 1800, projectorDist),
                                rotationY(-17.0) * cv::Matx33d(1, 0, 0, 0, std::cos(0.02), -std::sin(0.02), 0,
                                                               std::sin(0.02), std::cos(0.02)),
                                cv::Vec3d(-300, 4, 40));
    EXPECT_TRUE(rig) << rig.message();
    return *rig;
}

}  // namespace

TEST(LensModel, UndistortInvertsDistortion)
{
    const LensModel l = lens(780, 580, 1400, {-0.25, 0.12, 0.001, -0.0015, -0.02});
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> px(0, 780), py(0, 580);
    for (int i = 0; i < 200; ++i) {
        const cv::Vec2d pixel(px(rng), py(rng));
        const cv::Vec3d ray = l.rayThroughPixel(pixel);
        const cv::Vec2d back = l.project(ray);
        EXPECT_NEAR(back[0], pixel[0], 1e-9);
        EXPECT_NEAR(back[1], pixel[1], 1e-9);
    }
}

// A synthetic scene point seen by the camera and lit by a projector column
// must be recovered by ray-plane triangulation to 1e-6 relative.
TEST(RigModel, TriangulationRecoversSyntheticPoints)
{
    const RigModel rig = makeRig({-0.21, 0.09, 0.0007, -0.001, -0.01}, {0, 0, 0, 0, 0});
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> x(-250, 250), y(-180, 180), z(700, 1400);
    int tested = 0;
    for (int i = 0; i < 500; ++i) {
        const cv::Vec3d X(x(rng), y(rng), z(rng));
        const cv::Vec2d cameraPixel = rig.camera().project(X);
        const cv::Vec2d projectorPixel = rig.projector().project(rig.cameraToProjector(X));
        const Plane plane = rig.lightPlaneForColumn(projectorPixel[0]);
        EXPECT_NEAR(plane.signedDistance(X), 0.0, 1e-9 * cv::norm(X));
        const auto recovered = rig.triangulate(cameraPixel, plane);
        ASSERT_TRUE(recovered);
        EXPECT_LT(cv::norm(*recovered - X) / cv::norm(X), 1e-6) << "point " << i;
        ++tested;
    }
    EXPECT_EQ(tested, 500);
}

TEST(RigModel, LightPlanePassesThroughProjectorCentre)
{
    const RigModel rig = makeRig({0, 0, 0, 0, 0}, {0, 0, 0, 0, 0});
    const cv::Vec3d centre = rig.projectorCentreInCamera();
    for (double column : {0.0, 7.5, 511.5, 1023.0}) {
        const Plane plane = rig.lightPlaneForColumn(column);
        EXPECT_NEAR(cv::norm(plane.normal), 1.0, 1e-12);
        EXPECT_NEAR(plane.signedDistance(centre), 0.0, 1e-9);
    }
    // Planes ordered left to right: a point in the middle lies on the positive
    // side of the planes of smaller columns.
    const cv::Vec3d X(0, 0, 1000);
    const double column = rig.projector().project(rig.cameraToProjector(X))[0];
    EXPECT_GT(rig.lightPlaneForColumn(column - 10).signedDistance(X), 0);
    EXPECT_LT(rig.lightPlaneForColumn(column + 10).signedDistance(X), 0);
}

// With projector distortion a column's rays are no longer coplanar; the
// least-squares plane must stay within a small fraction of a millimetre at
// 1 m for a mild projector distortion (measured: 0.057 mm for k1 = 0.02 at
// column 700.5, against a 0.25 mm precision target).
TEST(RigModel, LightPlaneWithMildProjectorDistortion)
{
    const RigModel rig = makeRig({0, 0, 0, 0, 0}, {0.02, 0, 0, 0, 0});
    double worst = 0;
    for (double py = 0; py < 768; py += 32) {
        const cv::Vec2d projectorPixel(700.5, py);
        const cv::Vec3d ray = rig.projector().rayThroughPixel(projectorPixel);
        const cv::Vec3d Xp = ray * (1000.0 / ray[2]);
        const cv::Vec3d Xc = rig.projectorToCamera(Xp);
        worst = std::max(worst, std::abs(rig.lightPlaneForColumn(700.5).signedDistance(Xc)));
    }
    EXPECT_LT(worst, 0.08);
}

TEST(RigModel, RayParallelToPlaneGivesNoPoint)
{
    Plane plane;
    plane.normal = {1, 0, 0};
    plane.d = -10;
    EXPECT_FALSE(RigModel::intersectRay({0, 0, 1}, plane));
    EXPECT_TRUE(RigModel::intersectRay({0.01, 0, 1}, plane));
    EXPECT_FALSE(RigModel::intersectRay({-0.01, 0, 1}, plane));  // behind the camera
}

TEST(RigModel, RejectsBadGeometry)
{
    LensModel camera = lens(780, 580, 1400), projector = lens(1024, 768, 1800);
    const cv::Vec3d T(-300, 0, 0);

    LensModel singular = camera;
    singular.K(0, 0) = 0;
    auto r1 = RigModel::create(singular, projector, cv::Matx33d::eye(), T);
    ASSERT_FALSE(r1);
    EXPECT_NE(r1.message().find("camera_matrix"), std::string::npos) << r1.message();
    EXPECT_NE(r1.message().find("not invertible"), std::string::npos) << r1.message();

    LensModel nan = projector;
    nan.distortion[1] = std::nan("");
    auto r2 = RigModel::create(camera, nan, cv::Matx33d::eye(), T);
    ASSERT_FALSE(r2);
    EXPECT_EQ(r2.message(), "projector_distortion contains NaN or infinity");

    auto r3 = RigModel::create(camera, projector, cv::Matx33d(1, 0, 0, 0, 2, 0, 0, 0, 1), T);
    ASSERT_FALSE(r3);
    EXPECT_NE(r3.message().find("R is not a rotation matrix"), std::string::npos) << r3.message();

    auto r4 = RigModel::create(camera, projector, cv::Matx33d(-1, 0, 0, 0, 1, 0, 0, 0, 1), T);
    ASSERT_FALSE(r4);
    EXPECT_NE(r4.message().find("reflection"), std::string::npos);

    auto r5 = RigModel::create(camera, projector, cv::Matx33d::eye(), cv::Vec3d(0, 0, 0));
    ASSERT_FALSE(r5);
    EXPECT_NE(r5.message().find("baseline"), std::string::npos);

    LensModel empty = camera;
    empty.width = 0;
    auto r6 = RigModel::create(empty, projector, cv::Matx33d::eye(), T);
    ASSERT_FALSE(r6);
    EXPECT_NE(r6.message().find("camera_width/camera_height are 0x580"), std::string::npos) << r6.message();
}
