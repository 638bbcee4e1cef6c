// Region colour statistics kernel (pipeline/decoder/simd.hpp).
#include "pipeline/decoder/simd.hpp"

#include <algorithm>

#if defined(__ARM_NEON)
#include <arm_neon.h>
#elif defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__x86_64__)
#include <immintrin.h>
#endif

// Duff's device of blockCounts and blocksBelow: a loop of 64 blocks per step,
// entered by a jump into its body so that the first step takes the blocks
// past whole 64s: its block i (of 0-63) is counted by STRIA_COUNT(i), which
// the user defines (reading at + stride * i), entered at i = 64 - first
// (first: 1-64, 64 as 0, so the cases cover every value of first & 63);
// `at` moves on by 64 blocks per step, for `steps` steps.
#define STRIA_DUFF_BLOCK(i) \
    case (64 - (i)) & 63:   \
        STRIA_COUNT(i);     \
        [[fallthrough]];
#define STRIA_DUFF_BLOCKS8(i)                                                                                        \
    STRIA_DUFF_BLOCK(i) STRIA_DUFF_BLOCK(i + 1) STRIA_DUFF_BLOCK(i + 2) STRIA_DUFF_BLOCK(i + 3) STRIA_DUFF_BLOCK(i + 4) \
        STRIA_DUFF_BLOCK(i + 5) STRIA_DUFF_BLOCK(i + 6) STRIA_DUFF_BLOCK(i + 7)
#define STRIA_BLOCKS_OF_64(first, steps, at, stride)                                                                    \
    switch (static_cast<unsigned>(first) & 63) {                                                                        \
        do {                                                                                                            \
            STRIA_DUFF_BLOCKS8(0) STRIA_DUFF_BLOCKS8(8) STRIA_DUFF_BLOCKS8(16) STRIA_DUFF_BLOCKS8(24)                   \
            STRIA_DUFF_BLOCKS8(32) STRIA_DUFF_BLOCKS8(40) STRIA_DUFF_BLOCKS8(48) STRIA_DUFF_BLOCK(56)                   \
            STRIA_DUFF_BLOCK(57) STRIA_DUFF_BLOCK(58) STRIA_DUFF_BLOCK(59) STRIA_DUFF_BLOCK(60) STRIA_DUFF_BLOCK(61)     \
            STRIA_DUFF_BLOCK(62)                                                                                        \
        case 1:                                                                                                         \
            STRIA_COUNT(63);                                                                                            \
            at += (stride) * 64;                                                                                        \
        } while (--(steps) > 0);                                                                                        \
    }

// The count-down Duff's device of forBlocksDown (64 blocks) and the AVX2
// four-alike kernel (32 blocks): STRIA_STEP(b), which the user defines, for
// b = blocks - 1 down to 0 (1 <= blocks <= n), by a jump into straight-line
// code. The switch is on blocks & (n - 1) (n as 0): its n cases cover every
// value, so GCC's jump has no bounds check.
#define STRIA_DOWN_BLOCK(b, n)   \
    case (b) & ((n) - 1):        \
        STRIA_STEP((b) - 1);     \
        [[fallthrough]];
#define STRIA_DOWN_BLOCKS8(b, n)                                                                                      \
    STRIA_DOWN_BLOCK(b, n) STRIA_DOWN_BLOCK((b) - 1, n) STRIA_DOWN_BLOCK((b) - 2, n) STRIA_DOWN_BLOCK((b) - 3, n)     \
        STRIA_DOWN_BLOCK((b) - 4, n) STRIA_DOWN_BLOCK((b) - 5, n) STRIA_DOWN_BLOCK((b) - 6, n) STRIA_DOWN_BLOCK((b) - 7, n)
#define STRIA_DOWN_LAST8(n)                                                                                         \
    STRIA_DOWN_BLOCK(8, n) STRIA_DOWN_BLOCK(7, n) STRIA_DOWN_BLOCK(6, n) STRIA_DOWN_BLOCK(5, n) STRIA_DOWN_BLOCK(4, n) \
        STRIA_DOWN_BLOCK(3, n) STRIA_DOWN_BLOCK(2, n) case 1: STRIA_STEP(0);
#define STRIA_BLOCKS_DOWN_32(blocks)                                                                                    \
    switch (static_cast<unsigned>(blocks) & 31) {                                                                      \
        STRIA_DOWN_BLOCKS8(32, 32) STRIA_DOWN_BLOCKS8(24, 32) STRIA_DOWN_BLOCKS8(16, 32) STRIA_DOWN_LAST8(32)          \
    }
#define STRIA_BLOCKS_DOWN_64(blocks)                                                                                    \
    switch (static_cast<unsigned>(blocks) & 63) {                                                                      \
        STRIA_DOWN_BLOCKS8(64, 64) STRIA_DOWN_BLOCKS8(56, 64) STRIA_DOWN_BLOCKS8(48, 64) STRIA_DOWN_BLOCKS8(40, 64)    \
        STRIA_DOWN_BLOCKS8(32, 64) STRIA_DOWN_BLOCKS8(24, 64) STRIA_DOWN_BLOCKS8(16, 64) STRIA_DOWN_LAST8(64)          \
    }
// A four-region kernel's step: block b of each region's pixels (p0-p3)
// against its limits (l0-l3) into its counts (c0-c3), by count(c, l, p, b).
#define STRIA_FOUR_REGIONS(count, b) \
    count(c0, l0, p0, b);            \
    count(c1, l1, p1, b);            \
    count(c2, l2, p2, b);            \
    count(c3, l3, p3, b)

