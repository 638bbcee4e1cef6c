// Region colour statistics kernel (pipeline/decoder/simd.hpp).
#include "pipeline/decoder/simd.hpp"

#include <algorithm>

#if defined(__ARM_NEON)
#include <arm_neon.h>
#elif defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace stria::pipeline {

std::array<std::uint8_t, 3> channelMediansReference(const std::uint32_t* pixels, int count)
{
    const auto* bytes = reinterpret_cast<const std::uint8_t*>(pixels);
    std::array<std::uint8_t, 3> median{};
    for (int k = 0; k < 3; ++k) {
        std::array<std::int32_t, 256> histogram{};
        for (int i = 0; i < count; ++i) ++histogram[bytes[4 * i + k]];
        int v = 0;
        for (int seen = histogram[0]; seen <= count / 2; seen += histogram[++v]) {}
        median[k] = static_cast<std::uint8_t>(v);
    }
    return median;
}

#if defined(__ARM_NEON) || defined(__SSE2__)
namespace {

// From byte 16 - k on: k lanes of 0xff, then zeros.
alignas(16) constexpr std::uint8_t kLeadingLanes[32] = {255, 255, 255, 255, 255, 255, 255, 255,
                                                       255, 255, 255, 255, 255, 255, 255, 255};

// Per byte k < 3 of the pixels (blocks whole blocks of 4, then the bytes of
// the next block where restLanes is set), how many are below t[k]
// (1 <= t[k] <= 255). blocks <= 254: the per-lane byte counters cannot
// overflow. (The block after the last is read even where restLanes is
// empty.)
#if defined(__ARM_NEON)
using Bytes = uint8x16_t;
inline Bytes loadBytes(const std::uint8_t* p) { return vld1q_u8(p); }

inline std::array<int, 3> countBelow(const std::uint8_t* bytes, int blocks, Bytes restLanes, const std::array<int, 3>& t)
{
    const Bytes limit = vreinterpretq_u8_u32(vdupq_n_u32(static_cast<std::uint32_t>(t[0] | t[1] << 8 | t[2] << 16)));
    Bytes counts = vshrq_n_u8(vandq_u8(vcltq_u8(vld1q_u8(bytes + 16 * blocks), limit), restLanes), 7);
#pragma GCC unroll 2
    for (int b = 0; b < blocks; ++b) counts = vsubq_u8(counts, vcltq_u8(vld1q_u8(bytes + 16 * b), limit));
    // The four pixels' counters of each byte position added.
    const uint16x8_t pairs = vaddl_u8(vget_low_u8(counts), vget_high_u8(counts));
    const uint16x4_t sums = vadd_u16(vget_low_u16(pairs), vget_high_u16(pairs));
    return {vget_lane_u16(sums, 0), vget_lane_u16(sums, 1), vget_lane_u16(sums, 2)};
}

// The whole search in byte lanes, for count <= 255 (a byte position's four
// pixel counters sum to at most count).
inline std::array<std::uint8_t, 3> mediansInBytes(const std::uint8_t* bytes, int blocks, Bytes restLanes, int count)
{
    const Bytes half = vdupq_n_u8(static_cast<std::uint8_t>(count / 2));
    Bytes m = vdupq_n_u8(0), bit = vdupq_n_u8(128);
    for (int pass = 0; pass < 8; ++pass, bit = vshrq_n_u8(bit, 1)) {
        const Bytes limit = vorrq_u8(m, bit);
        Bytes counts = vshrq_n_u8(vandq_u8(vcltq_u8(vld1q_u8(bytes + 16 * blocks), limit), restLanes), 7);
#pragma GCC unroll 2
        for (int b = 0; b < blocks; ++b) counts = vsubq_u8(counts, vcltq_u8(vld1q_u8(bytes + 16 * b), limit));
        // Each byte position's sum over the four pixels, in every pixel's lanes.
        counts = vaddq_u8(counts, vextq_u8(counts, counts, 8));
        counts = vaddq_u8(counts, vextq_u8(counts, counts, 4));
        m = vorrq_u8(m, vandq_u8(bit, vcleq_u8(counts, half)));
    }
    return {vgetq_lane_u8(m, 0), vgetq_lane_u8(m, 1), vgetq_lane_u8(m, 2)};
}
#else
using Bytes = __m128i;
inline Bytes loadBytes(const std::uint8_t* p) { return _mm_loadu_si128(reinterpret_cast<const __m128i*>(p)); }

// x < t as max(x, t - 1) == t - 1 (SSE2 has no unsigned byte comparison).
inline __m128i belowMask(const std::uint8_t* x, __m128i limit)
{
    return _mm_cmpeq_epi8(_mm_max_epu8(loadBytes(x), limit), limit);
}

inline std::array<int, 3> countBelow(const std::uint8_t* bytes, int blocks, Bytes restLanes, const std::array<int, 3>& t)
{
    const __m128i limit = _mm_set1_epi32((t[0] - 1) | (t[1] - 1) << 8 | (t[2] - 1) << 16);
    const __m128i zero = _mm_setzero_si128();
    __m128i counts = _mm_sub_epi8(zero, _mm_and_si128(belowMask(bytes + 16 * blocks, limit), restLanes));
#pragma GCC unroll 2
    for (int b = 0; b < blocks; ++b) counts = _mm_sub_epi8(counts, belowMask(bytes + 16 * b, limit));
    // The four pixels' counters of each byte position added.
    __m128i sums = _mm_add_epi16(_mm_unpacklo_epi8(counts, zero), _mm_unpackhi_epi8(counts, zero));
    sums = _mm_add_epi16(sums, _mm_srli_si128(sums, 8));
    return {_mm_extract_epi16(sums, 0), _mm_extract_epi16(sums, 1), _mm_extract_epi16(sums, 2)};
}

// The whole search in byte lanes, for count <= 255 (a byte position's four
// pixel counters sum to at most count): no per-pass moves between vector
// and scalar registers.
inline std::array<std::uint8_t, 3> mediansInBytes(const std::uint8_t* bytes, int blocks, Bytes restLanes, int count)
{
    const __m128i zero = _mm_setzero_si128(), one = _mm_set1_epi8(1);
    const __m128i half = _mm_set1_epi8(static_cast<char>(count / 2));
    __m128i m = zero, bit = _mm_set1_epi8(static_cast<char>(128));
    // bit >> 1 in 16-bit lanes: no bit crosses into the next byte.
    for (int pass = 0; pass < 8; ++pass, bit = _mm_srli_epi16(bit, 1)) {
        const __m128i limit = _mm_sub_epi8(_mm_or_si128(m, bit), one);
        __m128i counts = _mm_sub_epi8(zero, _mm_and_si128(belowMask(bytes + 16 * blocks, limit), restLanes));
#pragma GCC unroll 2
        for (int b = 0; b < blocks; ++b) counts = _mm_sub_epi8(counts, belowMask(bytes + 16 * b, limit));
        // Each byte position's sum over the four pixels, in every pixel's lanes.
        counts = _mm_add_epi8(counts, _mm_shuffle_epi32(counts, _MM_SHUFFLE(1, 0, 3, 2)));
        counts = _mm_add_epi8(counts, _mm_shuffle_epi32(counts, _MM_SHUFFLE(2, 3, 0, 1)));
        // counts <= count / 2 as min(counts, half) == counts.
        m = _mm_or_si128(m, _mm_and_si128(bit, _mm_cmpeq_epi8(_mm_min_epu8(counts, half), counts)));
    }
    const auto v = static_cast<std::uint32_t>(_mm_cvtsi128_si32(m));
    return {static_cast<std::uint8_t>(v), static_cast<std::uint8_t>(v >> 8), static_cast<std::uint8_t>(v >> 16)};
}
#endif

}  // namespace
#endif

