// Board files: the shipped sim board loads; every kind of mistake is an
// error naming the file and the key.
#include "firmware/formats/board_file.hpp"
#include "firmware/formats/calibration_file.hpp"
#include "firmware/formats/pattern_file.hpp"

#include "pipeline/decoder.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

using stria::firmware::parseBoard;

namespace {

const std::string kMinimal = R"(name: t
camera: {backend: sim, width: 780, height: 580}
light: {backend: sim}
button: {backend: sim}
pattern: p.yaml
calibration: c.yaml
)";

std::string errorOf(const std::string& text)
{
    auto board = parseBoard(text, "/heads/x/board.yaml");
    return board.isOk() ? std::string("(no error)") : board.message();
}

}  // namespace

TEST(BoardFile, ShippedSimBoardLoads)
{
    const std::string path = std::string(STRIA_SOURCE_DIR) + "/board/sim/board.yaml";
    auto board = stria::firmware::loadBoardFile(path);
    ASSERT_TRUE(board.isOk()) << board.message();
    EXPECT_EQ(board->name, "sim");
    EXPECT_EQ(board->camera.backend, "sim");
    EXPECT_EQ(board->camera.width, 780);
    EXPECT_EQ(board->calibrationPath, std::string(STRIA_SOURCE_DIR) + "/board/sim/calibration.yaml");
    EXPECT_EQ(board->sim.scene, "fingertip");  // the simulated fingerprint head
    EXPECT_LT(board->settleMs + board->camera.exposureUs / 1000, board->light.maxOnMs);

    auto desktop = stria::firmware::loadBoardFile(std::string(STRIA_SOURCE_DIR) + "/board/sim-desktop/board.yaml");
    ASSERT_TRUE(desktop.isOk()) << desktop.message();
    EXPECT_EQ(desktop->name, "sim-desktop");
    EXPECT_EQ(desktop->sim.scene, "relief");
}

TEST(BoardFile, DefaultsAndRelativePaths)
{
    auto board = parseBoard(kMinimal + "output_dir: ../scans\n", "/heads/x/board.yaml");
    ASSERT_TRUE(board.isOk()) << board.message();
    EXPECT_EQ(board->patternPath, "/heads/x/p.yaml");
    EXPECT_EQ(board->outputDir, "/heads/scans");
    EXPECT_EQ(board->settleMs, 15);
    EXPECT_EQ(board->light.maxOnMs, 500);
    EXPECT_EQ(board->button.debounceMs, 20);
    EXPECT_TRUE(board->button.activeLow);
    EXPECT_DOUBLE_EQ(board->decoder.t, 1.0 / 3.0);
    EXPECT_FALSE(board->statusLed.has_value());
}

TEST(BoardFile, DecoderAndSimKeys)
{
    auto board = parseBoard(kMinimal + "decoder: {t: 0.25, A: 0.7, min_component_regions: 3, row_pairs: 1, "
                                       "noise_floor_factor: 0.9}\n"
                                       "sim: {scene: fan, noise: 8, real_time: true, presses: \"5,10b\"}\n",
                            "b.yaml");
    ASSERT_TRUE(board.isOk()) << board.message();
    EXPECT_DOUBLE_EQ(board->decoder.t, 0.25);
    EXPECT_DOUBLE_EQ(board->decoder.A, 0.7);
    EXPECT_EQ(board->decoder.minComponentRegions, 3);
    EXPECT_TRUE(board->decoder.segmentRowPairs);
    EXPECT_DOUBLE_EQ(board->decoder.noiseFloorFactor, 0.9);
    EXPECT_EQ(board->sim.scene, "fan");
    EXPECT_DOUBLE_EQ(board->sim.noise, 8);
    EXPECT_TRUE(board->sim.realTime);
    EXPECT_EQ(board->sim.presses, "5,10b");
}

