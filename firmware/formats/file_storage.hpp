#pragma once
// Small helpers over cv::FileStorage that turn its exceptions and silent
// defaults into errors naming the file and the key.
#include "pipeline/status.hpp"

#include <opencv2/core.hpp>

#include <string>
#include <vector>

namespace stria::firmware {

// Reads a whole file; the error names the path and the system's reason.
Result<std::string> readTextFile(const std::string& path);

// Opens YAML/XML/JSON text held in memory.
Status openFileStorage(cv::FileStorage& fs, const std::string& text, const std::string& sourceName);

// OpenCV's YAML reader keeps a trailing " # comment" inside an unquoted
// string value; YAML says " #" starts a comment. Returns the value without it.
std::string stripYamlComment(const std::string& value);

Result<int> readInt(const cv::FileNode& root, const char* key);
Result<std::string> readString(const cv::FileNode& root, const char* key);
// A matrix given as !!opencv-matrix or as a flat list of numbers; checks the
// element count (rows*cols) and that every value is finite.
Result<std::vector<double>> readMatrix(const cv::FileNode& root, const char* key, int rows, int cols);

}  // namespace stria::firmware
