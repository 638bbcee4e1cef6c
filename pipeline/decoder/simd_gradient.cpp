// Gradient row kernels (pipeline/decoder/simd.hpp).
#include "pipeline/decoder/simd.hpp"

#include <algorithm>
#include <cstdlib>
#include <type_traits>
#include <utility>

#if defined(__ARM_NEON)
#include <arm_neon.h>
#elif defined(__SSE2__)
#include <immintrin.h>
#endif

namespace stria::pipeline {
namespace {

// Pixel x with its neighbours' columns clamped to the row.
inline void gradientPixel(const std::uint8_t* up, const std::uint8_t* row, const std::uint8_t* down, int width,
                          bool alongY, int x, std::uint8_t* magnitude, AlongCounts& alongCounts)
{
    const int left = 3 * std::max(x - 1, 0), right = 3 * std::min(x + 1, width - 1), here = 3 * x;
    int best = 0, bestAlong = 0;
    for (int c = 0; c < 3; ++c) {
        // Sobel: central differences smoothed 1-2-1 across, /4.
        const int gx = std::abs(up[right + c] - up[left + c] + 2 * (row[right + c] - row[left + c]) +
                                down[right + c] - down[left + c]) / 4;
        const int gy = std::abs(down[left + c] - up[left + c] + 2 * (down[here + c] - up[here + c]) +
                                down[right + c] - up[right + c]) / 4;
        best = std::max(best, gx + gy);
        bestAlong = std::max(bestAlong, alongY ? gy : gx);
    }
    // best <= 510 and bestAlong <= 255.
    magnitude[x] = static_cast<std::uint8_t>((best + 1) / 2);
    ++alongCounts[x & 3][bestAlong];
}

#if defined(__ARM_NEON)
// AArch64's *_high_* forms (one instruction on the upper halves); 32-bit NEON
// (armv7-a) has none, so there the upper halves are taken by vget_high_u8 and
// the narrowed halves joined by vcombine.
[[gnu::always_inline]] inline uint16x8_t addlHigh(uint8x16_t a, uint8x16_t b)
{
#if defined(__aarch64__)
    return vaddl_high_u8(a, b);
#else
    return vaddl_u8(vget_high_u8(a), vget_high_u8(b));
#endif
}

[[gnu::always_inline]] inline uint16x8_t mlalHigh(uint16x8_t sum, uint8x16_t a, uint8x16_t b)
{
#if defined(__aarch64__)
    return vmlal_high_u8(sum, a, b);
#else
    return vmlal_u8(sum, vget_high_u8(a), vget_high_u8(b));
#endif
}

// (low + 1) / 2 and (high + 1) / 2 narrowed into one vector.
[[gnu::always_inline]] inline uint8x16_t halveRoundedNarrow(uint16x8_t low, uint16x8_t high)
{
#if defined(__aarch64__)
    return vrshrn_high_n_u16(vrshrn_n_u16(low, 1), high, 1);
#else
    return vcombine_u8(vrshrn_n_u16(low, 1), vrshrn_n_u16(high, 1));
#endif
}

// 16 pixels from x: the three channels de-interleaved by vld3. Pixels x +
// from to x + 15 are counted in the histogram (from > 0: a row's last block,
// over pixels done already).
inline void gradient16(const std::uint8_t* up, const std::uint8_t* row, const std::uint8_t* down, bool alongY, int x,
                       std::uint8_t* magnitude, AlongCounts& alongCounts, int from = 0)
{
    const uint8x16x3_t ul = vld3q_u8(up + 3 * (x - 1)), uh = vld3q_u8(up + 3 * x), ur = vld3q_u8(up + 3 * (x + 1));
    const uint8x16x3_t rl = vld3q_u8(row + 3 * (x - 1)), rr = vld3q_u8(row + 3 * (x + 1));
    const uint8x16x3_t dl = vld3q_u8(down + 3 * (x - 1)), dh = vld3q_u8(down + 3 * x),
                       dr = vld3q_u8(down + 3 * (x + 1));
    uint16x8_t best[2] = {vdupq_n_u16(0), vdupq_n_u16(0)}, bestAlong[2] = {vdupq_n_u16(0), vdupq_n_u16(0)};
    // Each Sobel sum's absolute value as the absolute difference (uabd) of
    // two smoothed columns (or rows), a + 2 b + c <= 1020 by uaddl and umlal
    // in uint16 lanes (5 instructions per 8 lanes; 3 differences, 2 adds, a
    // shift and the absolute value took 7).
    const uint8x16_t two = vdupq_n_u8(2);
    const uint8x8_t twoLow = vget_low_u8(two);
    auto sobelLow = [&](uint8x16_t a1, uint8x16_t b1, uint8x16_t c1, uint8x16_t a0, uint8x16_t b0, uint8x16_t c0) {
        const uint16x8_t plus = vmlal_u8(vaddl_u8(vget_low_u8(a1), vget_low_u8(c1)), vget_low_u8(b1), twoLow);
        const uint16x8_t minus = vmlal_u8(vaddl_u8(vget_low_u8(a0), vget_low_u8(c0)), vget_low_u8(b0), twoLow);
        return vabdq_u16(plus, minus);
    };
    auto sobelHigh = [&](uint8x16_t a1, uint8x16_t b1, uint8x16_t c1, uint8x16_t a0, uint8x16_t b0, uint8x16_t c0) {
        const uint16x8_t plus = mlalHigh(addlHigh(a1, c1), b1, two);
        const uint16x8_t minus = mlalHigh(addlHigh(a0, c0), b0, two);
        return vabdq_u16(plus, minus);
    };
    for (int c = 0; c < 3; ++c) {
        const uint16x8_t hx[2] = {sobelLow(ur.val[c], rr.val[c], dr.val[c], ul.val[c], rl.val[c], dl.val[c]),
                                 sobelHigh(ur.val[c], rr.val[c], dr.val[c], ul.val[c], rl.val[c], dl.val[c])};
        const uint16x8_t vy[2] = {sobelLow(dl.val[c], dh.val[c], dr.val[c], ul.val[c], uh.val[c], ur.val[c]),
                                 sobelHigh(dl.val[c], dh.val[c], dr.val[c], ul.val[c], uh.val[c], ur.val[c])};
        for (int half = 0; half < 2; ++half) {
            const uint16x8_t gx = vshrq_n_u16(hx[half], 2);
            const uint16x8_t gy = vshrq_n_u16(vy[half], 2);
            best[half] = vmaxq_u16(best[half], vaddq_u16(gx, gy));
            bestAlong[half] = vmaxq_u16(bestAlong[half], alongY ? gy : gx);
        }
    }
    // (best + 1) / 2 <= 255 narrowed by rounding shifts (rshrn: one
    // instruction per 8 lanes).
    vst1q_u8(magnitude + x, halveRoundedNarrow(best[0], best[1]));
    std::uint8_t along[16];
    vst1q_u8(along, vcombine_u8(vmovn_u16(bestAlong[0]), vmovn_u16(bestAlong[1])));
    for (int k = from; k < 16; ++k) ++alongCounts[(x + k) & 3][along[k]];
}
#elif defined(__SSE2__)
// The maximum over the three channels of 16 pixels of interleaved bytes
// (SSE2: no byte shuffle; the AVX versions take channelOf, below): each round
// interleaves the low halves of (a, high half of b), (high half of a, c), (b,
// high half of c); after 4 rounds a vector holds one channel (the
// de-interleave of OpenCV's SSE2 v_load_deinterleave).
inline __m128i channelMax(__m128i a, __m128i b, __m128i c)
{
    for (int round = 0; round < 4; ++round) {
        const __m128i na = _mm_unpacklo_epi8(a, _mm_unpackhi_epi64(b, b));
        const __m128i nb = _mm_unpacklo_epi8(_mm_unpackhi_epi64(a, a), c);
        const __m128i nc = _mm_unpacklo_epi8(b, _mm_unpackhi_epi64(c, c));
        a = na, b = nb, c = nc;
    }
    return _mm_max_epu8(_mm_max_epu8(a, b), c);
}

inline __m128i load8(const std::uint8_t* p)
{
    return _mm_loadu_si128(reinterpret_cast<const __m128i*>(p));
}

inline __m128i load16(const std::int16_t* p)
{
    return _mm_loadu_si128(reinterpret_cast<const __m128i*>(p));
}

inline void store16(std::int16_t* p, __m128i v)
{
    _mm_storeu_si128(reinterpret_cast<__m128i*>(p), v);
}

// The sums of gradientRow's first loop for 16 byte lanes, in int16 lanes
// widened by vpmovzxbw (SSE2: by unpacks, in two halves). Not always_inline:
// its AVX2 intrinsics could not be inlined into gradientRowBody, compiled
// for the baseline; the AVX versions inline it (flatten).
[[gnu::target("avx2")]] inline void smoothVertical16(const std::uint8_t* up, const std::uint8_t* row,
                                                     const std::uint8_t* down, std::int16_t* smooth,
                                                     std::int16_t* vertical)
{
    const __m256i u = _mm256_cvtepu8_epi16(load8(up)), r = _mm256_cvtepu8_epi16(load8(row)),
                  d = _mm256_cvtepu8_epi16(load8(down));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(smooth),
                        _mm256_add_epi16(_mm256_add_epi16(u, d), _mm256_add_epi16(r, r)));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(vertical), _mm256_sub_epi16(d, u));
}

