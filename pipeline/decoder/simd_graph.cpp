// Region graph kernels (pipeline/decoder/simd.hpp).
#include "pipeline/decoder/simd.hpp"

#include <cmath>

#if defined(__ARM_NEON)
#include <arm_neon.h>
#elif defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace stria::pipeline {

std::uint64_t borderMaskReference(const std::int32_t* a, const std::int32_t* b, int count)
{
    std::uint64_t bits = 0;
    for (int i = 0; i < count; ++i)
        if (a[i] != b[i]) bits |= std::uint64_t{1} << i;
    return bits;
}

std::uint64_t borderMask(const std::int32_t* a, const std::int32_t* b, int count)
{
    // 16 labels per step, no branch per pixel (a border every ~6 pixels is
    // unpredictable); the caller walks the set bits.
    std::uint64_t bits = 0;
    int i = 0;
#if defined(__ARM_NEON)
    const uint8x16_t weights = {1, 2, 4, 8, 16, 32, 64, 128, 1, 2, 4, 8, 16, 32, 64, 128};
    auto equal8 = [&](int at) {
        return vcombine_u16(vmovn_u32(vceqq_s32(vld1q_s32(a + at), vld1q_s32(b + at))),
                            vmovn_u32(vceqq_s32(vld1q_s32(a + at + 4), vld1q_s32(b + at + 4))));
    };
    for (; i + 16 <= count; i += 16) {
        const uint8x16_t differ = vbicq_u8(weights, vcombine_u8(vmovn_u16(equal8(i)), vmovn_u16(equal8(i + 8))));
        bits |= std::uint64_t{vaddv_u8(vget_low_u8(differ)) | static_cast<unsigned>(vaddv_u8(vget_high_u8(differ))) << 8}
                << i;
    }
#elif defined(__SSE2__)
    auto equal4 = [&](int at) {
        return _mm_cmpeq_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(a + at)),
                               _mm_loadu_si128(reinterpret_cast<const __m128i*>(b + at)));
    };
    for (; i + 16 <= count; i += 16) {
        // Saturating packs keep the all-ones / zero lanes.
        const __m128i equal = _mm_packs_epi16(_mm_packs_epi32(equal4(i), equal4(i + 4)),
                                              _mm_packs_epi32(equal4(i + 8), equal4(i + 12)));
        bits |= std::uint64_t(~_mm_movemask_epi8(equal) & 0xffff) << i;
    }
#endif
    for (; i < count; ++i) bits |= std::uint64_t{a[i] != b[i]} << i;
    return bits;
}

namespace {

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
    const __m128 px = _mm_set1_ps(primary[0]), py = _mm_set1_ps(primary[1]);
    const __m128 sign = _mm_set1_ps(-0.0f);
    const __m128 along = _mm_andnot_ps(sign, _mm_add_ps(_mm_mul_ps(gx, px), _mm_mul_ps(gy, py)));
    const __m128 across = _mm_andnot_ps(sign, _mm_add_ps(_mm_mul_ps(_mm_xor_ps(gx, sign), py), _mm_mul_ps(gy, px)));
    // {along0, across0, along1, across1} + {along1, across1, ..}, then
    // + {along2, across2, ..}: the reference's sums, channel by channel
    // (0 + a = a for a >= +0).
    const __m128 low = _mm_unpacklo_ps(along, across), high = _mm_unpackhi_ps(along, across);
    const __m128 sum = _mm_add_ps(_mm_add_ps(low, _mm_movehl_ps(low, low)), high);
    PairGradient out;
    _mm_storel_pi(reinterpret_cast<__m64*>(&out), sum);
    return out;
}
#endif

}  // namespace

PairGradient horizontalPairGradient(const std::uint8_t* up, const std::uint8_t* row, const std::uint8_t* down, int x,
                                    const cv::Vec2f& primary)
{
    const int i = 3 * x;
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

PairGradient verticalPairGradient(const std::uint8_t* row, const std::uint8_t* below, int x, const cv::Vec2f& primary)
{
    const int i = 3 * x;
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

}  // namespace stria::pipeline
