#pragma once
// A colour-coded picture of a depth map for people, in the style of the
// paper's figures: near = red ... far = blue (turbo-like), black = no data, and
// a scale bar labelled in millimetres along the bottom. Short gaps along a row
// between measured pixels of similar depth are filled for display.
#include <opencv2/core.hpp>

namespace stria::firmware {

// depth: CV_32FC1 in mm, NaN (or <= 0) = no data. When nearMm >= farMm the
// range is chosen robustly from the data (2nd..98th percentile), so a few
// outliers do not wash out the colours. Returns CV_8UC3 BGR for writePng:
// the depth map, with a 44-pixel strip below it holding the scale bar.
cv::Mat depthPreview(const cv::Mat& depth, double nearMm = 0.0, double farMm = 0.0);

}  // namespace stria::firmware
