#include "firmware/formats/image_file.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

using namespace stria::firmware;
namespace fs = std::filesystem;

namespace {
std::string tmp(const char* name) { return (fs::temp_directory_path() / name).string(); }
}  // namespace

TEST(ImageFile, PngRoundTripKeepsBgrBytes)
{
    cv::Mat image(37, 53, CV_8UC3);
    cv::randu(image, 0, 256);
    const std::string path = tmp("stria-roundtrip.png");
    ASSERT_TRUE(writePng(path, image));
    auto back = readPng(path);
    ASSERT_TRUE(back) << back.message();
    EXPECT_EQ(cv::norm(*back, image, cv::NORM_INF), 0.0);
}

TEST(ImageFile, GreyAndSixteenBitPngBecomeBgr)
{
    cv::Mat grey16(4, 5, CV_16UC1, cv::Scalar(0x8000));
    const std::string path = tmp("stria-grey16.png");
    ASSERT_TRUE(writePng(path, grey16));
    auto back = readPng(path);
    ASSERT_TRUE(back) << back.message();
    ASSERT_EQ(back->type(), CV_8UC3);
    EXPECT_EQ(back->at<cv::Vec3b>(2, 2), cv::Vec3b(128, 128, 128));
}

TEST(ImageFile, CorruptAndForeignFilesAreNamed)
{
    cv::Mat image(64, 64, CV_8UC3, cv::Scalar(1, 2, 3));
    const std::string good = tmp("stria-good.png");
    ASSERT_TRUE(writePng(good, image));
    std::ifstream in(good, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), {});
    const std::string truncated = tmp("stria-truncated.png");
    std::ofstream(truncated, std::ios::binary) << bytes.substr(0, bytes.size() / 2);
    auto r1 = readPng(truncated);
    ASSERT_FALSE(r1);
    EXPECT_NE(r1.message().find("image '" + truncated + "' is corrupt"), std::string::npos) << r1.message();

    const std::string text = tmp("stria-text.png");
    std::ofstream(text) << "not an image at all";
    auto r2 = readPng(text);
    ASSERT_FALSE(r2);
    EXPECT_EQ(r2.message(), "image '" + text + "' is not a PNG file");

    auto r3 = readPng("/nonexistent/x.png");
    ASSERT_FALSE(r3);
    EXPECT_EQ(r3.message(), "cannot read image '/nonexistent/x.png': No such file or directory");
}

TEST(ImageFile, FloatTiffRoundTripKeepsNaN)
{
    cv::Mat depth(20, 30, CV_32FC1);
    cv::randu(depth, 100.0f, 2000.0f);
    depth.at<float>(3, 4) = std::nanf("");
    const std::string path = tmp("stria-depth.tiff");
    ASSERT_TRUE(writeTiffFloat(path, depth));
    auto back = readTiffFloat(path);
    ASSERT_TRUE(back) << back.message();
    EXPECT_TRUE(std::isnan(back->at<float>(3, 4)));
    back->at<float>(3, 4) = depth.at<float>(3, 4) = 0;
    EXPECT_EQ(cv::norm(*back, depth, cv::NORM_INF), 0.0);

    const auto wrongType = writeTiffFloat(tmp("stria-bad.tiff"), cv::Mat(2, 2, CV_8UC1));
    ASSERT_FALSE(wrongType);
    EXPECT_FALSE(fs::exists(tmp("stria-bad.tiff")));
}
