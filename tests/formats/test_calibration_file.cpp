#include "firmware/formats/calibration_file.hpp"

#include <gtest/gtest.h>

#include <filesystem>

using namespace stria;
using namespace stria::firmware;

namespace {

const char* kValid = R"(
camera_width: 780
camera_height: 580
camera_matrix: !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [ 1400., 0., 392., 0., 1400., 288., 0., 0., 1. ]
camera_distortion: [ -0.1, 0.02, 0., 0., 0. ]
projector_width: 1024
projector_height: 768
projector_matrix: [ 1800., 0., 511.5, 0., 1800., 383.5, 0., 0., 1. ]
projector_distortion: [ 0., 0., 0., 0., 0. ]
R: [ 0.96126169593831889, 0., -0.27563735581699916, 0., 1., 0., 0.27563735581699916, 0., 0.96126169593831889 ]
T: [ -300., 0., 40. ]
)";

std::string without(const std::string& key)
{
    std::string text = kValid;
    const auto pos = text.find("\n" + key + ":");
    const auto end = text.find('\n', text.find(key + ":") + key.size() + 1);
    // multi-line matrices: drop the indented lines that follow
    auto stop = end;
    while (stop + 1 < text.size() && text[stop + 1] == ' ') stop = text.find('\n', stop + 1);
    return text.erase(pos, stop - pos);
}

}  // namespace

TEST(CalibrationFile, ParsesOpenCvMatricesAndPlainLists)
{
    auto rig = parseCalibration(kValid, "test.yaml");
    ASSERT_TRUE(rig) << rig.message();
    EXPECT_EQ(rig->camera().width, 780);
    EXPECT_DOUBLE_EQ(rig->camera().K(0, 2), 392.0);
    EXPECT_DOUBLE_EQ(rig->camera().distortion[0], -0.1);
    EXPECT_DOUBLE_EQ(rig->projector().K(1, 2), 383.5);
    EXPECT_DOUBLE_EQ(rig->T()[0], -300.0);
}

TEST(CalibrationFile, RoundTripsThroughSave)
{
    auto rig = parseCalibration(kValid, "test.yaml");
    ASSERT_TRUE(rig);
    const auto path = (std::filesystem::temp_directory_path() / "stria-calib-roundtrip.yaml").string();
    ASSERT_TRUE(saveCalibrationFile(*rig, path));
    auto back = loadCalibrationFile(path);
    ASSERT_TRUE(back) << back.message();
    EXPECT_EQ(cv::norm(back->R() - rig->R(), cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(back->camera().K - rig->camera().K, cv::NORM_INF), 0.0);
    EXPECT_EQ(back->projector().height, 768);
    std::filesystem::remove(path);
}

TEST(CalibrationFile, EveryMissingKeyIsNamed)
{
    for (const char* key : {"camera_width", "camera_height", "camera_matrix", "camera_distortion", "projector_width",
                            "projector_height", "projector_matrix", "projector_distortion", "R", "T"}) {
        auto rig = parseCalibration(without(key), "c.yaml");
        ASSERT_FALSE(rig) << key;
        EXPECT_NE(rig.message().find(std::string("calibration 'c.yaml': missing key '") + key + "'"),
                  std::string::npos)
            << rig.message();
    }
}

TEST(CalibrationFile, BadValuesAreNamed)
{
    std::string nan = kValid;
    nan.replace(nan.find("-0.1, 0.02"), 10, ".nan, 0.02");
    auto r1 = parseCalibration(nan, "c.yaml");
    ASSERT_FALSE(r1);
    EXPECT_EQ(r1.message(), "calibration 'c.yaml': key 'camera_distortion' contains NaN or infinity");

    std::string shape = kValid;
    shape.replace(shape.find("[ -300., 0., 40. ]"), 18, "[ -300., 0. ]");
    auto r2 = parseCalibration(shape, "c.yaml");
    ASSERT_FALSE(r2);
    EXPECT_EQ(r2.message(), "calibration 'c.yaml': key 'T' must be 3x1 (3 numbers), found 2 numbers");

    std::string singular = kValid;
    singular.replace(singular.find("[ 1800., 0., 511.5"), 18, "[ 0., 0., 511.5");
    auto r3 = parseCalibration(singular, "c.yaml");
    ASSERT_FALSE(r3);
    EXPECT_NE(r3.message().find("projector_matrix has focal lengths fx=0"), std::string::npos) << r3.message();

    auto r4 = parseCalibration("camera_width: [ oops", "c.yaml");
    ASSERT_FALSE(r4);
    EXPECT_NE(r4.message().find("'c.yaml' is not valid YAML"), std::string::npos) << r4.message();

    auto r5 = parseCalibration("", "c.yaml");
    ASSERT_FALSE(r5);
    EXPECT_EQ(r5.message(), "calibration: 'c.yaml' is empty");
}

TEST(CalibrationFile, MissingFileNamesPathAndReason)
{
    auto rig = loadCalibrationFile("/nonexistent/calib.yaml");
    ASSERT_FALSE(rig);
    EXPECT_EQ(rig.message(), "calibration: cannot read '/nonexistent/calib.yaml': No such file or directory");
}