namespace stria::pipeline {

std::array<std::uint8_t, 3> channelMediansReference(const std::uint32_t* pixels, int count)
{
    const auto* bytes = reinterpret_cast<const std::uint8_t*>(pixels);
    std::array<std::uint8_t, 3> median{};
    for (int k = 0; k < 3; ++k) {
        std::array<std::int32_t, 256> histogram{};
        for (int i = 0; i < count; ++i) ++histogram[bytes[4 * i + k] ^ kRegionByteBias];
        int v = 0;
        for (int seen = histogram[0]; seen <= count / 2; seen += histogram[++v]) {}
        median[k] = static_cast<std::uint8_t>(v);
    }
    return median;
}

namespace {
std::array<std::uint8_t, 3> mediansBody(const std::uint32_t* pixels, int count);

// What four regions' median searches need in each byte of their dword: at
// most count / 2 values below t, so at least count - count / 2 from t on.
[[maybe_unused]] inline std::array<std::uint32_t, 4> needsOfFour(const std::array<int, 4>& counts)
{
    std::array<std::uint32_t, 4> needs;
    for (int j = 0; j < 4; ++j) {
        const auto n = static_cast<std::uint32_t>(counts[j]);  // >= 1
        needs[j] = (n - n / 2) * 0x01010101u;
    }
    return needs;
}

}  // namespace

#if defined(__ARM_NEON) || defined(__SSE2__)
namespace {

alignas(16) constexpr std::uint8_t kThreeBytes[16] = {255, 255, 255, 0, 255, 255, 255, 0, 255, 255, 255, 0, 255, 255, 255, 0};

// The median m = values sorted[count / 2] is the largest t with at most
// count / 2 values below t: found bit by bit from the top, each step one
// counting pass over the pixels (4 pixels' 3 channels per compare, no
// branch per value; a region's ~256 bytes stay in L1 for the 8 passes).
// The pixels' bytes are the values ^ kRegionByteBias (the copy pass stores
// them so; on x86 0x80, on NEON 0 and the compares unsigned):
// the compares count the values at least t as signed bytes greater than
// (t - 1) ^ 0x80, 3 instructions per block with SSE2 (load, compare,
// subtract), where an unsigned compare took 4 (780x580 medians 6.09 ->
// 5.16 M instructions per decode, the copy pass's xor +0.16 M).
// A pass's counts go to 2 or 4 accumulators in turn: with one, its chain of
// dependent subtractions (1 cycle each) was the bound, not the compares
// (780x580 medians 0.66 -> 0.48 ms, 1388x1038 1.70 -> 1.28 ms).

// Calls step(b) for b = blocks - 1 down to 0, 1 <= blocks <= 64, by a jump into
// straight-line code (Duff's device): the 8 passes over a region take the
// same jump, which is predicted after the first, where a loop's exit was
// mispredicted in most passes. The switch is on blocks & 63 (64 as 0): its
// 64 cases cover every value, so GCC's jump has no bounds check.
template <class Step>
[[gnu::always_inline]] inline void forBlocksDown(int blocks, Step step)
{
#define STRIA_STEP(b) step(b)
    STRIA_BLOCKS_DOWN_64(blocks)
#undef STRIA_STEP
}

#if defined(__ARM_NEON)
using Bytes = uint8x16_t;
inline Bytes loadBytes(const std::uint8_t* p) { return vld1q_u8(p); }
inline Bytes zeroBytes() { return vdupq_n_u8(0); }
inline Bytes add(Bytes a, Bytes b) { return vaddq_u8(a, b); }
inline Bytes sub(Bytes a, Bytes b) { return vsubq_u8(a, b); }
inline Bytes bitAnd(Bytes a, Bytes b) { return vandq_u8(a, b); }
// All ones in the lanes of x at least the limit's t: x > t - 1 as unsigned
// bytes (x the raw value: kRegionByteBias is 0 on NEON; the limit is t - 1 =
// t + 0xff), where the signed compare of x86 took the copy's xor per block.
static_assert(kRegionByteBias == 0);
inline Bytes atLeast(const std::uint8_t* x, Bytes limit) { return vcgtq_u8(vld1q_u8(x), limit); }
inline Bytes limitOf(std::uint32_t t) { return vaddq_u8(vreinterpretq_u8_u32(vdupq_n_u32(t)), vdupq_n_u8(0xff)); }
// Each byte position's sum over the four pixels, in 16 bits.
inline std::array<int, 3> pixelSums(Bytes counts)
{
    const uint16x8_t pairs = vaddl_u8(vget_low_u8(counts), vget_high_u8(counts));
    const uint16x4_t sums = vadd_u16(vget_low_u16(pairs), vget_high_u16(pairs));
    return {vget_lane_u16(sums, 0), vget_lane_u16(sums, 1), vget_lane_u16(sums, 2)};
}

// One region's search in byte lanes, for count <= 255 (a byte position's four
// pixel counters sum to at most count).
struct ByteSearch {
    const std::uint8_t* bytes;
    int blocks;
    Bytes need, m;
};
inline Bytes firstBit() { return vdupq_n_u8(128); }
inline Bytes nextBit(Bytes bit) { return vshrq_n_u8(bit, 1); }
inline Bytes searchLimit(const ByteSearch& s, Bytes bit) { return vaddq_u8(vorrq_u8(s.m, bit), vdupq_n_u8(0xff)); }
inline void searchStep(ByteSearch& s, Bytes bit, Bytes counts)
{
    counts = vaddq_u8(counts, vextq_u8(counts, counts, 8));
    counts = vaddq_u8(counts, vextq_u8(counts, counts, 4));
    s.m = vorrq_u8(s.m, vandq_u8(bit, vcgeq_u8(counts, s.need)));
}
inline std::array<std::uint8_t, 3> searchResult(const ByteSearch& s)
{
    return {vgetq_lane_u8(s.m, 0), vgetq_lane_u8(s.m, 1), vgetq_lane_u8(s.m, 2)};
}
// Four regions' searches in the 4-byte lanes (dwords) j of one vector each.
inline Bytes limitsOf(Bytes m, Bytes bit) { return vaddq_u8(vorrq_u8(m, bit), vdupq_n_u8(0xff)); }
template <int j>
inline Bytes dwordOf(Bytes v)
{
    return vreinterpretq_u8_u32(vdupq_n_u32(vgetq_lane_u32(vreinterpretq_u32_u8(v), j)));
}
inline Bytes dwordsOf(const std::array<std::uint32_t, 4>& v) { return vreinterpretq_u8_u32(vld1q_u32(v.data())); }
// Dword j: the bytewise sum of counts j's 4 dwords.
inline Bytes sumsOfFour(Bytes c0, Bytes c1, Bytes c2, Bytes c3)
{
    const uint32x4x2_t a = vzipq_u32(vreinterpretq_u32_u8(c0), vreinterpretq_u32_u8(c1));  // c0 c1 c0 c1
    const uint32x4x2_t b = vzipq_u32(vreinterpretq_u32_u8(c2), vreinterpretq_u32_u8(c3));
    const Bytes s0 = vaddq_u8(vreinterpretq_u8_u32(a.val[0]), vreinterpretq_u8_u32(a.val[1]));
    const Bytes s1 = vaddq_u8(vreinterpretq_u8_u32(b.val[0]), vreinterpretq_u8_u32(b.val[1]));
    return vaddq_u8(vcombine_u8(vget_low_u8(s0), vget_low_u8(s1)), vcombine_u8(vget_high_u8(s0), vget_high_u8(s1)));
}
inline Bytes stepOfFour(Bytes m, Bytes bit, Bytes sums, Bytes need) { return vorrq_u8(m, vandq_u8(bit, vcgeq_u8(sums, need))); }
inline std::array<std::uint32_t, 4> dwords(Bytes v)
{
    std::array<std::uint32_t, 4> d;
    vst1q_u32(d.data(), vreinterpretq_u32_u8(v));
    return d;
}
// One region of up to 1020 pixels: the bytewise sums over a pass's 4 pixels
// per block in 16 bits (lanes 0-2; need in lanes 0-2, lane 3 never reached),
// the bits reached set in each dword of m.
// (Up to 32767 pixels with wordSums added over chunks of 255 blocks.)
using Words = uint16x4_t;
inline Words addWords(Words a, Words b) { return vadd_u16(a, b); }
inline Words wordSums(Bytes counts)
{
    const uint16x8_t pairs = vaddl_u8(vget_low_u8(counts), vget_high_u8(counts));
    return vadd_u16(vget_low_u16(pairs), vget_high_u16(pairs));
}
inline Words wordsNeed(int need) { return vreinterpret_u16_u64(vdup_n_u64(0xffff000000000000u | 0x100010001u * static_cast<std::uint64_t>(need))); }
inline Bytes stepOfWords(Bytes m, Bytes bit, Words sums, Words need)
{
    const uint8x8_t reached = vmovn_u16(vcombine_u16(vcge_u16(sums, need), vcge_u16(sums, need)));
    return vorrq_u8(m, vandq_u8(bit, vcombine_u8(reached, reached)));
}
#else
using Bytes = __m128i;
inline Bytes loadBytes(const std::uint8_t* p) { return _mm_loadu_si128(reinterpret_cast<const __m128i*>(p)); }
inline Bytes zeroBytes() { return _mm_setzero_si128(); }
inline Bytes add(Bytes a, Bytes b) { return _mm_add_epi8(a, b); }
inline Bytes sub(Bytes a, Bytes b) { return _mm_sub_epi8(a, b); }
inline Bytes bitAnd(Bytes a, Bytes b) { return _mm_and_si128(a, b); }
// All ones in the lanes of x at least the limit's t: x > t - 1 as signed
// bytes (x = value ^ kRegionByteBias = value ^ 0x80, the limit is (t - 1) ^
// 0x80 = t + 0x7f). SSE2 has
// no unsigned byte comparison: max(x, t - 1) == t - 1 on the values took one
// instruction more per block (a copy of the limit or of x).
inline Bytes atLeast(const std::uint8_t* x, Bytes limit) { return _mm_cmpgt_epi8(loadBytes(x), limit); }
inline Bytes limitOf(std::uint32_t t) { return _mm_add_epi8(_mm_set1_epi32(static_cast<int>(t)), _mm_set1_epi8(0x7f)); }
inline std::array<int, 3> pixelSums(Bytes counts)
{
    const __m128i zero = _mm_setzero_si128();
    __m128i sums = _mm_add_epi16(_mm_unpacklo_epi8(counts, zero), _mm_unpackhi_epi8(counts, zero));
    sums = _mm_add_epi16(sums, _mm_srli_si128(sums, 8));
    return {_mm_extract_epi16(sums, 0), _mm_extract_epi16(sums, 1), _mm_extract_epi16(sums, 2)};
}

struct ByteSearch {
    const std::uint8_t* bytes;
    int blocks;
    Bytes need, m;
};
inline Bytes firstBit() { return _mm_set1_epi8(static_cast<char>(128)); }
// bit >> 1 in 16-bit lanes: no bit crosses into the next byte.
inline Bytes nextBit(Bytes bit) { return _mm_srli_epi16(bit, 1); }
inline Bytes searchLimit(const ByteSearch& s, Bytes bit) { return _mm_add_epi8(_mm_or_si128(s.m, bit), _mm_set1_epi8(0x7f)); }
inline void searchStep(ByteSearch& s, Bytes bit, Bytes counts)
{
    counts = _mm_add_epi8(counts, _mm_shuffle_epi32(counts, _MM_SHUFFLE(1, 0, 3, 2)));
    counts = _mm_add_epi8(counts, _mm_shuffle_epi32(counts, _MM_SHUFFLE(2, 3, 0, 1)));
    // counts >= need as max(counts, need) == counts.
    s.m = _mm_or_si128(s.m, _mm_and_si128(bit, _mm_cmpeq_epi8(_mm_max_epu8(counts, s.need), counts)));
}
inline std::array<std::uint8_t, 3> searchResult(const ByteSearch& s)
{
    const auto v = static_cast<std::uint32_t>(_mm_cvtsi128_si32(s.m));
    return {static_cast<std::uint8_t>(v), static_cast<std::uint8_t>(v >> 8), static_cast<std::uint8_t>(v >> 16)};
}
// Four regions' searches in the 4-byte lanes (dwords) j of one vector each.
inline Bytes limitsOf(Bytes m, Bytes bit) { return _mm_add_epi8(_mm_or_si128(m, bit), _mm_set1_epi8(0x7f)); }
template <int j>
inline Bytes dwordOf(Bytes v)
{
    return _mm_shuffle_epi32(v, j * 0x55);
}
inline Bytes dwordsOf(const std::array<std::uint32_t, 4>& v)
{
    return _mm_setr_epi32(static_cast<int>(v[0]), static_cast<int>(v[1]), static_cast<int>(v[2]), static_cast<int>(v[3]));
}
// Dword j: the bytewise sum of counts j's 4 dwords.
inline Bytes sumsOfFour(Bytes c0, Bytes c1, Bytes c2, Bytes c3)
{
    // c0 c1 c0 c1 (dwords 0 and 2 plus 1 and 3), the same for c2 c3.
    const Bytes s0 = _mm_add_epi8(_mm_unpacklo_epi32(c0, c1), _mm_unpackhi_epi32(c0, c1));
    const Bytes s1 = _mm_add_epi8(_mm_unpacklo_epi32(c2, c3), _mm_unpackhi_epi32(c2, c3));
    return _mm_add_epi8(_mm_unpacklo_epi64(s0, s1), _mm_unpackhi_epi64(s0, s1));
}
// sums >= need as max(sums, need) == sums.
inline Bytes stepOfFour(Bytes m, Bytes bit, Bytes sums, Bytes need)
{
    return _mm_or_si128(m, _mm_and_si128(bit, _mm_cmpeq_epi8(_mm_max_epu8(sums, need), sums)));
}
inline std::array<std::uint32_t, 4> dwords(Bytes v)
{
    std::array<std::uint32_t, 4> d;
    _mm_storeu_si128(reinterpret_cast<__m128i*>(d.data()), v);
    return d;
}
// One region of up to 1020 pixels: the bytewise sums over a pass's 4 pixels
// per block in 16 bits (lanes 0-2; need - 1 in lanes 0-2, lane 3 and on never
// reached), the bits reached set in each dword of m.
// (Up to 32767 pixels with wordSums added over chunks of 255 blocks: signed
// compares.)
using Words = __m128i;
inline Words addWords(Words a, Words b) { return _mm_add_epi16(a, b); }
inline Words wordSums(Bytes counts)
{
    const __m128i zero = _mm_setzero_si128();
    const __m128i sums = _mm_add_epi16(_mm_unpacklo_epi8(counts, zero), _mm_unpackhi_epi8(counts, zero));
    return _mm_add_epi16(sums, _mm_srli_si128(sums, 8));  // lanes 0-3: the 4 dwords' sums
}
inline Words wordsNeed(int need)
{
    return _mm_setr_epi16(static_cast<short>(need - 1), static_cast<short>(need - 1), static_cast<short>(need - 1), 0x7fff,
                          0x7fff, 0x7fff, 0x7fff, 0x7fff);
}
inline Bytes stepOfWords(Bytes m, Bytes bit, Words sums, Words needLess1)
{
    const __m128i reached = _mm_cmpgt_epi16(sums, needLess1);
    return _mm_or_si128(m, _mm_and_si128(bit, _mm_shuffle_epi32(_mm_packs_epi16(reached, reached), 0)));
}
#endif

inline ByteSearch startSearch(const std::uint32_t* pixels, int count)
{
    // At most count / 2 below t: at least count - count / 2 from t on.
#if defined(__ARM_NEON)
    const Bytes need = vdupq_n_u8(static_cast<std::uint8_t>(count - count / 2));
#else
    const Bytes need = _mm_set1_epi8(static_cast<char>(count - count / 2));
#endif
    return {reinterpret_cast<const std::uint8_t*>(pixels), static_cast<int>((static_cast<unsigned>(count) + 3) / 4),
            need, zeroBytes()};
}

// The counts of a search's pixels from limit on (per byte position of the
// 4 pixels of a block; the block after the pixels' whole blocks is counted
// whole: its entries past the last pixel hold the value 0, below every limit).
[[gnu::always_inline]] inline Bytes passCounts(const ByteSearch& s, Bytes limit)
{
    Bytes even = zeroBytes(), odd = zeroBytes();
    forBlocksDown(s.blocks, [&](int b) {
        Bytes& counts = b & 1 ? odd : even;
        counts = sub(counts, atLeast(s.bytes + 16 * b, limit));
    });
    return add(even, odd);
}

// One pass of a search: its counts from the next limit on, then its next bit.
[[gnu::always_inline]] inline void searchPass(ByteSearch& s, Bytes bit)
{
    searchStep(s, bit, passCounts(s, searchLimit(s, bit)));
}

// Per byte k < 3 of the pixels (blocks of 4, the last padded with the value
// 0), how many are at least t[k] (1 <= t[k] <= 255).
// 1 <= blocks <= 254: the per-lane byte counters cannot overflow.
// blockCounts: per byte lane of a block, how many blocks are at least the
// limit there (1 <= blocks <= 255: the byte lanes cannot overflow).
[[gnu::always_inline]] inline Bytes blockCounts(const std::uint8_t* bytes, int blocks, Bytes limit)
{
    Bytes c[4] = {zeroBytes(), zeroBytes(), zeroBytes(), zeroBytes()};
    // Duff's device: a loop of 64 blocks per step, entered by a jump into
    // its body so the first step takes the blocks past whole 64s (the same
    // jump in each pass over a region). A loop of 4 blocks per step, which
    // GCC compiled with a copy of each accumulator per block, took 6.5
    // instructions per block, this 4 (straight-line code without the jump
    // targets, GCC regrouped the sums and spilled). The switch is on
    // first & 63 (64 as 0), whose cases cover every value: no bounds check.
    const int first = ((blocks - 1) & 63) + 1;  // 1..64
    int steps = (blocks + 63) / 64;
    // Byte offset of the step's block 0 (negative in the first step, whose
    // blocks 64 - first .. 63 are the region's first).
    std::ptrdiff_t at = 16 * static_cast<std::ptrdiff_t>(first - 64);
#define STRIA_COUNT(i) c[(i) & 3] = sub(c[(i) & 3], atLeast(bytes + (at + 16 * (i)), limit))
    STRIA_BLOCKS_OF_64(first, steps, at, 16)
#undef STRIA_COUNT
    return add(add(c[0], c[1]), add(c[2], c[3]));
}
inline std::array<int, 3> countAtLeast(const std::uint8_t* bytes, int blocks, const std::array<int, 3>& t)
{
    return pixelSums(blockCounts(bytes, blocks, limitOf(static_cast<std::uint32_t>(t[0] | t[1] << 8 | t[2] << 16))));
}

#if defined(__x86_64__)
// The x86-64-v3 version of channelMediansOfFourAlike (a function per target,
// GCC's multiversioning: an ifunc): 8 pixels (32 bytes) per compare, and the
// values below t counted, where the SSE2 body counts those at least t:
// t > x takes the block from memory as the compare's second operand (VEX
// loads need no alignment), 2 instructions per 8 pixels where SSE2 takes 3
// per 4 (load, compare, subtract). The counts at least t are then the
// slots (8 per block of 8, the pad entries' value 0 below every t: x86-64's
// kRegionPad of 7 fills the last block) less those below, in bytes modulo
// 256: exact, as at most 255 are at least t. (With a pad of 3, a region's
// odd last block of 4 took a 16-byte compare per pass, masked where its
// blocks were even, 12 instructions per pass for the four: 780x580 medians
// of four 1.49 -> 1.17 M instructions per decode without it and with the
// sums over the pixels in 32-byte vectors.)
//
// Their sums over each region's 8 pixels in 32-byte vectors, then the two
// halves added once.
[[gnu::target("arch=x86-64-v3")]] inline __m256i sumsOfFour256(__m256i c0, __m256i c1, __m256i c2, __m256i c3)
{
    const __m256i s0 = _mm256_add_epi8(_mm256_unpacklo_epi32(c0, c1), _mm256_unpackhi_epi32(c0, c1));
    const __m256i s1 = _mm256_add_epi8(_mm256_unpacklo_epi32(c2, c3), _mm256_unpackhi_epi32(c2, c3));
    return _mm256_add_epi8(_mm256_unpacklo_epi64(s0, s1), _mm256_unpackhi_epi64(s0, s1));
}

[[gnu::target("arch=x86-64-v3")]] std::array<std::uint32_t, 4> fourAlikeVersion(
    const std::array<const std::uint32_t*, 4>& pixels, const std::array<int, 4>& counts)
{
    const int blocks = (counts[0] + 7) / 8;  // 1-32
    const __m128i slots = _mm_set1_epi8(static_cast<char>(8 * blocks));
    const __m128i need = dwordsOf(needsOfFour(counts));
    const auto *p0 = reinterpret_cast<const std::uint8_t*>(pixels[0]), *p1 = reinterpret_cast<const std::uint8_t*>(pixels[1]),
               *p2 = reinterpret_cast<const std::uint8_t*>(pixels[2]), *p3 = reinterpret_cast<const std::uint8_t*>(pixels[3]);
    __m128i m = _mm_setzero_si128(), bit = firstBit();
    for (int pass = 0; pass < 8; ++pass, bit = nextBit(bit)) {
        // t ^ 0x80 in each byte: x < t as signed bytes of x = value ^ 0x80.
        const __m256i limits = _mm256_broadcastsi128_si256(_mm_xor_si128(_mm_or_si128(m, bit), _mm_set1_epi8(-128)));
        const __m256i l0 = _mm256_shuffle_epi32(limits, 0x00), l1 = _mm256_shuffle_epi32(limits, 0x55),
                      l2 = _mm256_shuffle_epi32(limits, 0xaa), l3 = _mm256_shuffle_epi32(limits, 0xff);
        __m256i c0 = _mm256_setzero_si256(), c1 = c0, c2 = c0, c3 = c0;
        // Blocks blocks - 1 down to 0 by a jump into straight-line code, as
        // forBlocksDown, over 32 blocks (STRIA_BLOCKS_DOWN_32).
#define STRIA_BELOW(c, l, p, b) \
    c = _mm256_add_epi8(c, _mm256_cmpgt_epi8(l, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p + 32 * (b)))))
#define STRIA_STEP(b) STRIA_FOUR_REGIONS(STRIA_BELOW, b)
        STRIA_BLOCKS_DOWN_32(blocks)
#undef STRIA_STEP
#undef STRIA_BELOW
        // Minus the counts below t (the compares' -1 added), plus the slots.
        const __m256i below = sumsOfFour256(c0, c1, c2, c3);
        const __m128i atLeast =
            _mm_add_epi8(slots, _mm_add_epi8(_mm256_castsi256_si128(below), _mm256_extracti128_si256(below, 1)));
        m = stepOfFour(m, bit, atLeast, need);
    }
    return dwords(_mm_and_si128(m, loadBytes(kThreeBytes)));
}

