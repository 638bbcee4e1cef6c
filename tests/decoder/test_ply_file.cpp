#include "firmware/formats/ply_file.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

namespace stria::firmware {
namespace {

namespace fs = std::filesystem;

fs::path tempDir()
{
    const fs::path dir = fs::temp_directory_path() / ("stria_ply_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    return dir;
}

std::vector<pipeline::ScanPoint> samplePoints()
{
    return {{cv::Vec3f(1.5f, -2.25f, 1000.125f), cv::Point2f(10.25f, 3.0f), 7},
            {cv::Vec3f(-0.001f, 3e-5f, 55.5f), cv::Point2f(779.75f, 579.0f), 126},
            {cv::Vec3f(0, 0, 1), cv::Point2f(0, 0), 0}};
}

void expectSame(const std::vector<pipeline::ScanPoint>& a, const std::vector<pipeline::ScanPoint>& b)
{
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
        for (int k = 0; k < 3; ++k) EXPECT_EQ(a[i].position[k], b[i].position[k]);
        EXPECT_EQ(a[i].pixel, b[i].pixel);
        EXPECT_EQ(a[i].edge, b[i].edge);
    }
}

TEST(PlyFile, BinaryRoundTripIsExactAnd24BytesPerPoint)
{
    const fs::path path = tempDir() / "points.ply";
    const auto points = samplePoints();
    ASSERT_TRUE(writePly(path.string(), points));
    auto back = readPly(path.string());
    ASSERT_TRUE(back) << back.message();
    expectSame(points, *back);
    std::ifstream in(path, std::ios::binary);
    std::string text((std::istreambuf_iterator<char>(in)), {});
    const std::size_t headerEnd = text.find("end_header\n") + 11;
    EXPECT_EQ(text.size() - headerEnd, 3u * 24u);
    EXPECT_NE(text.find("format binary_little_endian 1.0"), std::string::npos);
}

TEST(PlyFile, AsciiRoundTripIsExact)
{
    const fs::path path = tempDir() / "points_ascii.ply";
    const auto points = samplePoints();
    ASSERT_TRUE(writePly(path.string(), points, true));
    auto back = readPly(path.string());
    ASSERT_TRUE(back) << back.message();
    expectSame(points, *back);
}

TEST(PlyFile, TruncatedFileNamesTheVertex)
{
    const fs::path path = tempDir() / "short.ply";
    ASSERT_TRUE(writePly(path.string(), samplePoints()));
    fs::resize_file(path, fs::file_size(path) - 10);
    auto back = readPly(path.string());
    ASSERT_FALSE(back);
    EXPECT_EQ(back.message(), "PLY '" + path.string() + "': the file ends at vertex 2 of 3");
}

TEST(PlyFile, UnwritableDirectoryLeavesNothingAndSaysWhy)
{
    const fs::path path = tempDir() / "missing_dir" / "x.ply";
    const Status s = writePly(path.string(), samplePoints());
    ASSERT_FALSE(s);
    EXPECT_NE(s.message().find(path.parent_path().string()), std::string::npos) << s.message();
    EXPECT_FALSE(fs::exists(path));
}

}  // namespace
}  // namespace stria::firmware
