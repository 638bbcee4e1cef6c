// The region graph's pair kernels and border masks, inline (internal to the
// decoder: included by graph.cpp, whose border-pair loop calls them per pair
// and per 64 columns, and by simd_graph.cpp, whose horizontalPairGradient /
// verticalPairGradient (simd.hpp, tested against pairGradient) and borderMask
// (tested against borderMaskReference) are these). Inline because a call per
// border pair, with the constants set up again each time, cost 0.015 ms at
// 780x580 and 0.04 ms at 1388x1038.
#pragma once

#include "pipeline/decoder/simd.hpp"

#include <cmath>

#if defined(__ARM_NEON)
#include <arm_neon.h>
#elif defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace stria::pipeline::graph_kernels {

// A pair's terms from its channel differences gx, gy (one of them to be
// quartered, below), per channel, summed over the channels as pairGradient
// does: along = |gx xAlong - gy yAlong| and across = |gy yAcross - gx
// xAcross|. plainWeights gives pairGradient's own floats: its gx px + gy py
// is gx px - gy (-py) and its -gx py + gy px is gy px - gx py (negation is
// exact, and a + (-b) is a - b), as differences so that NEON takes each
// absolute difference in one instruction (fabd).
//
// The folded weights take the 0.25 into the weights of the quartered
// component instead (horizontal pairs: gy's, vertical ones: gx's), a
// multiply less per pair. The same floats where quarterFolds(primary):
// s * 0.25 (s an integer) and p * 0.25 are exact, so (0.25 s) p and
// s (0.25 p) are the one rounding of s p / 4, unless 0.25 p or the product
// is subnormal (|p| < 2^-124, never for a unit direction that is not 0).
struct PairWeights {
    float xAlong, yAlong, xAcross, yAcross;
};
inline PairWeights plainWeights(const cv::Vec2f& primary)
{
    return {primary[0], -primary[1], primary[1], primary[0]};
}
inline PairWeights horizontalFoldedWeights(const cv::Vec2f& primary)
{
    return {primary[0], -0.25f * primary[1], primary[1], 0.25f * primary[0]};
}
inline PairWeights verticalFoldedWeights(const cv::Vec2f& primary)
{
    return {0.25f * primary[0], -primary[1], 0.25f * primary[1], primary[0]};
}
inline bool quarterFolds(const cv::Vec2f& primary)
{
    auto folds = [](float p) { return p == 0 || !(std::abs(p) < 0x1p-124f); };  // NaN: NaN either way
    return folds(primary[0]) && folds(primary[1]);
}

