// Watershed descent and row sweep kernels (pipeline/decoder/simd.hpp).
#include "pipeline/decoder/simd.hpp"

#include <algorithm>
#include <bit>
#include <cstring>
#include <utility>

#if defined(__ARM_NEON)
#include <arm_neon.h>
#elif defined(__x86_64__)
#include <immintrin.h>
#endif

namespace stria::pipeline {
namespace {

// Pixel x with the missing neighbours at the row's ends never lower (255).
inline void descentPixel(const std::uint8_t* up, const std::uint8_t* row, const std::uint8_t* down, int width, int x,
                         std::uint8_t* code)
{
    const std::uint8_t left = x > 0 ? row[x - 1] : 255, right = x + 1 < width ? row[x + 1] : 255;
    const std::uint8_t lowest = std::min(std::min(up[x], left), std::min(right, down[x]));
    const std::uint8_t direction = up[x] == lowest ? kDescentUp
                                   : left == lowest ? kDescentLeft
                                   : right == lowest ? kDescentRight
                                                     : kDescentDown;
    code[x] = lowest < row[x] ? direction : kDescentFlat;
}

#if !defined(__ARM_NEON)
// descentRow's block of pixels 0 to kDescentBlock - 1 of the pointers, in a
// loop GCC vectorises (ivdep: once inlined, it tested the pointers for
// overlap in every block, restrict or not).
constexpr int kDescentBlock = 32;
[[gnu::always_inline]] inline void descentBlock(const std::uint8_t* __restrict u, const std::uint8_t* __restrict c,
                                                const std::uint8_t* __restrict d, std::uint8_t* __restrict out)
{
#pragma GCC ivdep
    for (int i = 0; i < kDescentBlock; ++i) {
        const std::uint8_t lowest = std::min(std::min(u[i], c[i - 1]), std::min(c[i + 1], d[i]));
        std::uint8_t direction = c[i + 1] == lowest ? kDescentRight : kDescentDown;
        direction = c[i - 1] == lowest ? kDescentLeft : direction;
        direction = u[i] == lowest ? kDescentUp : direction;
        out[i] = lowest < c[i] ? direction : kDescentFlat;
    }
}
#endif

}  // namespace

void descentRowReference(const std::uint8_t* up, const std::uint8_t* row, const std::uint8_t* down, int width,
                         std::uint8_t* code)
{
    for (int x = 0; x < width; ++x) descentPixel(up, row, down, width, x, code);
}

// (x86-64: clones for AVX2 and AVX-512, whose vectorised loop takes 32 or 64
// pixels per step.)
STRIA_X86_CLONES void descentRow(const std::uint8_t* up, const std::uint8_t* row, const std::uint8_t* down, int width,
                                 std::uint8_t* code)
{
    if (width < 3) {
        descentRowReference(up, row, down, width, code);
        return;
    }
    descentPixel(up, row, down, width, 0, code);
    int x = 1;
    // Pixels 1 to width - 2 in blocks; where the row does not divide into
    // them, a last block ends at pixel width - 2, over pixels done already
    // (they get the same codes again), instead of a tail pixel by pixel,
    // whose branches on the levels mispredicted (the blocks took 0.15 M
    // instructions and 2.4 k mispredictions off a 780x580 decode on x86-64).
#if defined(__ARM_NEON)
    // 16 pixels at once: the lowest neighbour by vminq, its direction by
    // selects in reverse tie order (the last select wins), all in byte lanes.
    const uint8x16_t toUp = vdupq_n_u8(kDescentUp), toLeft = vdupq_n_u8(kDescentLeft),
                     toRight = vdupq_n_u8(kDescentRight), toDown = vdupq_n_u8(kDescentDown),
                     flat = vdupq_n_u8(kDescentFlat);
    auto block = [&](int x) {
        const uint8x16_t u = vld1q_u8(up + x), l = vld1q_u8(row + x - 1), c = vld1q_u8(row + x),
                         r = vld1q_u8(row + x + 1), d = vld1q_u8(down + x);
        const uint8x16_t lowest = vminq_u8(vminq_u8(u, l), vminq_u8(r, d));
        uint8x16_t direction = vbslq_u8(vceqq_u8(r, lowest), toRight, toDown);
        direction = vbslq_u8(vceqq_u8(l, lowest), toLeft, direction);
        direction = vbslq_u8(vceqq_u8(u, lowest), toUp, direction);
        vst1q_u8(code + x, vbslq_u8(vcltq_u8(lowest, c), direction, flat));
    };
    constexpr int kBlock = 16;
#else
    // The same selects in a loop GCC vectorises (SSE2 byte lanes on x86-64;
    // the block's fixed length: no scalar tail of its own).
    constexpr int kBlock = kDescentBlock;
    auto block = [&](int x) { descentBlock(up + x, row + x, down + x, code + x); };
#endif
    if (width >= kBlock + 2) {
        for (; x + kBlock < width; x += kBlock) block(x);
        if (x < width - 1) block(width - 1 - kBlock);
        x = width - 1;
    }
    for (; x < width; ++x) descentPixel(up, row, down, width, x, code);
}

namespace {

// Whether the code's arrow (plateau, minimum or not) points in the
// direction: bits kPlateauArrow and kMinimumArrow ignored, bit 3
// (kDescentFlat) kept.
constexpr std::uint8_t kArrowBits = 0xff & ~kPlateauArrow & ~kMinimumArrow;

// Four labels or lane masks, in GCC's vector extensions: one source for the
// SSE2 and (32-bit ARM) NEON instructions (shuffles, compares, and/or). The x86-64-v3/v4
// versions of the sweeps take eight (Lanes8, below): a block's prefix scan
// in 3 steps instead of 2 (resolveWithCarry), but half the blocks, so half
// the steps of the carry chain per row.
using Lanes = std::int32_t __attribute__((vector_size(16)));

// The helpers below take and return 8-lane vectors too: GCC warns that their
// ABI differs without AVX, but they are always inlined, into the AVX2/AVX-512
// versions only (file-local, never called through the ABI).
#pragma GCC diagnostic ignored "-Wpsabi"

template <typename V>
constexpr int kLanes = sizeof(V) / sizeof(std::int32_t);

template <typename V>
[[gnu::always_inline]] inline V load(const std::int32_t* p)
{
    V v;
    std::memcpy(&v, p, sizeof v);
    return v;
}

template <typename V>
[[gnu::always_inline]] inline void store(std::int32_t* p, V v) { std::memcpy(p, &v, sizeof v); }

// a in the lanes of mask m (-1), else b. (The vector ternary would compare m
// with 0 first; in 8 lanes, on the sign bit, it is one vblendvps, where GCC
// made 3 instructions of the and-or.)
template <typename V>
[[gnu::always_inline]] inline V select(V m, V a, V b)
{
    if constexpr (sizeof(V) == 32)
        return m < 0 ? a : b;
    else
        return (a & m) | (b & ~m);
}

// Shuffle indices: lane i takes lane i - shift (i + shift when shift < 0),
// itself where that is outside the block; or `lane` in every lane.
template <typename V, int... i>
consteval V shifted(int shift, std::integer_sequence<int, i...>)
{
    return V{(i - shift >= 0 && i - shift < kLanes<V> ? i - shift : i)...};
}

template <typename V>
consteval V shifted(int shift)
{
    return shifted<V>(shift, std::make_integer_sequence<int, kLanes<V>>());
}

template <typename V, int... i>
consteval V everyLane(int lane, std::integer_sequence<int, i...>)
{
    return V{(static_cast<void>(i), lane)...};
}

template <typename V>
consteval V everyLane(int lane)
{
    return everyLane<V>(lane, std::make_integer_sequence<int, kLanes<V>>());
}

#if defined(__x86_64__)
// The AVX helpers of the 8-lane sweeps below: not always_inline, as the
// templates that call them are compiled for the baseline (an AVX intrinsic
// could not be inlined there); GCC inlines them into the AVX versions that
// inline the templates. (__builtin_convertvector made 40 instructions of
// lane inserts of zeroExtend8.)
[[gnu::target("avx2")]] inline __m256i zeroExtend8(const std::uint8_t* p)
{
    return _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p)));
}
[[gnu::target("avx")]] inline unsigned signBits8(__m256 v) { return static_cast<unsigned>(_mm256_movemask_ps(v)); }
[[gnu::target("avx2")]] inline __m256i signExtend8(const std::int8_t* p)
{
    return _mm256_cvtepi8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p)));
}
#endif