// The x86-64-v3 version of channelMedians for up to 32767 pixels (larger
// ones: the SSE2 body), as fourAlikeVersion: 8 pixels per compare, the
// values below t counted (2 instructions per 8 pixels, where the SSE2 body
// takes 3 per 4). The blocks' counts in byte lanes over chunks of up to 255
// blocks, summed per byte position in 16 bits; t is reached where at most
// slots - need are below it (slots = 8 * blocks, the pad entries below
// every t).
// blocksBelow: per byte lane, how many of the n (1-255) blocks of 8 pixels
// from bytes on are below the limit (a loop of 64 blocks per step entered by
// a jump into its body, as blockCounts; with 32 per step 1388x1038 had
// 3.3 k mispredictions more per decode, at the loop's exit). Inlined by
// force: called, each pass took ~30 instructions more.
[[gnu::target("arch=x86-64-v3"), gnu::always_inline]] inline __m256i blocksBelow(const std::uint8_t* bytes, int n, __m256i limit)
{
    __m256i c[4] = {_mm256_setzero_si256(), _mm256_setzero_si256(), _mm256_setzero_si256(), _mm256_setzero_si256()};
    // The first step takes the blocks past whole 64s (1-64: 64 as 0), its
    // block i at at + 32 i, entered at i = 64 - first.
    const int first = ((n - 1) & 63) + 1;
    int steps = (n + 63) / 64;
    std::ptrdiff_t at = 32 * static_cast<std::ptrdiff_t>(first - 64);
#define STRIA_COUNT(i) \
    c[(i) & 3] = _mm256_sub_epi8(c[(i) & 3], _mm256_cmpgt_epi8(limit, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(bytes + (at + 32 * (i))))))
    STRIA_BLOCKS_OF_64(first, steps, at, 32)
