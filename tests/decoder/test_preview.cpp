#include "firmware/formats/preview.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace stria::firmware {
namespace {

TEST(DepthPreview, NoDataIsBlackNearIsRedFarIsBlueWithScaleBar)
{
    cv::Mat depth(100, 300, CV_32FC1, cv::Scalar(std::nanf("")));
    for (int x = 0; x < 300; ++x)
        for (int y = 20; y < 80; ++y) depth.at<float>(y, x) = 900.0f + x;  // 900 .. 1199 mm
    depth.at<float>(50, 150) = 1e6f;  // one outlier must not stretch the range
    const cv::Mat out = depthPreview(depth);
    ASSERT_EQ(out.type(), CV_8UC3);
    EXPECT_EQ(out.cols, 300);
    EXPECT_EQ(out.rows, 100 + 44);
    EXPECT_EQ(out.at<cv::Vec3b>(5, 5), cv::Vec3b(0, 0, 0));
    const cv::Vec3b near = out.at<cv::Vec3b>(50, 2), far = out.at<cv::Vec3b>(50, 297);
    EXPECT_GT(near[2], 200);  // red
    EXPECT_LT(near[0], 60);
    EXPECT_GT(far[0], 200);   // blue
    EXPECT_LT(far[2], 60);
    // The bar holds labels: some white text pixels below the image.
    const cv::Mat bar = out.rowRange(100, out.rows);
    int white = 0;
    for (int y = 0; y < bar.rows; ++y)
        for (int x = 0; x < bar.cols; ++x) {
            const cv::Vec3b c = bar.at<cv::Vec3b>(y, x);
            white += c[0] > 200 && c[1] > 200 && c[2] > 200;
        }
    EXPECT_GT(white, 20);
}

TEST(DepthPreview, FixedRangeMapsEndsToRampEnds)
{
    cv::Mat depth(10, 300, CV_32FC1, cv::Scalar(500.0f));
    depth.at<float>(5, 5) = 400.0f;
    const cv::Mat out = depthPreview(depth, 400, 500);
    EXPECT_GT(out.at<cv::Vec3b>(5, 5)[2], 200);  // near end: red
    EXPECT_GT(out.at<cv::Vec3b>(0, 0)[0], 200);  // far end: blue
}

}  // namespace
}  // namespace stria::firmware
