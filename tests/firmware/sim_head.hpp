#pragma once
// A simulated head in a temporary folder for the firmware tests: the desktop
// rig's calibration and pattern files, and a board file whose keys a test can
// override ("settle_ms: 40" replaces the default line).
#include "firmware/formats/board_file.hpp"

#include <string>
#include <vector>

namespace stria::test {

class SimHead {
public:
    // `overrides`: "key: value" lines; a line for a key already present replaces it
    // (keys are matched with their indentation, e.g. "  max_on_ms: 50").
    explicit SimHead(const std::vector<std::string>& overrides = {});
    ~SimHead();

    const std::string& dir() const { return dir_; }
    const std::string& boardPath() const { return boardPath_; }
    std::string outDir() const { return dir_ + "/out"; }
    firmware::BoardConfig board() const;

private:
    std::string dir_;
    std::string boardPath_;
};

// Scan folders (scan-*) under `outDir`, sorted by name (= by time, then sequence).
std::vector<std::string> scanFolders(const std::string& outDir);

}  // namespace stria::test