#undef STRIA_COUNT
    return _mm256_add_epi8(_mm256_add_epi8(c[0], c[1]), _mm256_add_epi8(c[2], c[3]));
}

// A byte-lane count's sums per byte position of a pixel, in 16-bit lanes 0-3.
[[gnu::target("arch=x86-64-v3")]] inline __m128i positionSums(__m256i counts)
{
    const __m256i zero = _mm256_setzero_si256();
    const __m256i words = _mm256_add_epi16(_mm256_unpacklo_epi8(counts, zero), _mm256_unpackhi_epi8(counts, zero));
    const __m128i sums = _mm_add_epi16(_mm256_castsi256_si128(words), _mm256_extracti128_si256(words, 1));
    return _mm_add_epi16(sums, _mm_srli_si128(sums, 8));
}

[[gnu::target("arch=x86-64-v3")]] std::array<std::uint8_t, 3> mediansVersion(const std::uint32_t* pixels, int count)
{
    if (count > 32767) return mediansBody(pixels, count);
    const auto* bytes = reinterpret_cast<const std::uint8_t*>(pixels);
    const int blocks = (count + 7) / 8;
    // t reached where below <= slots - need (unsigned: up to 32768).
    const __m128i most = _mm_set1_epi16(static_cast<short>(8 * blocks - (count - count / 2)));
    const int firstBlocks = std::min(blocks, 255);
    __m128i m = _mm_setzero_si128(), bit = firstBit();
    for (int pass = 0; pass < 8; ++pass, bit = nextBit(bit)) {
        // t ^ 0x80 in each byte (m's dwords alike).
        const __m256i limits = _mm256_broadcastsi128_si256(_mm_xor_si128(_mm_or_si128(m, bit), _mm_set1_epi8(-128)));
        // The first chunk before the loop (one loop over all chunks took
        // 0.08 M instructions more per 1388x1038 decode).
        __m128i below = positionSums(blocksBelow(bytes, firstBlocks, limits));
        for (int first = 255; first < blocks; first += 255)
            below = _mm_add_epi16(below, positionSums(blocksBelow(bytes + 32 * static_cast<std::ptrdiff_t>(first),
                                                                  std::min(blocks - first, 255), limits)));
        const __m128i reached = _mm_cmpeq_epi16(_mm_min_epu16(below, most), below);
        m = _mm_or_si128(m, _mm_and_si128(bit, _mm_shuffle_epi32(_mm_packs_epi16(reached, reached), 0)));
    }
    const auto v = static_cast<std::uint32_t>(_mm_cvtsi128_si32(m));
    return {static_cast<std::uint8_t>(v), static_cast<std::uint8_t>(v >> 8), static_cast<std::uint8_t>(v >> 16)};
}
#endif
}  // namespace
#endif

