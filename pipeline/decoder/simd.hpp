#pragma once
// The decoder's pixel kernels with a plain scalar reference each. The fast
// versions (NEON intrinsics on ARM, auto-vectorised lanes elsewhere) must give
// exactly the reference's output: tests/decoder/test_kernels.cpp checks them
// on random and simulator frames.

#include <opencv2/core.hpp>

#include <algorithm>
#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <type_traits>

#if defined(__aarch64__)
#include <arm_neon.h>
#endif

// x86-64 builds target SSE2; the hottest kernels are also compiled for
// x86-64-v3 (AVX2) and -v4 (AVX-512), and the loader picks the best the CPU
// has (an ifunc per kernel): gradientRow as one definition per target of one
// body (simd_gradient.cpp: the AVX versions split the channels by byte
// shuffles), the watershed sweeps as one definition per target
// (simd_watershed.cpp: their AVX bodies take 8 labels per block, not 4). Integer lanes: the same results on each. 780x580 stage
// medians: watershed 1.33 -> 1.21 ms by the AVX-512 clones' one-instruction
// selects (vpternlogd) with the carry of storeWithCarry, then -0.03-0.05 ms
// by the 8-label blocks; gradient 0.44 -> 0.42 (the region medians: no
// faster). Since session 8 also: computeWatershed and descentRow as clones,
// computeGradient (gradient.cpp: its floor select) as clones,
// computePoints (depth.cpp) as clones, with
// the edge sample windows as one definition per target (simd_edges.cpp: the
// AVX2 body gathers a channel's 8 samples by vpshufb), and the region copy
// pass (regions.cpp: 4 pixels per byte shuffle on x86-64-v3; tbl on
// AArch64), and the region medians as one definition per
// target (simd_regions.cpp: the AVX2 bodies take 8 pixels per compare and
// count the values below t). tests/decoder runs the kernel tests again under qemu-x86_64 on
// CPUs without AVX-512 and without AVX (the AVX2 and SSE2 versions).
#if defined(__x86_64__)
#define STRIA_X86_CLONES __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define STRIA_X86_CLONES
#endif

