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

namespace {

// The reference's loops with the offsets in registers and the counts known
// not to alias the row (the reference reloads both after every increment).
void channelHistogramsScalar(const std::uint8_t* row, int width, const std::array<int, 3>& rgbOffset,
                             std::array<ValueHistogram, 3>& histogram)
{
    const std::uint8_t* __restrict r = row + rgbOffset[0];
    const std::uint8_t* __restrict g = row + rgbOffset[1];
    const std::uint8_t* __restrict b = row + rgbOffset[2];
    std::int32_t* __restrict hr = histogram[0].data();
    std::int32_t* __restrict hg = histogram[1].data();
    std::int32_t* __restrict hb = histogram[2].data();
    for (int x = 0; x < width; ++x) {
        ++hr[r[3 * x]];
        ++hg[g[3 * x]];
        ++hb[b[3 * x]];
    }
}

}  // namespace

void channelHistograms(const std::uint8_t* row, int width, const std::array<int, 3>& rgbOffset,
                       std::array<ValueHistogram, 3>& histogram)
{
    int x = 0;
#if defined(__ARM_NEON)
    // vld3 de-interleaves 16 pixels into byte planes; the counting itself
    // stays scalar (a histogram has no vector form), but from unit-stride
    // planes without per-pixel offset arithmetic.
    std::array<ValueHistogram*, 3> byByte;
    for (int c = 0; c < 3; ++c) byByte[rgbOffset[c]] = &histogram[c];
    alignas(16) std::uint8_t planes[3][16];
    for (; x + 16 <= width; x += 16) {
        const uint8x16x3_t v = vld3q_u8(row + 3 * x);
        for (int k = 0; k < 3; ++k) vst1q_u8(planes[k], v.val[k]);
        for (int k = 0; k < 3; ++k)
            for (int i = 0; i < 16; ++i) ++(*byByte[k])[planes[k][i]];
    }
#endif
    channelHistogramsScalar(row + 3 * x, width - x, rgbOffset, histogram);
}

void scatterLabelsByValueReference(const std::uint8_t* values, const std::int32_t* labels, int width,
                                   std::int32_t* cursor, std::int32_t* out)
{
    for (int x = 0; x < width; ++x) out[cursor[values[3 * x]]++] = labels[x];
}

void scatterLabelsByValue(const std::uint8_t* values, const std::int32_t* labels, int width, std::int32_t* cursor,
                          std::int32_t* out)
{
    int x = 0;
#if defined(__ARM_NEON)
    // vld3 picks the channel's 16 values (plane 0 of the de-interleaved
    // bytes from `values`); its 48 bytes end at values[3 * x + 47], within
    // the row while x + 17 <= width. The scatter stays scalar.
    alignas(16) std::uint8_t plane[16];
    for (; x + 17 <= width; x += 16) {
        vst1q_u8(plane, vld3q_u8(values + 3 * x).val[0]);
        for (int i = 0; i < 16; ++i) out[cursor[plane[i]]++] = labels[x + i];
    }
#endif
    // __restrict: otherwise every store to out could change the cursors.
    const std::uint8_t* __restrict v = values;
    const std::int32_t* __restrict l = labels;
    std::int32_t* __restrict c = cursor;
    std::int32_t* __restrict o = out;
#pragma GCC unroll 4
    for (; x < width; ++x) o[c[v[3 * x]]++] = l[x];
}

}  // namespace stria::pipeline
