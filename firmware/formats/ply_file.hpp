#pragma once
// Point clouds as PLY: one vertex per ScanPoint with properties
//   float x y z   (mm, camera frame)
//   float u v     (camera pixel, sub-pixel column and row)
//   int edge      (pattern edge index)
// Binary little-endian by default, ASCII on request; written atomically.
#include "pipeline/decoder.hpp"
#include "pipeline/status.hpp"

#include <span>
#include <string>
#include <vector>

namespace stria::firmware {

Status writePly(const std::string& path, std::span<const pipeline::ScanPoint> points, bool ascii = false);
// Reads what writePly writes (either encoding); errors name the file and the problem.
Result<std::vector<pipeline::ScanPoint>> readPly(const std::string& path);

}  // namespace stria::firmware
