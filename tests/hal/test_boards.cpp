// The real heads' board folders (board/fingerprint-cm4, board/endoscope-pi5)
// load, and their files agree with each other and with the geometry their
// README.md describes.
#include "firmware/formats/board_file.hpp"
#include "firmware/formats/calibration_file.hpp"
#include "firmware/formats/pattern_file.hpp"

#include <gtest/gtest.h>

#include <cctype>
#include <ostream>

namespace stria::firmware {
namespace {

struct Head {
    const char* folder;
    const char* cameraBackend;
    const char* cameraDevice;
    const char* gpioChip;  // by label: chip numbers change between kernels
    double workingDistanceMm;  // where the camera and projector axes cross
};

void PrintTo(const Head& head, std::ostream* os) { *os << head.folder; }

class RealHead : public ::testing::TestWithParam<Head> {};

TEST_P(RealHead, BoardPatternAndCalibrationAgree)
{
    const Head head = GetParam();
    const std::string folder = std::string(STRIA_SOURCE_DIR) + "/board/" + head.folder;
    auto board = loadBoardFile(folder + "/board.yaml");
    ASSERT_TRUE(board.isOk()) << board.message();
    EXPECT_EQ(board->name, head.folder);
    EXPECT_EQ(board->camera.backend, head.cameraBackend);
    EXPECT_EQ(board->camera.device, head.cameraDevice);
    EXPECT_EQ(board->light.chip, head.gpioChip);
    EXPECT_EQ(board->button.chip, head.gpioChip);
    EXPECT_EQ(board->light.line, 17);   // README.md pin maps
    EXPECT_EQ(board->button.line, 27);
    EXPECT_EQ(board->light.backend, "gpiod");
    EXPECT_EQ(board->button.backend, "gpiod");
    EXPECT_FALSE(board->light.activeLow);
    EXPECT_TRUE(board->button.activeLow);
    EXPECT_LT(board->settleMs + board->camera.exposureUs / 1000.0, board->light.maxOnMs);

    auto rig = loadCalibrationFile(board->calibrationPath);
    ASSERT_TRUE(rig.isOk()) << rig.message();
    EXPECT_EQ(rig->camera().width, board->camera.width);
    EXPECT_EQ(rig->camera().height, board->camera.height);
    auto pattern = loadPatternFile(board->patternPath);
    ASSERT_TRUE(pattern.isOk()) << pattern.message();
    EXPECT_LE(pattern->projectorColumnsUsed(), rig->projector().width);

    // The projector's centre column lights the camera's optical axis at the
    // working distance.
    const double centreColumn = rig->projector().K(0, 2);
    const cv::Vec2d principalPoint(rig->camera().K(0, 2), rig->camera().K(1, 2));
    auto onAxis = rig->triangulate(principalPoint, rig->lightPlaneForColumn(centreColumn));
    ASSERT_TRUE(onAxis.has_value());
    EXPECT_NEAR((*onAxis)[2], head.workingDistanceMm, 0.1);
    EXPECT_NEAR((*onAxis)[0], 0.0, 1e-6);
}

INSTANTIATE_TEST_SUITE_P(Boards, RealHead,
                         ::testing::Values(Head{"fingerprint-cm4", "libcamera", "0", "pinctrl-bcm2711", 60.0},
                                           Head{"endoscope-pi5", "v4l2", "/dev/stria-endoscope", "pinctrl-rp1", 20.0}),
                         [](const auto& info) {
                             std::string name = info.param.folder;
                             for (char& c : name) c = std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
                             return name;
                         });

}  // namespace
}  // namespace stria::firmware