// The kernels take 8 bytes from each row (two pixels and two bytes), widen
// them to int16 lanes, form the reference's integer differences (exact), and
// only then convert the lanes of pixel x's three channels to float.
#if defined(__ARM_NEON)
using Int16s = int16x8_t;
using Floats = float32x4_t;
inline Int16s nextPixel(Int16s v) { return vextq_s16(v, v, 3); }  // lanes 3.. to 0..
inline Int16s plus(Int16s a, Int16s b) { return vaddq_s16(a, b); }
inline Int16s minus(Int16s a, Int16s b) { return vsubq_s16(a, b); }
inline Floats firstPixel(Int16s v) { return vcvtq_f32_s32(vmovl_s16(vget_low_s16(v))); }
inline Floats quarter(Floats v) { return vmulq_n_f32(v, 0.25f); }
// firstPixel(plus(a, b)) and firstPixel(minus(a, b)) by one widening add or
// subtract (saddl, ssubl) of the low halves, where the int16 add and the
// widening took two: the same exact integers (int16 sums of bytes' sums and
// differences do not wrap).
inline Floats firstPixelOfSum(Int16s a, Int16s b) { return vcvtq_f32_s32(vaddl_s16(vget_low_s16(a), vget_low_s16(b))); }
inline Floats firstPixelOfDifference(Int16s a, Int16s b)
{
    return vcvtq_f32_s32(vsubl_s16(vget_low_s16(a), vget_low_s16(b)));
}
// Two rows' 8 bytes' differences and sums, and the next pixel's bytes less
// these, by the widening forms (usubl, uaddl: one instruction, where
// widening each operand first took two more); reinterpreted as int16, the
// same exact values (|difference| <= 255, sum <= 510).
inline Int16s difference8(const std::uint8_t* a, const std::uint8_t* b)
{
    return vreinterpretq_s16_u16(vsubl_u8(vld1_u8(a), vld1_u8(b)));
}
inline Int16s sum8(const std::uint8_t* a, const std::uint8_t* b)
{
    return vreinterpretq_s16_u16(vaddl_u8(vld1_u8(a), vld1_u8(b)));
}
inline Int16s nextPixelDifference(const std::uint8_t* p)
{
    const uint8x8_t bytes = vld1_u8(p);
    return vreinterpretq_s16_u16(vsubl_u8(vext_u8(bytes, bytes, 3), bytes));  // lanes 0-4: bytes 3-7 less 0-4
}
inline PairGradient pairTerms(Floats gx, Floats gy, const PairWeights& w)
{
#if defined(__aarch64__)
    // The weights with lane 3 (the next pixel's first channel) 0: both
    // products there are +-0 (gx, gy are small integers), and so the terms
    // +0 (fabd's absolute value). Then two pairwise adds give the
    // reference's sums: {along0 + along1, along2 + 0, across0 + across1,
    // across2 + 0}, then lanes 0 + 1 and 2 + 3, where a2 + 0 is a2 (a2 >=
    // +0, or a NaN that stays): (a0 + a1) + a2 as the reference adds them.
    // The weight vectors are loop invariants (set up once per loop); 2
    // instructions where the zip, the lane move and two adds below took 5.
    auto weights = [](float v) { return vsetq_lane_f32(0.0f, vdupq_n_f32(v), 3); };
    const Floats along = vabdq_f32(vmulq_f32(gx, weights(w.xAlong)), vmulq_f32(gy, weights(w.yAlong)));
    const Floats across = vabdq_f32(vmulq_f32(gy, weights(w.yAcross)), vmulq_f32(gx, weights(w.xAcross)));
    const Floats pairs = vpaddq_f32(along, across);
    const float32x2_t sum = vget_low_f32(vpaddq_f32(pairs, pairs));
    return {vget_lane_f32(sum, 0), vget_lane_f32(sum, 1)};
#else
    const Floats along = vabdq_f32(vmulq_n_f32(gx, w.xAlong), vmulq_n_f32(gy, w.yAlong));
    const Floats across = vabdq_f32(vmulq_n_f32(gy, w.yAcross), vmulq_n_f32(gx, w.xAcross));
    // The reference's sums, channel by channel (0 + a = a for a >= +0), for
    // both terms in the lanes of one pair: {along0, across0} + {along1,
    // across1}, then + {along2, across2}, from a zip of the two (lane by
    // lane extracts and scalar adds took 9 instructions).
    const float32x4x2_t zipped = vzipq_f32(along, across);
    const float32x2_t sum = vadd_f32(vadd_f32(vget_low_f32(zipped.val[0]), vget_high_f32(zipped.val[0])),
                                     vget_low_f32(zipped.val[1]));
    return {vget_lane_f32(sum, 0), vget_lane_f32(sum, 1)};
#endif
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
inline Floats firstPixelOfSum(Int16s a, Int16s b) { return firstPixel(plus(a, b)); }
inline Floats firstPixelOfDifference(Int16s a, Int16s b) { return firstPixel(minus(a, b)); }
inline Int16s difference8(const std::uint8_t* a, const std::uint8_t* b) { return minus(bytes8(a), bytes8(b)); }
inline Int16s sum8(const std::uint8_t* a, const std::uint8_t* b) { return plus(bytes8(a), bytes8(b)); }
inline Int16s nextPixelDifference(const std::uint8_t* p)
{
    const Int16s here = bytes8(p);
    return minus(nextPixel(here), here);
}
inline PairGradient pairTerms(Floats gx, Floats gy, const PairWeights& w)
{
    // |v| as v & 0x7fffffff (andps takes its operands in either order, andnps
    // needed a copy of the sign mask): fewer instructions, the same bits.
    // The differences as sums with a negated weight (addps takes its
    // operands in either order, subps needed copies: the same floats).
    const __m128 xAlong = _mm_set1_ps(w.xAlong), minusYAlong = _mm_set1_ps(-w.yAlong);
    const __m128 minusXAcross = _mm_set1_ps(-w.xAcross), yAcross = _mm_set1_ps(w.yAcross);
    const __m128 magnitude = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
    const __m128 along = _mm_and_ps(_mm_add_ps(_mm_mul_ps(gx, xAlong), _mm_mul_ps(gy, minusYAlong)), magnitude);
    const __m128 across = _mm_and_ps(_mm_add_ps(_mm_mul_ps(gx, minusXAcross), _mm_mul_ps(gy, yAcross)), magnitude);
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

// borderMask (simd.hpp): inline, so that the graph's vertical border loop
// (graph.cpp) takes it without a call per 64 columns and its constants set up
// again each time; the out-of-line borderMask, which the tests compare with
// borderMaskReference, is this.
[[gnu::always_inline]] inline std::uint64_t borderMask(const std::int32_t* a, const std::int32_t* b, int count)
{
    // 16 labels per step, no branch per pixel (a border every ~6 pixels is
    // unpredictable); the caller walks the set bits. A whole word (most
    // calls) in four steps with constant shifts; a shorter one in steps and
    // a last step of the 16 labels ending at count, which overlaps the step
    // before (the same bits again) instead of a label by label tail.
    // 32-bit ARM (armv7-a NEON) has none of uzp1, addv and byteMask64's
    // AArch64 instructions: it takes the label by label loop.
#if defined(__aarch64__) || defined(__SSE2__)
#if defined(__aarch64__)
    const uint8x16_t weights = {1, 2, 4, 8, 16, 32, 64, 128, 1, 2, 4, 8, 16, 32, 64, 128};
    // 16 labels' comparisons as bytes (0xff: equal): the low bytes of the
    // 32-bit masks gathered by three uzp1 (even elements), in order (the
    // narrowing moves took 6 instructions).
    auto equal16 = [&](int at) {
        auto equal4 = [&](int i) { return vreinterpretq_u16_u32(vceqq_s32(vld1q_s32(a + i), vld1q_s32(b + i))); };
        const uint16x8_t low = vuzp1q_u16(equal4(at), equal4(at + 4));
        const uint16x8_t high = vuzp1q_u16(equal4(at + 8), equal4(at + 12));
        return vuzp1q_u8(vreinterpretq_u8_u16(low), vreinterpretq_u8_u16(high));
    };
    auto differ16 = [&](int at) -> std::uint64_t {
        const uint8x16_t differ = vbicq_u8(weights, equal16(at));
        return vaddv_u8(vget_low_u8(differ)) | static_cast<unsigned>(vaddv_u8(vget_high_u8(differ))) << 8;
    };
    // A whole word by byteMask64 (simd.hpp) of the 64 labels' differences.
    auto differ64 = [&]() -> std::uint64_t {
        return byteMask64(vmvnq_u8(equal16(0)), vmvnq_u8(equal16(16)), vmvnq_u8(equal16(32)), vmvnq_u8(equal16(48)));
    };
#else
    auto equal4 = [&](int at) {
        return _mm_cmpeq_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(a + at)),
                               _mm_loadu_si128(reinterpret_cast<const __m128i*>(b + at)));
    };
    // 16 labels' equalities as bits (saturating packs keep the all-ones /
    // zero lanes).
    auto equal16 = [&](int at) -> std::uint64_t {
        const __m128i equal = _mm_packs_epi16(_mm_packs_epi32(equal4(at), equal4(at + 4)),
                                              _mm_packs_epi32(equal4(at + 8), equal4(at + 12)));
        return static_cast<unsigned>(_mm_movemask_epi8(equal));
    };
    auto differ16 = [&](int at) -> std::uint64_t { return ~equal16(at) & 0xffff; };
    // A whole word's equalities inverted once (the 16 bits' masks
    // zero-extended: no masking each).
    auto differ64 = [&]() -> std::uint64_t {
        return ~(equal16(0) | equal16(16) << 16 | equal16(32) << 32 | equal16(48) << 48);
    };
#endif
    if (count == 64) return differ64();
    if (count >= 16) {
        std::uint64_t bits = 0;
        int i = 0;
        for (; i + 16 <= count; i += 16) bits |= differ16(i) << i;
        if (i < count) bits |= differ16(count - 16) << (count - 16);
        return bits;
    }
#endif
    std::uint64_t bits = 0;
    for (int i = 0; i < count; ++i) bits |= std::uint64_t{a[i] != b[i]} << i;
    return bits;
}