#if defined(__x86_64__)
namespace {
[[gnu::target("default")]] std::array<std::uint8_t, 3> mediansVersion(const std::uint32_t* pixels, int count)
{
    return mediansBody(pixels, count);
}
}  // namespace
#endif

std::array<std::uint8_t, 3> channelMedians(const std::uint32_t* pixels, int count)
{
#if defined(__x86_64__)
    return mediansVersion(pixels, count);
#else
    return mediansBody(pixels, count);
#endif
}

namespace {
// The SSE2 and NEON body.
std::array<std::uint8_t, 3> mediansBody(const std::uint32_t* pixels, int count)
{
#if defined(__ARM_NEON) || defined(__SSE2__)
    if (count <= 255) {
        ByteSearch s = startSearch(pixels, count);
        Bytes bit = firstBit();
        for (int pass = 0; pass < 8; ++pass, bit = nextBit(bit)) searchPass(s, bit);
        return searchResult(s);
    }
    if (count <= 4 * 255) {
        // Up to 255 blocks: one pass's counts in byte lanes (blockCounts),
        // summed over a block's 4 pixels in 16 bits, the step in vector
        // lanes: ~27 instructions per pass besides the blocks, where the
        // scalar steps below took ~75 (1388x1038, 1500 such regions per
        // decode: 8.40 -> 7.92 M instructions per decode).
        const auto* bytes = reinterpret_cast<const std::uint8_t*>(pixels);
        const int blocks = (count + 3) / 4;
        const Words need = wordsNeed(count - count / 2);
        Bytes m = zeroBytes(), bit = firstBit();
        for (int pass = 0; pass < 8; ++pass, bit = nextBit(bit))
            m = stepOfWords(m, bit, wordSums(blockCounts(bytes, blocks, limitsOf(m, bit))), need);
        const std::uint32_t v = dwords(m)[0];
        return {static_cast<std::uint8_t>(v), static_cast<std::uint8_t>(v >> 8), static_cast<std::uint8_t>(v >> 16)};
    }
    if (count <= 32767) {
        // The same over chunks of 255 blocks, their 16-bit sums added
        // (1388x1038, 665 chunks per decode: -0.08 M instructions
        // per decode; apart from the above, where the chunk loop cost more
        // than it saved here).
        const auto* bytes = reinterpret_cast<const std::uint8_t*>(pixels);
        const int blocks = (count + 3) / 4;
        const Words need = wordsNeed(count - count / 2);
        Bytes m = zeroBytes(), bit = firstBit();
        for (int pass = 0; pass < 8; ++pass, bit = nextBit(bit)) {
            const Bytes limit = limitsOf(m, bit);
            Words sums = wordSums(blockCounts(bytes, 255, limit));
            int first = 255;
            do {
                sums = addWords(sums, wordSums(blockCounts(bytes + 16 * first, std::min(blocks - first, 255), limit)));
                first += 255;
            } while (first < blocks);
            m = stepOfWords(m, bit, sums, need);
        }
        const std::uint32_t v = dwords(m)[0];
        return {static_cast<std::uint8_t>(v), static_cast<std::uint8_t>(v >> 8), static_cast<std::uint8_t>(v >> 16)};
    }
    // Larger regions: the counts summed in 16 bits per chunk of up to 254
    // blocks (the byte counters' limit), over the chunks in int. (A
    // histogram's increments wait on each other where neighbouring pixels
    // share a value, as in large uniform regions.)
    const int blocks = (count + 3) / 4;
    const auto* bytes = reinterpret_cast<const std::uint8_t*>(pixels);
    std::array<int, 3> m{};
    for (int bit = 128; bit > 0; bit >>= 1) {
        const std::array<int, 3> t{m[0] | bit, m[1] | bit, m[2] | bit};
        std::array<int, 3> notBelow{};
        for (int first = 0;; first += 254) {
            const int chunk = std::min(254, blocks - first);
            const bool last = first + chunk == blocks;
            const std::array<int, 3> part = countAtLeast(bytes + 16 * first, chunk, t);
            for (int k = 0; k < 3; ++k) notBelow[k] += part[k];
            if (last) break;
        }
        // At most count / 2 below t.
        for (int k = 0; k < 3; ++k) m[k] |= notBelow[k] >= count - count / 2 ? bit : 0;
    }
    return {static_cast<std::uint8_t>(m[0]), static_cast<std::uint8_t>(m[1]), static_cast<std::uint8_t>(m[2])};
#else
    return channelMediansReference(pixels, count);
#endif
}

#if defined(__ARM_NEON) || defined(__SSE2__)
// The 8 passes of four regions' median search, region j in dword j (of m,
// its medians so far, and of need): per pass, the four regions' counts at or
// above their limits from `passCounts(l0, l1, l2, l3)` (each limit in the
// three bytes of every dword), summed and compared together. The kernels
// below differ only in how they walk the regions' pixels.
struct FourCounts {
    Bytes c0, c1, c2, c3;
};
template <class PassCounts>
[[gnu::always_inline]] inline std::array<std::uint32_t, 4> searchFour(Bytes need, PassCounts passCounts)
{
    Bytes m = zeroBytes(), bit = firstBit();
    for (int pass = 0; pass < 8; ++pass, bit = nextBit(bit)) {
        const Bytes limits = limitsOf(m, bit);
        const FourCounts c = passCounts(dwordOf<0>(limits), dwordOf<1>(limits), dwordOf<2>(limits), dwordOf<3>(limits));
        m = stepOfFour(m, bit, sumsOfFour(c.c0, c.c1, c.c2, c.c3), need);
    }
    // Byte 3 of each dword: the search's junk, cleared.
    return dwords(bitAnd(m, loadBytes(kThreeBytes)));
}
#endif
}  // namespace