// The codes of a block of 4 in each lane (byte k = pixel k, the next 4 in
// the next 4 lanes): lane k's byte k % 4 is pixel k's code, so one
// and-compare per direction gives the lane masks, without widening the bytes.
// 8 lanes (AVX2, AVX-512): lane k is pixel k's code, zero-extended by one
// vpmovzxbd (the codes in lane k's byte k % 4, as for 4 lanes, took a
// vpbroadcastq and a vpermd more).
template <typename V>
[[gnu::always_inline]] inline V codesOf(const std::uint8_t* code)
{
    static_assert(std::endian::native == std::endian::little, "byte k of the word is pixel k");
#if defined(__x86_64__)
    if constexpr (kLanes<V> == 8) return reinterpret_cast<V>(zeroExtend8(code));
#endif
    V v;
    for (int i = 0; i < kLanes<V>; i += 4) {
        std::int32_t c;
        std::memcpy(&c, code + i, sizeof c);
        for (int k = 0; k < 4; ++k) v[i + k] = c;
    }
    return v;
}

// -1 in the lanes whose code has an arrow in the direction, else 0.
template <typename V>
[[gnu::always_inline]] inline V arrowsIn(V codes, std::uint8_t direction)
{
    constexpr auto byteK = [](std::uint32_t value) {
        V v{};
        for (int i = 0; i < kLanes<V>; ++i)
            v[i] = static_cast<std::int32_t>(kLanes<V> == 8 ? value : value << (8 * (i % 4)));
        return v;
    };
    return (codes & byteK(kArrowBits)) == byteK(direction);
}