TEST(BoardFile, ErrorsNameFileAndKey)
{
    EXPECT_EQ(errorOf("name: t\n"), "board '/heads/x/board.yaml': key 'pattern' is missing");
    std::string noCamera = kMinimal;
    noCamera.replace(noCamera.find("camera"), noCamera.find("light") - noCamera.find("camera"), "");
    EXPECT_EQ(errorOf(noCamera), "board '/heads/x/board.yaml': section 'camera' is missing");
    std::string text = kMinimal;
    text.replace(text.find("backend: sim, width"), 12, "backend: usb");
    EXPECT_EQ(errorOf(text),
              "board '/heads/x/board.yaml': key 'camera.backend' is 'usb', expected one of: sim, v4l2, libcamera");
    EXPECT_EQ(errorOf(kMinimal + "settle_ms: -3\n"),
              "board '/heads/x/board.yaml': key 'settle_ms' is -3.000000, must be between 0.000000 and 10000.000000");
    std::string gpio = kMinimal;
    gpio.replace(gpio.find("light: {backend: sim}"), 21, "light: {backend: gpiod, chip: gpiochip0}");
    EXPECT_EQ(errorOf(gpio), "board '/heads/x/board.yaml': key 'light.backend' gpiod needs 'chip' and 'line'");
    EXPECT_EQ(errorOf(kMinimal + "sim: {scene: teapot}\n"),
              "board '/heads/x/board.yaml': key 'sim.scene' is 'teapot', expected one of: plane, sphere, relief, "
              "clutter, fan, fingertip, tube");
    std::string flag = kMinimal;
    flag.replace(flag.find("button: {backend: sim}"), 22, "button: {backend: sim, active_low: maybe}");
    EXPECT_EQ(errorOf(flag), "board '/heads/x/board.yaml': key 'button.active_low' must be true or false (or 1/0)");
    EXPECT_EQ(errorOf(kMinimal + "decoder: {alpha: fast}\n"),
              "board '/heads/x/board.yaml': key 'decoder.alpha' must be a number");
    auto missing = stria::firmware::loadBoardFile("/nonexistent/board.yaml");
    ASSERT_FALSE(missing.isOk());
    EXPECT_EQ(missing.message(), "board: cannot read '/nonexistent/board.yaml': No such file or directory");
}

TEST(BoardFile, EveryShippedBoardLoadsWithItsCalibrationAndPattern)
{
    int boards = 0, rowPairBoards = 0;
    for (const auto& entry : std::filesystem::directory_iterator(std::string(STRIA_SOURCE_DIR) + "/board")) {
        const std::string path = entry.path().string() + "/board.yaml";
        if (!std::filesystem::exists(path)) continue;
        ++boards;
        auto board = stria::firmware::loadBoardFile(path);
        ASSERT_TRUE(board.isOk()) << board.message();
        auto rig = stria::firmware::loadCalibrationFile(board->calibrationPath);
        ASSERT_TRUE(rig.isOk()) << rig.message();
        EXPECT_EQ(rig->camera().width, board->camera.width) << path;
        EXPECT_EQ(rig->camera().height, board->camera.height) << path;
        auto pattern = stria::firmware::loadPatternFile(board->patternPath);
        ASSERT_TRUE(pattern.isOk()) << pattern.message();
        EXPECT_LE(pattern->projectorColumnsUsed(), rig->projector().width) << path;
        EXPECT_LT(board->settleMs + board->camera.exposureUs / 1000, board->light.maxOnMs) << path;
        // The decoder section works with this calibration (row pairs need its stripes along the columns).
        auto decoder = stria::pipeline::Decoder::create(*pattern, *rig, board->decoder);
        EXPECT_TRUE(decoder.isOk()) << path << ": " << decoder.message();
        rowPairBoards += board->decoder.segmentRowPairs;
    }
    EXPECT_GE(rowPairBoards, 1);  // the endoscope's video mode
    EXPECT_GE(boards, 1);
}
