// Region colour statistics kernels (pipeline/decoder/simd.hpp).
#include "pipeline/decoder/simd.hpp"

#if defined(__ARM_NEON)
#include <arm_neon.h>
#endif

namespace stria::pipeline {

void channelHistogramsReference(const std::uint8_t* row, int width, const std::array<int, 3>& rgbOffset,
                                std::array<ValueHistogram, 3>& histogram)
{
    for (int x = 0; x < width; ++x)
        for (int c = 0; c < 3; ++c) ++histogram[c][row[3 * x + rgbOffset[c]]];
}

void channelHistograms(const std::uint8_t* row, int width, const std::array<int, 3>& rgbOffset,
                       std::array<ValueHistogram, 3>& histogram)
{
    channelHistogramsReference(row, width, rgbOffset, histogram);
}

void scatterLabelsByValueReference(const std::uint8_t* values, const std::int32_t* labels, int width,
                                   std::int32_t* cursor, std::int32_t* out)
{
    for (int x = 0; x < width; ++x) out[cursor[values[3 * x]]++] = labels[x];
}

void scatterLabelsByValue(const std::uint8_t* values, const std::int32_t* labels, int width, std::int32_t* cursor,
                          std::int32_t* out)
{
    scatterLabelsByValueReference(values, labels, width, cursor, out);
}

}  // namespace stria::pipeline
