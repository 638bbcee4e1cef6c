#pragma once
// Board files: everything about one scanner head, in OpenCV FileStorage YAML
// (board/NAME/board.yaml). Paths inside are relative to the board file.
// docs/boards.md describes every key; errors name the file and the key.
#include "pipeline/decoder.hpp"
#include "pipeline/status.hpp"

#include <optional>
#include <string>

namespace stria::firmware {

struct BoardCamera {
    std::string backend;  // sim | v4l2 | libcamera
    std::string device;   // /dev/video0, a libcamera id or index; unused by sim
    int width = 0, height = 0;
    double exposureUs = 10000;
    double gain = 1.0;
    int bufferCount = 3;
    int timeoutMs = 1000;  // longest wait for a frame
};

struct BoardLight {
    std::string backend;  // sim | gpiod
    std::string chip;     // gpiochip0, or a label/path gpiod_chip_open_lookup accepts
    int line = -1;
    bool activeLow = false;
    int maxOnMs = 500;    // watchdog: the LED is forced off after this long
};

struct BoardButton {
    std::string backend;  // sim | gpiod
    std::string chip;
    int line = -1;
    bool activeLow = true;  // buttons usually pull the line to ground
    int debounceMs = 20;
};

// The simulated head (camera/light/button backend "sim").
struct BoardSim {
    std::string rig = "desktop";  // desktop | desktop-large | fingerprint | endoscope
    std::string scene = "relief";
    std::string albedo = "uniform";
    std::uint64_t seed = 1;
    double noise = 2.0;           // Gaussian noise sigma, 8-bit digits
    double ambient = 0.05;
    double contrast = 1.0;
    int samplesPerPixel = 4;
    int frameIntervalUs = 33333;  // free-running sensor frame period
    bool realTime = false;        // replay presses in real time, else at once
    std::string presses;          // press script ("100,900b,1500"; see hal/sim/sim_button.hpp)
};

struct BoardConfig {
    std::string path;  // the board file itself
    std::string name;
    BoardCamera camera;
    BoardLight light;
    BoardButton button;
    std::optional<BoardLight> statusLed;
    std::string patternPath;      // resolved against the board file's folder
    std::string calibrationPath;
    int settleMs = 15;            // LED on -> capture
    std::string outputDir;        // resolved; default output folder of `stria scan`
    pipeline::DecoderParams decoder;
    BoardSim sim;
};

Result<BoardConfig> loadBoardFile(const std::string& path);
// `sourcePath` names the file in errors and anchors relative paths.
Result<BoardConfig> parseBoard(const std::string& text, const std::string& sourcePath);

}  // namespace stria::firmware