// The AVX versions' 16-pixel blocks (gradientRow's block, below; not
// always_inline, as smoothVertical16): lanes16 in one register of 16 int16
// lanes (two of 8 in SSE2), packed into [magnitude halves | along] bytes;
// then the maximum over the channels of both at once, in 32 byte lanes, by
// channelOf (3 instructions per channel, where channelMax's rounds took 8
// per 16 bytes). A block 139 -> 94 instructions.
// (Constants in 32-byte vectors, for the AVX versions only.)
#pragma GCC diagnostic ignored "-Wpsabi"
using Bytes32 = std::int8_t __attribute__((vector_size(32)));

// Byte j: -1 where byte j % 16 of source k holds channel ch (a, b, c: k = 0,
// 1, 2), else 0; byte p: the index of pixel p % 16's channel ch in 16 bytes
// of channel ch (channelOf, below).
template <int ch, int k, int... j>
consteval Bytes32 sourceMask(std::integer_sequence<int, j...>)
{
    return Bytes32{static_cast<std::int8_t>(((ch - j % 16) % 3 + 3) % 3 == k ? -1 : 0)...};
}

template <int ch, int... p>
consteval Bytes32 pixelOrder(std::integer_sequence<int, p...>)
{
    return Bytes32{static_cast<std::int8_t>((3 * (p % 16) + ch) % 16)...};
}