// 4 lanes: stores v with carry in the lanes of m and returns the label the
// next block takes, lane `last` of the stored block in every lane. The chain
// from block to block is this carry alone. On x86-64 (SSE2) it is (carry &
// m's last lane) | (own's last lane), the broadcasts off the chain (in the
// AVX-512 version, before it took resolveWithCarry, one vpternlogd: watershed
// 1.37 -> 1.21 ms at 780x580, where a select then a broadcast took 3
// dependent instructions). On other targets (32-bit ARM: a vbsl then a dup)
// the select then the broadcast; arm64 has its own sweeps (sweepNeon, below).
// (stored: the block as stored, for the unresolved mask of the last sweep.)
template <int last, typename V>
[[gnu::always_inline]] inline V storeWithCarry(std::int32_t* out, V m, V v, V carry, V& stored)
{
    constexpr V lastLane = everyLane<V>(last);
#if defined(__x86_64__)
    const V own = v & ~m;
    stored = own | (carry & m);
    store(out, stored);
    return (carry & __builtin_shuffle(m, lastLane)) | __builtin_shuffle(own, lastLane);
#else
    stored = select(m, carry, v);
    store(out, stored);
    return __builtin_shuffle(stored, lastLane);
#endif
}

// Bit i set if lane i of v is negative (kUnresolved): on x86-64 by
// movmskps, the sign bits of the lanes (GCC's own lane-by-lane reduction of a
// compare took 20 instructions). 8 lanes (the AVX2 and AVX-512 versions): one
// vmovmskps of all 8, where two SSE ones of the halves took 6 instructions
// with the extract and the or. (The builtin, not _mm256_movemask_ps: an AVX
// intrinsic could not be inlined into this template, compiled for the
// baseline; the builtin is expanded only where the template is inlined, in
// the AVX versions.)
template <typename V>
[[gnu::always_inline]] inline std::uint64_t negativeBits(V v)
{
#if defined(__x86_64__)
    if constexpr (kLanes<V> == 8)
        return signBits8(reinterpret_cast<__m256>(v));
    std::uint64_t bits = 0;
    for (int i = 0; i < kLanes<V>; i += 4) {
        __m128 quarter;
        std::memcpy(&quarter, reinterpret_cast<const char*>(&v) + 4 * i, sizeof quarter);
        bits |= std::uint64_t{static_cast<unsigned>(_mm_movemask_ps(quarter))} << i;
    }
    return bits;
#else
    // Lane i's weight 2^i, summed. (arm64 has its own sweeps, below.)
    static_assert(kLanes<V> == 4);
    const V bits = (v >> 31) & V{1, 2, 4, 8};
    return static_cast<std::uint64_t>(bits[0] + bits[1] + bits[2] + bits[3]);
#endif
}

// One step of a block's prefix scan: lane i takes lane i - shift's label
// (i + |shift| when shift < 0) while its mask is set, and keeps its mask
// only if that lane's was set too.
template <int shift, typename V>
[[gnu::always_inline]] inline void scanStep(V& v, V& m)
{
    constexpr V index = shifted<V>(shift);
    v = select(m, __builtin_shuffle(v, index), v);
    m &= __builtin_shuffle(m, index);
}