std::array<std::uint32_t, 4> channelMediansOfFour(const std::array<const std::uint32_t*, 4>& pixels,
                                                  const std::array<int, 4>& counts)
{
#if defined(__ARM_NEON) || defined(__SSE2__)
    if (std::max({counts[0], counts[1], counts[2], counts[3]}) <= 255) {
        // Each pass ends in a chain of dependent steps (the sums over the
        // pixels, the next limit), which the other regions' compares
        // overlap (780x580 medians 0.46 -> 0.42 ms, from two at a time).
        // The four take these steps together, region j's in dword j of m
        // (its medians so far) and need: the sums over each region's 4
        // pixels as a transposition, one compare for the four (780x580
        // medians of four 3.49 -> 3.08 M instructions per decode, 2.99 with
        // the unsigned divisions of the set-up).
        std::array<ByteSearch, 4> searches;
        for (int j = 0; j < 4; ++j) searches[j] = startSearch(pixels[j], counts[j]);
        return searchFour(dwordsOf(needsOfFour(counts)), [&](Bytes l0, Bytes l1, Bytes l2, Bytes l3)
                                                             __attribute__((always_inline)) {
            return FourCounts{passCounts(searches[0], l0), passCounts(searches[1], l1), passCounts(searches[2], l2),
                              passCounts(searches[3], l3)};
        });
    }
#endif
    std::array<std::uint32_t, 4> medians;
    for (int j = 0; j < 4; ++j) {
        const std::array<std::uint8_t, 3> v = channelMedians(pixels[j], counts[j]);
        medians[j] = v[0] | v[1] << 8 | v[2] << 16;
    }
    return medians;
}