template <bool alongY>
[[gnu::target("avx2")]] inline __m256i lanes16Avx2(const std::int16_t* smooth, const std::int16_t* vertical, int i)
{
    // (No lambdas: they would not take the target.)
    const __m256i dx = _mm256_sub_epi16(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(smooth + i + 3)),
                                        _mm256_loadu_si256(reinterpret_cast<const __m256i*>(smooth + i - 3)));
    const __m256i v = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(vertical + i));
    const __m256i dy =
        _mm256_add_epi16(_mm256_add_epi16(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(vertical + i - 3)),
                                          _mm256_loadu_si256(reinterpret_cast<const __m256i*>(vertical + i + 3))),
                         _mm256_add_epi16(v, v));
    const __m256i gx = _mm256_srli_epi16(_mm256_abs_epi16(dx), 2), gy = _mm256_srli_epi16(_mm256_abs_epi16(dy), 2);
    // Quadwords: halves of lanes 0-7, along of 0-7, halves of 8-15, along
    // of 8-15; reordered 0, 2, 1, 3.
    const __m256i packed = _mm256_packus_epi16(_mm256_avg_epu16(gx, gy), alongY ? gy : gx);
    return _mm256_permute4x64_epi64(packed, 0xd8);
}

// Channel ch of 16 pixels of interleaved bytes a, b, c, in pixel order (in
// each 16-byte half, the two halves alike): byte j of a, b and c is byte j,
// 16 + j and 32 + j of the 48, of three different channels (16 = 1 mod 3),
// so two blends (vpblendvb) gather the channel's 16 bytes into one vector
// and one byte shuffle (vpshufb) puts them in pixel order.
template <int ch>
[[gnu::target("avx2")]] inline __m256i channelOf(__m256i a, __m256i b, __m256i c)
{
    constexpr auto j = std::make_integer_sequence<int, 32>();
    const __m256i ab = _mm256_blendv_epi8(a, b, reinterpret_cast<__m256i>(sourceMask<ch, 1>(j)));
    const __m256i abc = _mm256_blendv_epi8(ab, c, reinterpret_cast<__m256i>(sourceMask<ch, 2>(j)));
    return _mm256_shuffle_epi8(abc, reinterpret_cast<__m256i>(pixelOrder<ch>(j)));
}

