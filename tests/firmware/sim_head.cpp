#include "tests/firmware/sim_head.hpp"

#include "firmware/formats/atomic_file.hpp"
#include "firmware/formats/calibration_file.hpp"
#include "firmware/formats/pattern_file.hpp"
#include "hal/sim/scene/scene.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <sstream>

namespace stria::test {

namespace {

// Cheap to render (1 sample per pixel) but otherwise the paper's setting:
// textured relief ~1 m away, noise sigma 2. At the nominal 10 ms exposure the
// camera's frame equals a plain rendering of the scene (tests compare).
constexpr const char* kBoard = R"(name: test-head
camera:
  backend: sim
  width: 780
  height: 580
  exposure_us: 10000
  gain: 1.0
  timeout_ms: 300
light:
  backend: sim
  max_on_ms: 400
button:
  backend: sim
  debounce_ms: 20
pattern: pattern.yaml
calibration: calibration.yaml
settle_ms: 6
output_dir: out
sim:
  rig: desktop
  scene: relief
  albedo: coloured
  seed: 3
  noise: 2
  samples_per_pixel: 1
  frame_interval_us: 2000
  real_time: 0
  presses: "0"
)";

std::string applyOverrides(const std::vector<std::string>& overrides)
{
    std::vector<std::string> lines;
    std::istringstream in(kBoard);
    for (std::string line; std::getline(in, line);) lines.push_back(line);
    for (const std::string& o : overrides) {
        const std::string key = o.substr(0, o.find(':') + 1);
        auto it = std::find_if(lines.begin(), lines.end(), [&](const std::string& l) { return l.rfind(key, 0) == 0; });
        if (it != lines.end())
            *it = o;
        else
            lines.push_back(o);
    }
    std::string text;
    for (const auto& l : lines) text += l + "\n";
    return text;
}

}  // namespace

SimHead::SimHead(const std::vector<std::string>& overrides)
{
    std::string tmpl = (std::filesystem::temp_directory_path() / "stria-head-XXXXXX").string();
    dir_ = mkdtemp(tmpl.data());
    boardPath_ = dir_ + "/board.yaml";
    const auto rig = hal::sim::desktopRig();
    EXPECT_TRUE(firmware::saveCalibrationFile(rig.rig, dir_ + "/calibration.yaml"));
    EXPECT_TRUE(firmware::savePatternFile(rig.pattern, dir_ + "/pattern.yaml"));
    EXPECT_TRUE(firmware::writeFileAtomically(boardPath_, applyOverrides(overrides)));
}

SimHead::~SimHead()
{
    std::error_code ec;
    std::filesystem::permissions(dir_, std::filesystem::perms::owner_all, ec);
    std::filesystem::remove_all(dir_, ec);
}

firmware::BoardConfig SimHead::board() const
{
    auto board = firmware::loadBoardFile(boardPath_);
    EXPECT_TRUE(board.isOk()) << board.message();
    return board.isOk() ? *board : firmware::BoardConfig{};
}

std::vector<std::string> scanFolders(const std::string& outDir)
{
    std::vector<std::string> folders;
    std::error_code ec;
    for (const auto& entry : std::filesystem::directory_iterator(outDir, ec))
        if (entry.path().filename().string().rfind("scan-", 0) == 0) folders.push_back(entry.path().string());
    std::sort(folders.begin(), folders.end());
    return folders;
}

}  // namespace stria::test
