// The region graph's pair kernels, inline (internal to the decoder: included
// by graph.cpp, whose border-pair loop calls them per pair, and by
// simd_graph.cpp, whose horizontalPairGradient / verticalPairGradient
// (simd.hpp, tested against pairGradient) are these). Inline because a call
// per border pair, with the constants set up again each time, cost 0.015 ms
// at 780x580 and 0.04 ms at 1388x1038.
#pragma once

#include "pipeline/decoder/simd.hpp"

#include <cmath>

#if defined(__ARM_NEON)
#include <arm_neon.h>
#elif defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace stria::pipeline::graph_kernels {

// The kernels take 8 bytes from each row (two pixels and two bytes), widen
// them to int16 lanes, form the reference's integer differences (exact), and
// only then convert the lanes of pixel x's three channels to float.
#if defined(__ARM_NEON)
using Int16s = int16x8_t;
using Floats = float32x4_t;
inline Int16s bytes8(const std::uint8_t* p) { return vreinterpretq_s16_u16(vmovl_u8(vld1_u8(p))); }
inline Int16s nextPixel(Int16s v) { return vextq_s16(v, v, 3); }  // lanes 3.. to 0..
inline Int16s plus(Int16s a, Int16s b) { return vaddq_s16(a, b); }
inline Int16s minus(Int16s a, Int16s b) { return vsubq_s16(a, b); }
inline Floats firstPixel(Int16s v) { return vcvtq_f32_s32(vmovl_s16(vget_low_s16(v))); }
inline Floats quarter(Floats v) { return vmulq_n_f32(v, 0.25f); }
inline PairGradient pairTerms(Floats gx, Floats gy, const cv::Vec2f& primary)
{
    const float px = primary[0], py = primary[1];
    const Floats along = vabsq_f32(vaddq_f32(vmulq_n_f32(gx, px), vmulq_n_f32(gy, py)));
    const Floats across = vabsq_f32(vaddq_f32(vmulq_n_f32(vnegq_f32(gx), py), vmulq_n_f32(gy, px)));
    // The reference's sums, channel by channel (0 + a = a for a >= +0).
    return {(vgetq_lane_f32(along, 0) + vgetq_lane_f32(along, 1)) + vgetq_lane_f32(along, 2),
            (vgetq_lane_f32(across, 0) + vgetq_lane_f32(across, 1)) + vgetq_lane_f32(across, 2)};
}
#elif defined(__SSE2__)
using Int16s = __m128i;
using Floats = __m128;
inline Int16s bytes8(const std::uint8_t* p)
{
    return _mm_unpacklo_epi8(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p)), _mm_setzero_si128());
}
inline Int16s nextPixel(Int16s v) { return _mm_srli_si128(v, 6); }
inline Int16s plus(Int16s a, Int16s b) { return _mm_add_epi16(a, b); }
inline Int16s minus(Int16s a, Int16s b) { return _mm_sub_epi16(a, b); }
inline Floats firstPixel(Int16s v) { return _mm_cvtepi32_ps(_mm_srai_epi32(_mm_unpacklo_epi16(v, v), 16)); }
inline Floats quarter(Floats v) { return _mm_mul_ps(v, _mm_set1_ps(0.25f)); }
inline PairGradient pairTerms(Floats gx, Floats gy, const cv::Vec2f& primary)
{
    // -gx * py as gx * -py (the same float: rounding is symmetric), and |v|
    // as v & 0x7fffffff (andps takes its operands in either order, andnps
    // needed a copy of the sign mask): fewer instructions, the same bits.
    const __m128 px = _mm_set1_ps(primary[0]), py = _mm_set1_ps(primary[1]), minusPy = _mm_set1_ps(-primary[1]);
    const __m128 magnitude = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
    const __m128 along = _mm_and_ps(_mm_add_ps(_mm_mul_ps(gx, px), _mm_mul_ps(gy, py)), magnitude);
    const __m128 across = _mm_and_ps(_mm_add_ps(_mm_mul_ps(gx, minusPy), _mm_mul_ps(gy, px)), magnitude);
    // {along0, across0, along1, across1} + {along1, across1, ..}, then
    // + {along2, across2, ..}: the reference's sums, channel by channel
    // (0 + a = a for a >= +0). The upper half by pshufd, which needs no copy.
    const __m128 low = _mm_unpacklo_ps(along, across), high = _mm_unpackhi_ps(along, across);
    const __m128 lowUpper = _mm_castsi128_ps(_mm_shuffle_epi32(_mm_castps_si128(low), _MM_SHUFFLE(3, 2, 3, 2)));
    const __m128 sum = _mm_add_ps(_mm_add_ps(low, lowUpper), high);
    // Out of the register lane by lane: a 64-bit store and a 32-bit reload
    // of its upper half (the edge's update) stalled on store forwarding.
    return {_mm_cvtss_f32(sum), _mm_cvtss_f32(_mm_shuffle_ps(sum, sum, _MM_SHUFFLE(1, 1, 1, 1)))};
}
#endif


inline PairGradient horizontalPair(const std::uint8_t* up, const std::uint8_t* row, const std::uint8_t* down,
                                   std::size_t x, const cv::Vec2f& primary)
{
    const std::size_t i = 3 * x;
#if defined(__ARM_NEON) || defined(__SSE2__)
    const Int16s here = bytes8(row + i), vertical = minus(bytes8(down + i), bytes8(up + i));
    return pairTerms(firstPixel(minus(nextPixel(here), here)), quarter(firstPixel(plus(vertical, nextPixel(vertical)))),
                     primary);
#else
    PairGradient out;
    for (int c = 0; c < 3; ++c) {
        const float gx = static_cast<float>(row[i + 3 + c] - row[i + c]);
        const float gy = 0.25f * static_cast<float>(down[i + c] - up[i + c] + down[i + 3 + c] - up[i + 3 + c]);
        out.primary += std::abs(gx * primary[0] + gy * primary[1]);
        out.secondary += std::abs(-gx * primary[1] + gy * primary[0]);
    }
    return out;
#endif
}

inline PairGradient verticalPair(const std::uint8_t* row, const std::uint8_t* below, std::size_t x,
                                 const cv::Vec2f& primary)
{
    const std::size_t i = 3 * x;
#if defined(__ARM_NEON) || defined(__SSE2__)
    const Int16s here = bytes8(row + i), hereBelow = bytes8(below + i);
    const Int16s across =
        plus(minus(nextPixel(here), bytes8(row + i - 3)), minus(nextPixel(hereBelow), bytes8(below + i - 3)));
    return pairTerms(quarter(firstPixel(across)), firstPixel(minus(hereBelow, here)), primary);
#else
    PairGradient out;
    for (int c = 0; c < 3; ++c) {
        const float gy = static_cast<float>(below[i + c] - row[i + c]);
        const float gx =
            0.25f * static_cast<float>(row[i + 3 + c] - row[i - 3 + c] + below[i + 3 + c] - below[i - 3 + c]);
        out.primary += std::abs(gx * primary[0] + gy * primary[1]);
        out.secondary += std::abs(-gx * primary[1] + gy * primary[0]);
    }
    return out;
#endif
}

}  // namespace stria::pipeline::graph_kernels