template <bool alongY>
[[gnu::target("avx2")]] inline void block16Avx2(const std::int16_t* smooth, const std::int16_t* vertical, int x,
                                                std::uint8_t* magnitude, std::uint8_t* along)
{
    const __m256i a = lanes16Avx2<alongY>(smooth, vertical, 3 * x),
                  b = lanes16Avx2<alongY>(smooth, vertical, 3 * x + 16),
                  c = lanes16Avx2<alongY>(smooth, vertical, 3 * x + 32);
    const __m256i m =
        _mm256_max_epu8(_mm256_max_epu8(channelOf<0>(a, b, c), channelOf<1>(a, b, c)), channelOf<2>(a, b, c));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(magnitude + x), _mm256_castsi256_si128(m));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(along), _mm256_extracti128_si256(m, 1));
}

// |v| / 4 of 8 int16 lanes (|v| <= 1020), in the SSE2 version. As a GCC
// vector expression, not intrinsics: SSE2 has no pabsw (GCC makes a
// subtraction from 0 and a pmaxsw); compiled for AVX it is one vpabsw (the
// AVX versions take lanes16Avx2's).
inline __m128i absQuarter(__m128i v)
{
    using Int16x8 = std::int16_t __attribute__((vector_size(16)));
    const Int16x8 w = reinterpret_cast<Int16x8>(v);
    return _mm_srli_epi16(reinterpret_cast<__m128i>(w < 0 ? -w : w), 2);
}
#endif

}  // namespace

void gradientRowReference(const std::uint8_t* up, const std::uint8_t* row, const std::uint8_t* down, int width,
                          bool alongY, std::uint8_t* magnitude, AlongCounts& alongCounts)
{
    for (int x = 0; x < width; ++x) gradientPixel(up, row, down, width, alongY, x, magnitude, alongCounts);
}