// 8 lanes (the AVX2 and AVX-512 versions): a block's labels with the lanes
// of mask m copying their left neighbour's (right: their right neighbour's)
// as it is by then, and the carry (the label beyond the block, in every lane)
// where the copies lead out of the block, in one permute: lane i takes the
// label of the nearest lane at or left of it (right: at or right of it) that
// keeps its own, -1 where there is none; vpermd takes that lane's label
// (index -1: lane 7's, replaced) and a select on the index's sign bit the
// carry. The source lanes depend on the 8 mask bits alone: a table of them
// per mask (kCopySources, bytes sign-extended by one vpmovsxbd), indexed by
// the mask's vmovmskps, where a prefix maximum over the lanes (the lane's
// own index or -1; 3 shuffle and max steps, right: an unsigned minimum)
// took 7 instructions per block instead of 2 (sweepRow per 780x580 decode
// 2.48 -> 1.91 M instructions, the 4 KB of tables 0.3 k more D1 misses).
// (Scalar reference: the second loop of sweepRowUpLeftReference, the third
// of sweepRowReference.)
#if defined(__x86_64__)
struct CopySources {
    std::int8_t left[256][8];   // lane i: the largest j <= i whose mask bit is clear, else -1
    std::int8_t right[256][8];  // lane i: the smallest j >= i whose mask bit is clear, else -1
};

consteval CopySources copySources()
{
    CopySources t{};
    for (int mask = 0; mask < 256; ++mask)
        for (int i = 0; i < 8; ++i) {
            int left = -1, right = -1;
            for (int j = i; j >= 0 && left < 0; --j)
                if ((mask >> j & 1) == 0) left = j;
            for (int j = i; j < 8 && right < 0; ++j)
                if ((mask >> j & 1) == 0) right = j;
            t.left[mask][i] = static_cast<std::int8_t>(left);
            t.right[mask][i] = static_cast<std::int8_t>(right);
        }
    return t;
}

alignas(64) constexpr CopySources kCopySources = copySources();
#endif

template <bool right, typename V>
[[gnu::always_inline]] inline V resolveWithCarry(V v, V m, V carry)
{
    static_assert(kLanes<V> == 8);
#if defined(__x86_64__)
    const unsigned bits = signBits8(reinterpret_cast<__m256>(m));
    const V source = reinterpret_cast<V>(signExtend8(right ? kCopySources.right[bits] : kCopySources.left[bits]));
    return source < 0 ? carry : __builtin_shuffle(v, source);
#else
    static_assert(!sizeof(V), "8 lanes only in the x86-64 versions");
#endif
}

// A pixel copying its neighbour's label after the neighbour's own copy is a
// serial chain: as selects per pixel, 3 dependent instructions each. Here a
// block resolves its runs by a prefix scan in log2(lanes) shuffle steps (lane
// i takes lane i - 1, then i - 2, ..., while its mask is set), and only the
// lanes that copy from beyond the block (their mask still set) take the
// previous block's label (storeWithCarry); 8 lanes by resolveWithCarry.
template <typename V>
[[gnu::always_inline]] inline void upLeftLanes(const std::uint8_t* code, const std::int32_t* above, std::int32_t* row,
                                               int width)
{
    constexpr int n = kLanes<V>;
    const int blocks = width & ~(n - 1);
    V carry = V{} + kUnresolved;  // the label left of the block, in every lane
    for (int x = 0; x < blocks; x += n) {
        const V codes = codesOf<V>(code + x);
        V v = select(arrowsIn(codes, kDescentUp), load<V>(above + x), load<V>(row + x));
        V m = arrowsIn(codes, kDescentLeft);
        if constexpr (n == 8) {
            const V stored = resolveWithCarry<false>(v, m, carry);
            store(row + x, stored);
            carry = __builtin_shuffle(stored, everyLane<V>(n - 1));
        } else {
            scanStep<1>(v, m);
            scanStep<2>(v, m);
            V stored;
            carry = storeWithCarry<n - 1>(row + x, m, v, carry, stored);
        }
    }
    std::int32_t previous = carry[0];
    for (int x = blocks; x < width; ++x) {
        if ((code[x] & kArrowBits) == kDescentUp) row[x] = above[x];
        if ((code[x] & kArrowBits) == kDescentLeft) row[x] = previous;
        previous = row[x];
    }
}