namespace {
std::array<std::uint32_t, 4> fourAlikeBody(const std::array<const std::uint32_t*, 4>& pixels, const std::array<int, 4>& counts);
#if defined(__x86_64__)
[[gnu::target("default")]] std::array<std::uint32_t, 4> fourAlikeVersion(const std::array<const std::uint32_t*, 4>& pixels,
                                                                         const std::array<int, 4>& counts)
{
    return fourAlikeBody(pixels, counts);
}
#endif
}  // namespace

std::array<std::uint32_t, 4> channelMediansOfFourAlike(const std::array<const std::uint32_t*, 4>& pixels,
                                                       const std::array<int, 4>& counts)
{
#if defined(__x86_64__)
    return fourAlikeVersion(pixels, counts);
#else
    return fourAlikeBody(pixels, counts);
#endif
}

namespace {
// The SSE2 and NEON body.
std::array<std::uint32_t, 4> fourAlikeBody(const std::array<const std::uint32_t*, 4>& pixels, const std::array<int, 4>& counts)
{
#if defined(__aarch64__)
    // arm64: blocks of 8 pixels (kRegionPad 7), the two 16-byte halves of a
    // region's block at adjacent offsets, which GCC loads by one ldp (the
    // closest NEON has to AVX2's compares from memory): 5 instructions per
    // 8 pixels where two blocks of 4 took 6. As below otherwise; the
    // counts per byte lane are the same sums (modulo 256, at most 255).
    const int pairs = (counts[0] + 7) / 8;  // 1-32
    const auto *p0 = reinterpret_cast<const std::uint8_t*>(pixels[0]), *p1 = reinterpret_cast<const std::uint8_t*>(pixels[1]),
               *p2 = reinterpret_cast<const std::uint8_t*>(pixels[2]), *p3 = reinterpret_cast<const std::uint8_t*>(pixels[3]);
    return searchFour(dwordsOf(needsOfFour(counts)), [&](Bytes l0, Bytes l1, Bytes l2, Bytes l3)
                                                         __attribute__((always_inline)) {
        Bytes c0 = zeroBytes(), c1 = zeroBytes(), c2 = zeroBytes(), c3 = zeroBytes();
        // Blocks pairs - 1 down to 0 by a jump into straight-line code, as
        // forBlocksDown, over 32 blocks (STRIA_BLOCKS_DOWN_32).
#define STRIA_AT_LEAST(c, l, p, b) c = sub(c, add(atLeast(p + 32 * (b), l), atLeast(p + 32 * (b) + 16, l)))
#define STRIA_STEP(b) STRIA_FOUR_REGIONS(STRIA_AT_LEAST, b)
        STRIA_BLOCKS_DOWN_32(pairs)
#undef STRIA_STEP
#undef STRIA_AT_LEAST
        return FourCounts{c0, c1, c2, c3};
    });
#elif defined(__ARM_NEON) || defined(__SSE2__)
    // As channelMediansOfFour, the four regions' blocks in one walk per pass:
    // block b of each region in turn, one accumulator per region (four
    // independent chains), one jump per pass where channelMediansOfFour's
    // four walks took four, each to its own region's target (mispredicted
    // where the four differ).
    const int blocks = (counts[0] + 3) / 4;
    std::array<const std::uint8_t*, 4> bytes;
    for (int j = 0; j < 4; ++j) bytes[j] = reinterpret_cast<const std::uint8_t*>(pixels[j]);
    const std::uint8_t *p0 = bytes[0], *p1 = bytes[1], *p2 = bytes[2], *p3 = bytes[3];
    return searchFour(dwordsOf(needsOfFour(counts)), [&](Bytes l0, Bytes l1, Bytes l2, Bytes l3)
                                                         __attribute__((always_inline)) {
        Bytes c0 = zeroBytes(), c1 = zeroBytes(), c2 = zeroBytes(), c3 = zeroBytes();
        // Inlined in all 64 cases (GCC otherwise calls it from some, its
        // accumulators in memory).
        forBlocksDown(blocks, [&](int b) __attribute__((always_inline)) {
            c0 = sub(c0, atLeast(p0 + 16 * b, l0));
            c1 = sub(c1, atLeast(p1 + 16 * b, l1));
            c2 = sub(c2, atLeast(p2 + 16 * b, l2));
            c3 = sub(c3, atLeast(p3 + 16 * b, l3));
        });
        return FourCounts{c0, c1, c2, c3};
    });
#else
    return channelMediansOfFour(pixels, counts);
#endif
}

}  // namespace

}  // namespace stria::pipeline

#undef STRIA_BLOCKS_OF_64
#undef STRIA_FOUR_REGIONS
#undef STRIA_BLOCKS_DOWN_64
#undef STRIA_BLOCKS_DOWN_32
#undef STRIA_DOWN_LAST8
#undef STRIA_DOWN_BLOCKS8
#undef STRIA_DOWN_BLOCK
#undef STRIA_DUFF_BLOCKS8
#undef STRIA_DUFF_BLOCK
