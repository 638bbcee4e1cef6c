#pragma once
// Image files: PNG through libpng, 32-bit float TIFF through libtiff (see the
// top-level CMakeLists.txt for why not OpenCV's imgcodecs). Every write is
// atomic (AtomicFile): a failed write leaves no file behind.
#include "pipeline/status.hpp"

#include <opencv2/core.hpp>

#include <string>
#include <vector>

namespace stria::firmware {

// Any 8- or 16-bit PNG (grey, grey+alpha, RGB, RGBA, palette) as 8-bit BGR
// (CV_8UC3), the decoder's layout. Errors name the file and what is wrong.
Result<cv::Mat> readPng(const std::string& path);
// CV_8UC1 (grey), CV_8UC3 (BGR), CV_8UC4 (BGRA) or CV_16UC1.
Result<std::vector<unsigned char>> encodePng(const cv::Mat& image);
Status writePng(const std::string& path, const cv::Mat& image);

// Single-channel 32-bit float TIFF (depth maps in mm, NaN = no data).
Status writeTiffFloat(const std::string& path, const cv::Mat& image);
Result<cv::Mat> readTiffFloat(const std::string& path);

}  // namespace stria::firmware