namespace {

// gradientRow's body; shuffles: the 16-pixel blocks by block16Avx2 and its
// byte shuffles (x86-64 AVX2 and AVX-512 versions).
template <bool shuffles>
[[gnu::always_inline]] inline void gradientRowBody(const std::uint8_t* up, const std::uint8_t* row,
                                                   const std::uint8_t* down, int width, bool alongY,
                                                   std::uint8_t* magnitude, AlongCounts& alongCounts,
                                                   [[maybe_unused]] std::int16_t* lanes)
{
    if (width < 3) {
        gradientRowReference(up, row, down, width, alongY, magnitude, alongCounts);
        return;
    }
    gradientPixel(up, row, down, width, alongY, 0, magnitude, alongCounts);
    int x = 1;
#if defined(__ARM_NEON)
    for (; x + 16 < width; x += 16) gradient16(up, row, down, alongY, x, magnitude, alongCounts);
    // The pixels left before the last one by a last block ending at pixel
    // width - 2 (as on SSE2, below), where they took gradientPixel each.
    if (x < width - 1 && width >= 18) {
        gradient16(up, row, down, alongY, width - 17, magnitude, alongCounts, x - (width - 17));
        x = width - 1;
    }
#else
    // Per byte lane i (pixel i / 3, channel i % 3) of the interior pixels,
    // in SSE2 (the scalar loops are the SSE2 loops' reference and tails;
    // GCC vectorises them on other targets): separable Sobel in
    // int16 lanes, then the magnitude halved ((s + 1) / 2 keeps the order, so
    // its maximum is the halved maximum) and the along gradient, both <= 255,
    // in byte lanes; then per pixel the maximum over its three lanes.
    const int bytes = 3 * width;
    std::int16_t* smooth = lanes;            // up + 2 row + down
    std::int16_t* vertical = lanes + bytes;  // down - up
    auto* halfSum = reinterpret_cast<std::uint8_t*>(lanes + 2 * bytes);  // (|dx| + |dy| + 1) / 2
    std::uint8_t* alongLane = halfSum + bytes;
    int i = 0;
#if defined(__SSE2__)
    // As the loop below, each row loaded once (GCC loaded up and down twice).
    // The AVX versions: by smoothVertical16 (half the instructions).
    // (Two per step: the loop took 3 of the 12 instructions per 16 bytes.)
    if constexpr (shuffles) {
        for (; i + 32 <= bytes; i += 32) {
            smoothVertical16(up + i, row + i, down + i, smooth + i, vertical + i);
            smoothVertical16(up + i + 16, row + i + 16, down + i + 16, smooth + i + 16, vertical + i + 16);
        }
        if (i + 16 <= bytes) {
            smoothVertical16(up + i, row + i, down + i, smooth + i, vertical + i);
            i += 16;
        }
    }
    for (; i + 16 <= bytes; i += 16) {
        const __m128i zero = _mm_setzero_si128();
        const __m128i u = load8(up + i), r = load8(row + i), d = load8(down + i);
        const __m128i uw[2] = {_mm_unpacklo_epi8(u, zero), _mm_unpackhi_epi8(u, zero)};
        const __m128i rw[2] = {_mm_unpacklo_epi8(r, zero), _mm_unpackhi_epi8(r, zero)};
        const __m128i dw[2] = {_mm_unpacklo_epi8(d, zero), _mm_unpackhi_epi8(d, zero)};
        for (int half = 0; half < 2; ++half) {
            store16(smooth + i + 8 * half,
                    _mm_add_epi16(_mm_add_epi16(uw[half], dw[half]), _mm_add_epi16(rw[half], rw[half])));
            store16(vertical + i + 8 * half, _mm_sub_epi16(dw[half], uw[half]));
        }
    }
#endif
    for (; i < bytes; ++i) {
        smooth[i] = static_cast<std::int16_t>(up[i] + 2 * row[i] + down[i]);
        vertical[i] = static_cast<std::int16_t>(down[i] - up[i]);
    }
#if defined(__SSE2__)
    // 16 pixels per step: their 48 byte lanes as the loop below computes them,
    // with pavgw for (gx + gy + 1) >> 1 and no masks before the byte packs
    // (GCC masks each value it packs), then split into their channels in
    // registers (instead of a running maximum over three lanes and a scalar
    // pick of every third: 0.54 -> 0.45 ms at 780x580 with the loop above).
    // (alongY as a constant of each instantiation of blocks, below: a branch
    // per lanes16 with both packs took 3 instructions more.)
    const auto lanes16 = [&](auto alongYConstant, int i, __m128i& half, __m128i& along) {
        __m128i gx[2], gy[2];
        for (int h = 0; h < 2; ++h) {
            const int j = i + 8 * h;
            const __m128i dx = _mm_sub_epi16(load16(smooth + j + 3), load16(smooth + j - 3));
            const __m128i v = load16(vertical + j);
            const __m128i dy = _mm_add_epi16(_mm_add_epi16(load16(vertical + j - 3), load16(vertical + j + 3)),
                                             _mm_add_epi16(v, v));
            gx[h] = absQuarter(dx);
            gy[h] = absQuarter(dy);
        }
        half = _mm_packus_epi16(_mm_avg_epu16(gx[0], gy[0]), _mm_avg_epu16(gx[1], gy[1]));
        along = decltype(alongYConstant)::value ? _mm_packus_epi16(gy[0], gy[1]) : _mm_packus_epi16(gx[0], gx[1]);
    };
    // The along maxima pass through the byte lanes' memory, unused in this
    // loop (GCC would extract each byte of a local array by a store of all).
    std::uint8_t* along = halfSum;
    const auto blocks = [&](auto alongYConstant) {
        const auto block = [&](int x) {
            if constexpr (shuffles) {
                block16Avx2<decltype(alongYConstant)::value>(smooth, vertical, x, magnitude, along);
            } else {
                __m128i h[3], a[3];
                for (int c = 0; c < 3; ++c) lanes16(alongYConstant, 3 * x + 16 * c, h[c], a[c]);
                _mm_storeu_si128(reinterpret_cast<__m128i*>(magnitude + x), channelMax(h[0], h[1], h[2]));
                _mm_storeu_si128(reinterpret_cast<__m128i*>(along), channelMax(a[0], a[1], a[2]));
            }
        };
        for (; x + 16 < width; x += 16) {
            block(x);
            // x = 1 mod 16, so each pixel's histogram copy is a constant.
            for (int k = 0; k < 16; ++k) ++alongCounts[(1 + k) & 3][along[k]];
        }
        // The pixels left before the last one (1 to 15 of them) by a last
        // block ending at pixel width - 2, over pixels done already (the same
        // magnitudes again), counting only the new ones, where the lane loop
        // and the pixel loop below took about 4 times the instructions.
        if (x < width - 1 && width >= 18) {
            const int last = width - 17;
            block(last);
            for (int k = x - last; k < 16; ++k) ++alongCounts[(last + k) & 3][along[k]];
            x = width - 1;
        }
    };
    if (alongY)
        blocks(std::true_type{});
    else
        blocks(std::false_type{});
#endif
    // (With SSE2: on rows narrower than 18 pixels only.)
    for (i = 3 * x; i < bytes - 3; ++i) {
        const std::int16_t dx = static_cast<std::int16_t>(smooth[i + 3] - smooth[i - 3]);
        const std::int16_t dy = static_cast<std::int16_t>(vertical[i - 3] + 2 * vertical[i] + vertical[i + 3]);
        const std::int16_t gx = static_cast<std::int16_t>((dx < 0 ? -dx : dx) >> 2);
        const std::int16_t gy = static_cast<std::int16_t>((dy < 0 ? -dy : dy) >> 2);
        halfSum[i] = static_cast<std::uint8_t>((gx + gy + 1) >> 1);
        alongLane[i] = static_cast<std::uint8_t>(alongY ? gy : gx);
    }
    for (; x + 1 < width; ++x) {
        const int l = 3 * x;
        magnitude[x] = std::max(std::max(halfSum[l], halfSum[l + 1]), halfSum[l + 2]);
        ++alongCounts[x & 3][std::max(std::max(alongLane[l], alongLane[l + 1]), alongLane[l + 2])];
    }
#endif
    for (; x < width; ++x) gradientPixel(up, row, down, width, alongY, x, magnitude, alongCounts);
}

#if defined(__x86_64__)
// One definition per target (GCC's function multiversioning, an ifunc; as
// target_clones, but the AVX versions take byte shuffles, which SSE2 lacks,
// and AVX2 helpers, which only flatten inlines: GCC left some a call).
[[gnu::target("default")]] void gradientRowVersion(const std::uint8_t* up, const std::uint8_t* row,
                                                   const std::uint8_t* down, int width, bool alongY,
                                                   std::uint8_t* magnitude, AlongCounts& alongCounts,
                                                   std::int16_t* lanes)
{
    gradientRowBody<false>(up, row, down, width, alongY, magnitude, alongCounts, lanes);
}
[[gnu::target("arch=x86-64-v3"), gnu::flatten]] void gradientRowVersion(const std::uint8_t* up, const std::uint8_t* row,
                                                          const std::uint8_t* down, int width, bool alongY,
                                                          std::uint8_t* magnitude, AlongCounts& alongCounts,
                                                          std::int16_t* lanes)
{
    gradientRowBody<true>(up, row, down, width, alongY, magnitude, alongCounts, lanes);
}
[[gnu::target("arch=x86-64-v4"), gnu::flatten]] void gradientRowVersion(const std::uint8_t* up, const std::uint8_t* row,
                                                          const std::uint8_t* down, int width, bool alongY,
                                                          std::uint8_t* magnitude, AlongCounts& alongCounts,
                                                          std::int16_t* lanes)
{
    gradientRowBody<true>(up, row, down, width, alongY, magnitude, alongCounts, lanes);
}
#endif

}  // namespace

void gradientRow(const std::uint8_t* up, const std::uint8_t* row, const std::uint8_t* down, int width, bool alongY,
                 std::uint8_t* magnitude, AlongCounts& alongCounts, std::int16_t* lanes)
{
#if defined(__x86_64__)
    gradientRowVersion(up, row, down, width, alongY, magnitude, alongCounts, lanes);
#else
    gradientRowBody<false>(up, row, down, width, alongY, magnitude, alongCounts, lanes);
#endif
}

}  // namespace stria::pipeline