// The same from the right (the tail first), lanes mirrored. (Written out
// twice on purpose: one always_inline scan for both directions, with the
// shuffle masks as arguments, cost 3 % more instructions in this kernel.)
// The last sweep also marks the pixels left unresolved (negative labels: in
// the watershed, whose path leads down), as each block is final when stored:
// sign-bit masks, where a pass of 16-label compares over the row took 4 times
// more instructions.
template <typename V>
[[gnu::always_inline]] inline void sweepLanes(const std::uint8_t* code, const std::int32_t* above, std::int32_t* row,
                                              int width, std::uint64_t* unresolved)
{
    upLeftLanes<V>(code, above, row, width);
    constexpr int n = kLanes<V>;
    const int blocks = width & ~(n - 1);
    for (int k = 0; k < (width + 63) / 64; ++k) unresolved[k] = 0;
    std::int32_t next = kUnresolved;
    for (int x = width - 1; x >= blocks; --x) {
        if ((code[x] & kArrowBits) == kDescentRight) row[x] = next;
        next = row[x];
        unresolved[x >> 6] |= std::uint64_t{next < 0} << (x & 63);
    }
    V carry = V{} + next;
    // (x as std::ptrdiff_t: its word index without a sign extension per block.)
    for (std::ptrdiff_t x = blocks - n; x >= 0; x -= n) {
        V v = load<V>(row + x);
        V m = arrowsIn(codesOf<V>(code + x), kDescentRight);
        V stored;
        if constexpr (n == 8) {
            stored = resolveWithCarry<true>(v, m, carry);
            store(row + x, stored);
            carry = __builtin_shuffle(stored, everyLane<V>(0));
        } else {
            scanStep<-1>(v, m);
            scanStep<-2>(v, m);
            carry = storeWithCarry<0>(row + x, m, v, carry, stored);
        }
        // Blocks of 4 or 8 at multiples of their size: never across a word.
        unresolved[x >> 6] |= negativeBits(stored) << (x & 63);
    }
}

#if defined(__x86_64__)
// x86-64: 4 lanes in SSE2, 8 in the AVX2 and AVX-512 versions (picked at run
// time by GCC's function multiversioning, an ifunc each; target_clones cannot
// give its clones different bodies).
using Lanes8 = std::int32_t __attribute__((vector_size(32)));

[[gnu::target("default")]] void upLeftVersion(const std::uint8_t* c, const std::int32_t* a, std::int32_t* r, int w)
{
    upLeftLanes<Lanes>(c, a, r, w);
}
[[gnu::target("arch=x86-64-v3")]] void upLeftVersion(const std::uint8_t* c, const std::int32_t* a, std::int32_t* r,
                                                      int w)
{
    upLeftLanes<Lanes8>(c, a, r, w);
}
[[gnu::target("arch=x86-64-v4")]] void upLeftVersion(const std::uint8_t* c, const std::int32_t* a, std::int32_t* r,
                                                      int w)
{
    upLeftLanes<Lanes8>(c, a, r, w);
}
[[gnu::target("default")]] void sweepVersion(const std::uint8_t* c, const std::int32_t* a, std::int32_t* r, int w,
                                             std::uint64_t* u)
{
    sweepLanes<Lanes>(c, a, r, w, u);
}
[[gnu::target("arch=x86-64-v3")]] void sweepVersion(const std::uint8_t* c, const std::int32_t* a, std::int32_t* r,
                                                     int w, std::uint64_t* u)
{
    sweepLanes<Lanes8>(c, a, r, w, u);
}
[[gnu::target("arch=x86-64-v4")]] void sweepVersion(const std::uint8_t* c, const std::int32_t* a, std::int32_t* r,
                                                     int w, std::uint64_t* u)
{
    sweepLanes<Lanes8>(c, a, r, w, u);
}
#endif

#if defined(__aarch64__)
// arm64: the same sweeps in NEON intrinsics, 4 labels per q register, in
// fewer instructions per block than GCC made of the generic template above
// (its shuffles became 2-register tbl lookups with 2 register copies each,
// the codes a movi and 4 lane inserts: 31 + 37 instructions per block, 17
// per pixel; here 18 + 15 per block and the bits' pass, about 8.5 per pixel,
// sweepRow per 780x580 decode 7.73 -> 3.99 M instructions):
// - a block's codes by one broadcast, and-compares as codesOf/arrowsIn;
// - the run scan resolved to one table lookup: each lane holds its own
//   labels' byte indices (byte k of lane i: 4 i + k), or -1 (0xff bytes,
//   outside the table) where its mask is set. A prefix max over the lanes
//   (2 ext + smax steps, -1 shifted in) gives each lane the indices of the
//   nearest lane at or left of it that keeps its own label; tbx copies that
//   lane's label and leaves the carry (the destination) where the indices
//   are -1: the lanes that copy from beyond the block. The right sweep the
//   same mirrored: unsigned min, 0xffffffff shifted in from the right;
// - the unresolved bits by a pass over the finished row, 64 labels per word:
//   ld4 deinterleaves the labels' bytes, so its 4th register holds the 16
//   top bytes (sign bits) in pixel order; byteMask64 (simd.hpp) makes the
//   64 bits of four of them (17 instructions per word, where
//   the per-block sign bits (cmlt, and, addv) and the word's or took 9 per 4).