std::array<std::uint8_t, 3> channelMedians(const std::uint32_t* pixels, int count)
{
#if defined(__ARM_NEON) || defined(__SSE2__)
    // The median m = values sorted[count / 2] is the largest t with at most
    // count / 2 values below t: found bit by bit from the top, each step one
    // counting pass over the pixels (4 pixels' 3 channels per compare, no
    // branch per value; a region's ~256 bytes stay in L1 for the 8 passes).
    const int blocks = count / 4;
    const auto* bytes = reinterpret_cast<const std::uint8_t*>(pixels);
    const Bytes restLanes = loadBytes(kLeadingLanes + 16 - 4 * (count - 4 * blocks));
    if (count <= 255) return mediansInBytes(bytes, blocks, restLanes, count);
    // Larger regions: the counts summed in 16 bits per chunk of up to 254
    // blocks (the byte counters' limit), over the chunks in int. (A
    // histogram's increments wait on each other where neighbouring pixels
    // share a value, as in large uniform regions.)
    const Bytes noLanes = loadBytes(kLeadingLanes + 16);
    std::array<int, 3> m{};
    for (int bit = 128; bit > 0; bit >>= 1) {
        const std::array<int, 3> t{m[0] | bit, m[1] | bit, m[2] | bit};
        std::array<int, 3> below{};
        for (int first = 0;; first += 254) {
            const int chunk = std::min(254, blocks - first);
            const bool last = first + chunk == blocks;
            const std::array<int, 3> part = countBelow(bytes + 16 * first, chunk, last ? restLanes : noLanes, t);
            for (int k = 0; k < 3; ++k) below[k] += part[k];
            if (last) break;
        }
        for (int k = 0; k < 3; ++k) m[k] |= below[k] <= count / 2 ? bit : 0;
    }
    return {static_cast<std::uint8_t>(m[0]), static_cast<std::uint8_t>(m[1]), static_cast<std::uint8_t>(m[2])};
#else
    return channelMediansReference(pixels, count);
#endif
}

}  // namespace stria::pipeline