namespace stria::pipeline {

// A value made opaque to GCC: an empty asm that may have changed it, in a
// register. GCC then keeps it in a register rather than building a
// constant again per iteration or folding a pointer back into another, and
// cannot turn the select that made it into a branch on the select's
// operands (graph.cpp's pair loops, the watershed's union, the region
// copy's blocks).
template <typename T>
[[gnu::always_inline]] inline void hide(T& value)
{
    asm("" : "+r"(value));
}

// The position of a mask word's lowest set bit, for bits != 0 (the border
// masks' bit loops in graph.cpp and depth.cpp). On x86-64 one rep bsf into a
// 64-bit register (tzcnt where the CPU has BMI1, bsf before it: the same for
// a word that is not 0), where GCC 12 wraps std::countr_zero's int in an xor
// that clears the register first and a sign extension (movslq) after it, two
// instructions per border pair (graph stage 10.97 -> 10.74 M instructions per
// 780x580 decode).
[[gnu::always_inline]] inline std::size_t lowestBit(std::uint64_t bits)
{
#if defined(__x86_64__)
    std::uint64_t at;
    asm("rep bsf %1, %0" : "=r"(at) : "rm"(bits) : "cc");
    return at;
#else
    return static_cast<unsigned>(std::countr_zero(bits));
#endif
}

// Bit positions as a list ("flattening", simdjson's flatten_bits, Lemire):
// appends x0 + i for each set bit i of bits to out, in increasing order, and
// returns out past the last. The reference is the plain loop
//   for (; bits; bits &= bits - 1) *out++ = x0 + std::countr_zero(bits);
// whose exit, once per word, a branch predictor misses on most words (the
// bit counts are noise to it). Here the first kGroup positions are written
// without a branch, whatever the count (past the last set bit they are
// junk, which the next word's positions overwrite or the caller never
// reads), and only a word with more takes a branch (chosen so that few do).
// A stage walks a whole row's list in one loop: one mispredicted exit per
// row instead of one per word. out needs room for kGroup entries past the
// row's last position. Position: std::int32_t (the watershed's lists) or
// std::uint16_t (the regions' border lists, DecoderWorkspace::borderPositions).
template <int kGroup, class Position>
[[gnu::always_inline]] inline Position* appendBitPositions(std::uint64_t bits, std::type_identity_t<Position> x0,
                                                           Position* out)
{
    const int count = std::popcount(bits);
    auto group = [&](Position* to) __attribute__((always_inline)) {
        for (int i = 0; i < kGroup; ++i) {
            to[i] = static_cast<Position>(x0 + static_cast<Position>(lowestBit(bits)));  // junk once bits is 0 (unused)
            bits &= bits - 1;
        }
    };
    group(out);
    if (count > kGroup) [[unlikely]]
        for (Position* to = out + kGroup; bits != 0; to += kGroup) group(to);
    return out + count;
}

#if defined(__aarch64__)
// AArch64 has no movemask: bit i of the result is set where byte i of the 64
// in m0..m3 (each byte 0 or 0xff) is set. Each byte keeps its own bit of its
// group of 8 (1, 2, .., 128), and three rounds of pairwise adds sum each
// group into one byte (19 instructions per 64 bytes, where 16 per 16 took
// two addv and a shift). The watershed's flat pixels and sweeps and the
// graph's border masks take it.
[[gnu::always_inline]] inline std::uint64_t byteMask64(uint8x16_t m0, uint8x16_t m1, uint8x16_t m2, uint8x16_t m3)
{
    const uint8x16_t weights = vreinterpretq_u8_u64(vdupq_n_u64(0x8040201008040201ull));
    const uint8x16_t a = vpaddq_u8(vandq_u8(m0, weights), vandq_u8(m1, weights));
    const uint8x16_t b = vpaddq_u8(vandq_u8(m2, weights), vandq_u8(m3, weights));
    const uint8x16_t ab = vpaddq_u8(a, b);
    return vgetq_lane_u64(vreinterpretq_u64_u8(vpaddq_u8(ab, ab)), 0);
}
#endif

// One row of the gradient stage (gradient.cpp) from the rows above, at and
// below it (clamped at the image border by the caller): per pixel,
// magnitude = (max over channels of Sobel |dx|/4 + |dy|/4, + 1) / 2, and
// along = max over channels of |dy|/4 (alongY) or |dx|/4 counted in a
// histogram: pixel x adds 1 to alongCounts[x % 4][along] (neighbouring
// pixels mostly share a value: one counter would serialise the increments).
using AlongCounts = std::array<std::array<std::int32_t, 256>, 4>;
void gradientRowReference(const std::uint8_t* up, const std::uint8_t* row, const std::uint8_t* down, int width,
                          bool alongY, std::uint8_t* magnitude, AlongCounts& alongCounts);
// Same output. lanes: 12 x width int16 of scratch (unused with NEON).
void gradientRow(const std::uint8_t* up, const std::uint8_t* row, const std::uint8_t* down, int width, bool alongY,
                 std::uint8_t* magnitude, AlongCounts& alongCounts, std::int16_t* lanes);

// Watershed by steepest descent (watershed.cpp): per pixel of a row, the
// direction of its lowest 4-neighbour if that is strictly lower than the
// pixel, ties broken in the order up, left, right, down; kDescentFlat if no
// neighbour is lower. up and down are the rows above and below, a row of 255
// on the image border (a missing neighbour is never lower).
inline constexpr std::uint8_t kDescentUp = 0, kDescentLeft = 1, kDescentRight = 2, kDescentDown = 3, kDescentFlat = 8;
void descentRowReference(const std::uint8_t* up, const std::uint8_t* row, const std::uint8_t* down, int width,
                         std::uint8_t* code);
void descentRow(const std::uint8_t* up, const std::uint8_t* row, const std::uint8_t* down, int width,
                std::uint8_t* code);
// Code bit set on arrows the plateau pass added (code kPlateauArrow | direction).
inline constexpr std::uint8_t kPlateauArrow = 4;
// Code bit set on the pixels of regional minima (code kMinimumArrow | an
// arrow up or left to a pixel of the same minimum, or | kDescentFlat where
// it has neither: on the first pixel of a new minimum's run).
inline constexpr std::uint8_t kMinimumArrow = 16;
// The label of a pixel whose basin is not known yet (and beyond the row's ends).
inline constexpr std::int32_t kUnresolved = std::numeric_limits<std::int32_t>::min();
// The watershed's row sweeps: each pixel of the row with an arrow up (bits
// kPlateauArrow and kMinimumArrow ignored) takes the label above it, then, from the left, each pixel with an
// arrow left takes its left neighbour's label as it is by then, then, from
// the right, each pixel with an arrow right its right neighbour's. Beyond the
// row's ends the label is kUnresolved. above: width labels (in row 0, which
// has no arrow up, any width readable labels, e.g. the row itself).
// sweepRow takes 4 labels per step, runs of arrows by a prefix scan (GCC
// vector extensions: SSE2 on x86-64, 8 labels in its AVX2/AVX-512 versions;
// NEON intrinsics on arm64, the scan as one tbx lookup). unresolved: (width + 63) /
// 64 words, bit x % 64 of word x / 64 set where row[x] is negative after the
// sweeps (kUnresolved: in the watershed no other label is negative by then).
void sweepRowReference(const std::uint8_t* code, const std::int32_t* above, std::int32_t* row, int width,
                       std::uint64_t* unresolved);
void sweepRow(const std::uint8_t* code, const std::int32_t* above, std::int32_t* row, int width,
              std::uint64_t* unresolved);
// The first two of these sweeps (arrows up, then left) only.
void sweepRowUpLeftReference(const std::uint8_t* code, const std::int32_t* above, std::int32_t* row, int width);
void sweepRowUpLeft(const std::uint8_t* code, const std::int32_t* above, std::int32_t* row, int width);

// Edge location (depth.cpp): for the count samples i = first, first + 1, ...
// of a row, the colour change from pixel i to i + 1 (R G B at rgbOffset),
// crosstalk-corrected by m and projected on weight: weight . (m * change).
void projectedGradientsReference(const std::uint8_t* row, int first, int count, const std::array<int, 3>& rgbOffset,
                                 const cv::Matx33f& m, const cv::Vec3f& weight, float* out);
// The same for count windows of a row at once (the depth stage's edges):
// window j's kWindowSamples samples from firsts[j], weighted by weights[j],
// into out[j][0..7] (out[j][8] is the caller's), -infinity for samples
// outside the row (i < 0 or i > width - 2). Equal to the reference as
// floats: its products in its order, the sums without its leading 0 +,
// which can change the sign of a zero sum only.
inline constexpr int kWindowSamples = 8;
void projectedGradientWindows(const std::uint8_t* row, int width, const std::int32_t* firsts,
                              const cv::Vec3f* weights, int count, const std::array<int, 3>& rgbOffset,
                              const cv::Matx33f& m, std::array<float, kWindowSamples + 1>* out);

// Region colours (regions.cpp): per byte k < 3 of count >= 1 pixels of 4
// bytes (a frame pixel's 3 and one more, each stored as value ^
// kRegionByteBias), the median of the pixels' values k: the value
// at index count / 2 of them sorted. channelMedians reads whole
// blocks of pixels, the last one whole: the kRegionPad entries after the last
// pixel must hold the value 0 in bytes 0-2 (kRegionByteBias stored),
// which is below every value the search compares with (and not counted).
// x86-64: 7, to the next multiple of 8 (the AVX2 versions' blocks of 8
// pixels); arm64 the same (channelMediansOfFourAlike's blocks of 8, loaded
// by ldp); 3 elsewhere (blocks of 4).
// The bytes' bias: each stored as value ^ kRegionByteBias. 0x80 on x86
// (SSE2 has only signed byte compares: the bias orders the values as signed
// bytes), 0 on NEON, whose unsigned compares take the raw bytes (the copy
// pass without its xor).
#if defined(__ARM_NEON)
inline constexpr std::uint8_t kRegionByteBias = 0;
#else
inline constexpr std::uint8_t kRegionByteBias = 0x80;
#endif
#if defined(__x86_64__) || defined(__aarch64__)
inline constexpr int kRegionPad = 7;
#else
inline constexpr int kRegionPad = 3;
#endif
std::array<std::uint8_t, 3> channelMediansReference(const std::uint32_t* pixels, int count);
std::array<std::uint8_t, 3> channelMedians(const std::uint32_t* pixels, int count);
// The same for four regions at once, faster where each has up to 255 pixels:
// region j's medians in bytes 0-2 of dword j (byte 3 zero).
std::array<std::uint32_t, 4> channelMediansOfFour(const std::array<const std::uint32_t*, 4>& pixels,
                                                  const std::array<int, 4>& counts);
// The same for four regions of 1-255 pixels with the same number of blocks
// of 4 ((count + 3) / 4 equal), their blocks walked together.
std::array<std::uint32_t, 4> channelMediansOfFourAlike(const std::array<const std::uint32_t*, 4>& pixels,
                                                       const std::array<int, 4>& counts);

// Region statistics and graph (regions.cpp, graph.cpp). Bit i of the result
// is set where a[i] != b[i], for i < count <= 64: with b = a + 1 the borders
// between horizontal neighbours of a label row (the ends of its runs), with
// b = a + width those to the row below.
std::uint64_t borderMaskReference(const std::int32_t* a, const std::int32_t* b, int count);
std::uint64_t borderMask(const std::int32_t* a, const std::int32_t* b, int count);
// Calls visit(i) for each i < count with a[i] != b[i], in increasing order,
// from borderMask's 64-bit masks: no branch per pixel (whether neighbours
// share a label is noise to a branch predictor), one per border.
template <class Visit>
inline void forEachBorder(const std::int32_t* a, const std::int32_t* b, int count, Visit&& visit)
{
    for (int i0 = 0; i0 < count; i0 += 64)
        for (std::uint64_t bits = borderMask(a + i0, b + i0, std::min(64, count - i0)); bits; bits &= bits - 1)
            visit(i0 + std::countr_zero(bits));
}
// Eq. 8's terms of one border pixel pair: the image gradient at the pair's
// middle, summed over the channels as |component along primary| and
// |component across it|. The reference is pairGradient (workspace.hpp), for
// every pair; these give its floats bit for bit from BGR/RGB rows, for the
// pair (x, y)-(x + 1, y) from rows y - 1, y, y + 1 (clamped by the caller)
// with x + 2 < width, and for (x, y)-(x, y + 1) from rows y, y + 1 with
// 0 < x and x + 2 < width (they read 8 bytes from 3 * x, and from 3 * x - 3).
struct PairGradient {
    float primary = 0, secondary = 0;
};
PairGradient horizontalPairGradient(const std::uint8_t* up, const std::uint8_t* row, const std::uint8_t* down, int x,
                                    const cv::Vec2f& primary);
PairGradient verticalPairGradient(const std::uint8_t* row, const std::uint8_t* below, int x, const cv::Vec2f& primary);

// Four floats in GCC's vector extensions (SSE2 and NEON from one source).
using Float4 = float __attribute__((vector_size(16)));

// Rows to columns: v[j][i] = v[i][j] before. The edge and depth stages take
// 4 records at a time and work on one field per vector, a record per lane.
inline void transpose4(Float4 v[4])
{
    using Index = std::int32_t __attribute__((vector_size(16)));
    const Float4 t0 = __builtin_shuffle(v[0], v[1], Index{0, 4, 1, 5}), t1 = __builtin_shuffle(v[2], v[3], Index{0, 4, 1, 5});
    const Float4 t2 = __builtin_shuffle(v[0], v[1], Index{2, 6, 3, 7}), t3 = __builtin_shuffle(v[2], v[3], Index{2, 6, 3, 7});
    v[0] = __builtin_shuffle(t0, t1, Index{0, 1, 4, 5});
    v[1] = __builtin_shuffle(t0, t1, Index{2, 3, 6, 7});
    v[2] = __builtin_shuffle(t2, t3, Index{0, 1, 4, 5});
    v[3] = __builtin_shuffle(t2, t3, Index{2, 3, 6, 7});
}

}  // namespace stria::pipeline
