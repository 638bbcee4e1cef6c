#pragma once
// The decoder's pixel kernels with a plain scalar reference each. The fast
// versions (NEON intrinsics on ARM, auto-vectorised lanes elsewhere) must give
// exactly the reference's output: tests/decoder/test_kernels.cpp checks them
// on random and simulator frames.

#include <opencv2/core.hpp>

#include <array>
#include <cstdint>

namespace stria::pipeline {

// One row of the gradient stage (gradient.cpp) from the rows above, at and
// below it (clamped at the image border by the caller): per pixel,
// magnitude = (max over channels of Sobel |dx|/4 + |dy|/4, + 1) / 2 and
// along = max over channels of |dy|/4 (alongY) or |dx|/4.
void gradientRowReference(const std::uint8_t* up, const std::uint8_t* row, const std::uint8_t* down, int width,
                          bool alongY, std::uint8_t* magnitude, std::uint8_t* along);
// Same output. lanes: 12 x width int16 of scratch (unused with NEON).
void gradientRow(const std::uint8_t* up, const std::uint8_t* row, const std::uint8_t* down, int width, bool alongY,
                 std::uint8_t* magnitude, std::uint8_t* along, std::int16_t* lanes);

// Edge location (depth.cpp): for the count samples i = first, first + 1, ...
// of a row, the colour change from pixel i to i + 1 (R G B at rgbOffset),
// crosstalk-corrected by m and projected on weight: weight . (m * change),
// summed in that order (so the NEON lanes give the same floats).
void projectedGradientsReference(const std::uint8_t* row, int first, int count, const std::array<int, 3>& rgbOffset,
                                 const cv::Matx33f& m, const cv::Vec3f& weight, float* out);
void projectedGradients(const std::uint8_t* row, int first, int count, const std::array<int, 3>& rgbOffset,
                        const cv::Matx33f& m, const cv::Vec3f& weight, float* out);

// Region colour statistics (regions.cpp). A 256-bin count of byte values.
using ValueHistogram = std::array<std::int32_t, 256>;
// Adds one BGR/RGB row's values to the R, G, B histograms (rgbOffset: byte
// offset of R, G, B within a pixel).
void channelHistogramsReference(const std::uint8_t* row, int width, const std::array<int, 3>& rgbOffset,
                                std::array<ValueHistogram, 3>& histogram);
void channelHistograms(const std::uint8_t* row, int width, const std::array<int, 3>& rgbOffset,
                       std::array<ValueHistogram, 3>& histogram);
// One row of the counting sort of labels by value: for each pixel x, in order,
// out[cursor[v]++] = labels[x] where v = values[3 * x] (one channel of the row).
void scatterLabelsByValueReference(const std::uint8_t* values, const std::int32_t* labels, int width,
                                   std::int32_t* cursor, std::int32_t* out);
void scatterLabelsByValue(const std::uint8_t* values, const std::int32_t* labels, int width, std::int32_t* cursor,
                          std::int32_t* out);

}  // namespace stria::pipeline