// value in byte k of lane k.
constexpr uint32x4_t byteK(std::uint32_t value) { return uint32x4_t{value, value << 8, value << 16, value << 24}; }

// Lane k's byte k is pixel k's code (a broadcast of the 4 codes), the other
// bytes and bits kPlateauArrow and kMinimumArrow cleared.
[[gnu::always_inline]] inline uint32x4_t maskedCodes(const std::uint8_t* code)
{
    static_assert(std::endian::native == std::endian::little, "byte k of the word is pixel k");
    using Unaligned = std::uint32_t __attribute__((aligned(1), may_alias));  // one ld1r
    return vandq_u32(vdupq_n_u32(*reinterpret_cast<const Unaligned*>(code)), byteK(kArrowBits));
}

// -1 in the lanes whose (masked) code is the direction, else 0.
[[gnu::always_inline]] inline uint32x4_t arrowsMask(uint32x4_t codes, std::uint8_t direction)
{
    return vceqq_u32(codes, byteK(direction));
}

// Byte k of lane i: 4 i + k, lane i's label's bytes in a tbl/tbx lookup.
constexpr uint32x4_t kLaneBytes = {0x03020100, 0x07060504, 0x0b0a0908, 0x0f0e0d0c};

// The labels of a block with the lanes of mask m copying their left
// neighbour's (lane 0: the carry's, the label left of the block in every
// lane) as it is by then (scalar reference: the second loop of
// sweepRowUpLeftReference).
[[gnu::always_inline]] inline int32x4_t copyLeft(int32x4_t v, uint32x4_t m, int32x4_t carry)
{
    const int32x4_t none = vdupq_n_s32(-1);
    int32x4_t source = vreinterpretq_s32_u32(vorrq_u32(m, kLaneBytes));
    source = vmaxq_s32(source, vextq_s32(none, source, 3));
    source = vmaxq_s32(source, vextq_s32(none, source, 2));
    return vreinterpretq_s32_u8(vqtbx1q_u8(vreinterpretq_u8_s32(carry), vreinterpretq_u8_s32(v),
                                           vreinterpretq_u8_s32(source)));
}

// The same from the right (lane 3: the carry's).
[[gnu::always_inline]] inline int32x4_t copyRight(int32x4_t v, uint32x4_t m, int32x4_t carry)
{
    const uint32x4_t none = vdupq_n_u32(~0u);
    uint32x4_t source = vorrq_u32(m, kLaneBytes);
    source = vminq_u32(source, vextq_u32(source, none, 1));
    source = vminq_u32(source, vextq_u32(source, none, 2));
    return vreinterpretq_s32_u8(vqtbx1q_u8(vreinterpretq_u8_s32(carry), vreinterpretq_u8_s32(v),
                                           vreinterpretq_u8_u32(source)));
}

// 8 labels per step, as two blocks of 4 whose copy sources (copyLeft's and
// copyRight's prefix max, 5 instructions per block) come from a table
// indexed by the block's 4 mask bits instead: the 8 codes' masks by one byte
// compare, and with the bit weights and addv (3 instructions per 8 pixels),
// each half's 4 bits by one and or shift, its entry by one load. A table of
// 8-bit masks with a 2-register tbx per half took more: GCC copied the two
// labels registers into two consecutive pairs, one per tbx.
// 27 instructions per 8 pixels in the left sweep and 23 in the right one,
// where two blocks of 4 took 36 and 32 (watershed per 780x580 decode 8.51 ->
// 7.57 M instructions). The tables: 512 bytes.
// (Scalar reference: the second loop of sweepRowUpLeftReference, the third
// of sweepRowReference; copyLeft and copyRight above, the same for a block of
// 4 alone, do the block left over when the row does not divide by 8.)

// Entry m, lane i: bytes 4 j + k, j the largest j <= i whose bit in m is
// clear (right: the smallest j >= i); 0xff where there is none. (Two arrays:
// each entry's address in the loops one and or shift of the bits from its
// array's base.)
using CopyTable = std::array<std::array<std::uint8_t, 16>, 16>;

