#pragma once
// Calibration files: OpenCV FileStorage YAML with the names OpenCV users know:
// camera_width, camera_height, camera_matrix (3x3), camera_distortion (1x5),
// projector_width, projector_height, projector_matrix, projector_distortion,
// R (3x3), T (3x1), with X_projector = R * X_camera + T in millimetres.
#include "pipeline/rig.hpp"

#include <string>

namespace stria::firmware {

Result<pipeline::RigModel> loadCalibrationFile(const std::string& path);
Result<pipeline::RigModel> parseCalibration(const std::string& text, const std::string& sourceName);
Status saveCalibrationFile(const pipeline::RigModel& rig, const std::string& path);

}  // namespace stria::firmware