// kFolded: w are the folded weights (horizontalFoldedWeights /
// verticalFoldedWeights), else plainWeights and the quarter taken here.
template <bool kFolded = false>
inline PairGradient horizontalPair(const std::uint8_t* up, const std::uint8_t* row, const std::uint8_t* down,
                                   std::size_t x, const PairWeights& w)
{
    const std::size_t i = 3 * x;
#if defined(__ARM_NEON) || defined(__SSE2__)
    const Int16s vertical = difference8(down + i, up + i);
    const Floats gy = firstPixelOfSum(vertical, nextPixel(vertical));
    return pairTerms(firstPixel(nextPixelDifference(row + i)), kFolded ? gy : quarter(gy), w);
#else
    PairGradient out;
    for (int c = 0; c < 3; ++c) {
        const float gx = static_cast<float>(row[i + 3 + c] - row[i + c]);
        const float sy = static_cast<float>(down[i + c] - up[i + c] + down[i + 3 + c] - up[i + 3 + c]);
        const float gy = kFolded ? sy : 0.25f * sy;
        out.primary += std::abs(gx * w.xAlong - gy * w.yAlong);
        out.secondary += std::abs(gy * w.yAcross - gx * w.xAcross);
    }
    return out;
#endif
}

template <bool kFolded = false>
inline PairGradient verticalPair(const std::uint8_t* row, const std::uint8_t* below, std::size_t x,
                                 const PairWeights& w)
{
    const std::size_t i = 3 * x;
#if defined(__ARM_NEON) || defined(__SSE2__)
    // The two rows' sums first (exact in int16): one shift of a pixel less.
    const Floats gx = firstPixelOfDifference(nextPixel(sum8(row + i, below + i)), sum8(row + i - 3, below + i - 3));
    return pairTerms(kFolded ? gx : quarter(gx), firstPixel(difference8(below + i, row + i)), w);
#else
    PairGradient out;
    for (int c = 0; c < 3; ++c) {
        const float gy = static_cast<float>(below[i + c] - row[i + c]);
        const float sx =
            static_cast<float>(row[i + 3 + c] - row[i - 3 + c] + below[i + 3 + c] - below[i - 3 + c]);
        const float gx = kFolded ? sx : 0.25f * sx;
        out.primary += std::abs(gx * w.xAlong - gy * w.yAlong);
        out.secondary += std::abs(gy * w.yAcross - gx * w.xAcross);
    }
    return out;
#endif
}

}  // namespace stria::pipeline::graph_kernels