consteval CopyTable copyTable(bool right)
{
    CopyTable t{};
    for (int mask = 0; mask < 16; ++mask)
        for (int i = 0; i < 4; ++i) {
            int source = -1;
            for (int j = i; j >= 0 && j < 4 && source < 0; j += right ? 1 : -1)
                if ((mask >> j & 1) == 0) source = j;
            for (int k = 0; k < 4; ++k)
                t[mask][4 * i + k] = static_cast<std::uint8_t>(source < 0 ? 0xff : 4 * source + k);
        }
    return t;
}

alignas(64) constexpr CopyTable kCopyLeft = copyTable(false);
alignas(64) constexpr CopyTable kCopyRight = copyTable(true);

// The 8 codes at c with bits kPlateauArrow and kMinimumArrow cleared.
[[gnu::always_inline]] inline uint8x8_t maskedCodes8(const std::uint8_t* c)
{
    return vand_u8(vld1_u8(c), vdup_n_u8(kArrowBits));
}

// Bit i set where code i is the direction.
[[gnu::always_inline]] inline unsigned arrowBits8(uint8x8_t codes, std::uint8_t direction)
{
    const uint8x8_t weights = vcreate_u8(0x8040201008040201ull);
    return vaddv_u8(vand_u8(vceq_u8(codes, vdup_n_u8(direction)), weights));
}

// A block's labels v with each lane's from its source in the table entry,
// the carry's where that is 0xff.
[[gnu::always_inline]] inline int32x4_t copyFromTable(const std::uint8_t* entry, int32x4_t v, int32x4_t carry)
{
    return vreinterpretq_s32_u8(vqtbx1q_u8(vreinterpretq_u8_s32(carry), vreinterpretq_u8_s32(v), vld1q_u8(entry)));
}

void upLeftNeon(const std::uint8_t* code, const std::int32_t* above, std::int32_t* row, int width)
{
    const int blocks8 = width & ~7, blocks = width & ~3;
    int32x4_t carry = vdupq_n_s32(kUnresolved);
    // (Pointers: post-indexed loads and stores, 2 instructions of loop per block.)
    const std::uint8_t* c = code;
    const std::int32_t* a = above;
    for (std::int32_t* r = row; r != row + blocks8; c += 8, a += 8, r += 8) {
        const uint8x8_t codes = maskedCodes8(c);
        // The up lanes' masks: the byte compare widened to 32 bits.
        const int16x8_t up = vmovl_s8(vreinterpret_s8_u8(vceq_u8(codes, vdup_n_u8(kDescentUp))));
        int32x4_t lo = vbslq_s32(vreinterpretq_u32_s32(vmovl_s16(vget_low_s16(up))), vld1q_s32(a), vld1q_s32(r));
        int32x4_t hi = vbslq_s32(vreinterpretq_u32_s32(vmovl_high_s16(up)), vld1q_s32(a + 4), vld1q_s32(r + 4));
        const unsigned bits = arrowBits8(codes, kDescentLeft);
        lo = copyFromTable(kCopyLeft[bits & 15].data(), lo, carry);
        hi = copyFromTable(kCopyLeft[bits >> 4].data(), hi, vdupq_laneq_s32(lo, 3));
        vst1q_s32(r, lo);
        vst1q_s32(r + 4, hi);
        carry = vdupq_laneq_s32(hi, 3);
    }
    if (blocks > blocks8) {
        const uint32x4_t codes = maskedCodes(code + blocks8);
        const int32x4_t v =
            vbslq_s32(arrowsMask(codes, kDescentUp), vld1q_s32(above + blocks8), vld1q_s32(row + blocks8));
        vst1q_s32(row + blocks8, copyLeft(v, arrowsMask(codes, kDescentLeft), carry));
    }
    std::int32_t previous = blocks > 0 ? row[blocks - 1] : kUnresolved;
    for (int x = blocks; x < width; ++x) {
        if ((code[x] & kArrowBits) == kDescentUp) row[x] = above[x];
        if ((code[x] & kArrowBits) == kDescentLeft) row[x] = previous;
        previous = row[x];
    }
}

// 0xff in byte k where label k of the 16 at p is negative: byte k of the 4th
// ld4 register is label k's top byte.
[[gnu::always_inline]] inline uint8x16_t negativeBytes(const std::int32_t* p)
{
    const uint8x16x4_t bytes = vld4q_u8(reinterpret_cast<const std::uint8_t*>(p));
    return vreinterpretq_u8_s8(vshrq_n_s8(vreinterpretq_s8_u8(bytes.val[3]), 7));
}

void sweepNeon(const std::uint8_t* code, const std::int32_t* above, std::int32_t* row, int width,
               std::uint64_t* unresolved)
{
    upLeftNeon(code, above, row, width);
    const int blocks = width & ~3;
    std::int32_t next = kUnresolved;
    for (int x = width - 1; x >= blocks; --x) {
        if ((code[x] & kArrowBits) == kDescentRight) row[x] = next;
        next = row[x];
    }
    int32x4_t carry = vdupq_n_s32(next);
    const int blocks8 = width & ~7;
    if (blocks > blocks8) {
        const int32x4_t stored =
            copyRight(vld1q_s32(row + blocks8), arrowsMask(maskedCodes(code + blocks8), kDescentRight), carry);
        vst1q_s32(row + blocks8, stored);
        carry = vdupq_laneq_s32(stored, 0);
    }
    for (int x = blocks8 - 8; x >= 0; x -= 8) {
        int32x4_t hi = vld1q_s32(row + x + 4), lo = vld1q_s32(row + x);
        const unsigned bits = arrowBits8(maskedCodes8(code + x), kDescentRight);
        hi = copyFromTable(kCopyRight[bits >> 4].data(), hi, carry);
        lo = copyFromTable(kCopyRight[bits & 15].data(), lo, vdupq_laneq_s32(hi, 0));
        vst1q_s32(row + x, lo);
        vst1q_s32(row + x + 4, hi);
        carry = vdupq_laneq_s32(lo, 0);
    }
    // The unresolved bits (negative labels), 64 per word, then 16, then 1.
    int x = 0;
    for (; x + 64 <= width; x += 64)
        unresolved[x >> 6] = byteMask64(negativeBytes(row + x), negativeBytes(row + x + 16),
                                        negativeBytes(row + x + 32), negativeBytes(row + x + 48));
    if (x == width) return;
    std::uint64_t word = 0;
    const uint8x16_t weights = {1, 2, 4, 8, 16, 32, 64, 128, 1, 2, 4, 8, 16, 32, 64, 128};  // as byteMask64's
    for (; x + 16 <= width; x += 16) {
        const uint8x16_t w = vandq_u8(negativeBytes(row + x), weights), pairs = vpaddq_u8(w, w),
                         quads = vpaddq_u8(pairs, pairs);
        word |= std::uint64_t{vgetq_lane_u16(vreinterpretq_u16_u8(vpaddq_u8(quads, quads)), 0)} << (x & 63);
    }
    for (; x < width; ++x) word |= std::uint64_t{row[x] < 0} << (x & 63);
    unresolved[(width - 1) >> 6] = word;
}
#endif

}  // namespace

void sweepRowUpLeftReference(const std::uint8_t* code, const std::int32_t* above, std::int32_t* row, int width)
{
    for (int x = 0; x < width; ++x)
        if ((code[x] & kArrowBits) == kDescentUp) row[x] = above[x];
    for (int x = 0; x < width; ++x)
        if ((code[x] & kArrowBits) == kDescentLeft) row[x] = x > 0 ? row[x - 1] : kUnresolved;
}

void sweepRowReference(const std::uint8_t* code, const std::int32_t* above, std::int32_t* row, int width,
                       std::uint64_t* unresolved)
{
    sweepRowUpLeftReference(code, above, row, width);
    for (int x = width - 1; x >= 0; --x)
        if ((code[x] & kArrowBits) == kDescentRight) row[x] = x + 1 < width ? row[x + 1] : kUnresolved;
    for (int k = 0; k < (width + 63) / 64; ++k) unresolved[k] = 0;
    for (int x = 0; x < width; ++x) unresolved[x / 64] |= std::uint64_t{row[x] < 0} << (x % 64);
}

void sweepRowUpLeft(const std::uint8_t* code, const std::int32_t* above, std::int32_t* row, int width)
{
#if defined(__x86_64__)
    upLeftVersion(code, above, row, width);
#elif defined(__aarch64__)
    upLeftNeon(code, above, row, width);
#else
    upLeftLanes<Lanes>(code, above, row, width);
#endif
}

void sweepRow(const std::uint8_t* code, const std::int32_t* above, std::int32_t* row, int width,
              std::uint64_t* unresolved)
{
#if defined(__x86_64__)
    sweepVersion(code, above, row, width, unresolved);
#elif defined(__aarch64__)
    sweepNeon(code, above, row, width, unresolved);
#else
    sweepLanes<Lanes>(code, above, row, width, unresolved);
#endif
}

}  // namespace stria::pipeline
