// Watershed descent and row sweep kernels (pipeline/decoder/simd.hpp).
#include "pipeline/decoder/simd.hpp"

#include <algorithm>
#include <bit>
#include <cstring>

#if defined(__ARM_NEON)
#include <arm_neon.h>
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

}  // namespace

void descentRowReference(const std::uint8_t* up, const std::uint8_t* row, const std::uint8_t* down, int width,
                         std::uint8_t* code)
{
    for (int x = 0; x < width; ++x) descentPixel(up, row, down, width, x, code);
}

void descentRow(const std::uint8_t* up, const std::uint8_t* row, const std::uint8_t* down, int width,
                std::uint8_t* code)
{
    if (width < 3) {
        descentRowReference(up, row, down, width, code);
        return;
    }
    descentPixel(up, row, down, width, 0, code);
    int x = 1;
#if defined(__ARM_NEON)
    // 16 pixels at once: the lowest neighbour by vminq, its direction by
    // selects in reverse tie order (the last select wins), all in byte lanes.
    const uint8x16_t toUp = vdupq_n_u8(kDescentUp), toLeft = vdupq_n_u8(kDescentLeft),
                     toRight = vdupq_n_u8(kDescentRight), toDown = vdupq_n_u8(kDescentDown),
                     flat = vdupq_n_u8(kDescentFlat);
    for (; x + 16 < width; x += 16) {
        const uint8x16_t u = vld1q_u8(up + x), l = vld1q_u8(row + x - 1), c = vld1q_u8(row + x),
                         r = vld1q_u8(row + x + 1), d = vld1q_u8(down + x);
        const uint8x16_t lowest = vminq_u8(vminq_u8(u, l), vminq_u8(r, d));
        uint8x16_t direction = vbslq_u8(vceqq_u8(r, lowest), toRight, toDown);
        direction = vbslq_u8(vceqq_u8(l, lowest), toLeft, direction);
        direction = vbslq_u8(vceqq_u8(u, lowest), toUp, direction);
        vst1q_u8(code + x, vbslq_u8(vcltq_u8(lowest, c), direction, flat));
    }
#else
    // The same selects in a loop GCC vectorises (SSE2 byte lanes on x86-64).
    const std::uint8_t* __restrict u = up;
    const std::uint8_t* __restrict c = row;
    const std::uint8_t* __restrict d = down;
    std::uint8_t* __restrict out = code;
    for (; x + 1 < width; ++x) {
        const std::uint8_t lowest = std::min(std::min(u[x], c[x - 1]), std::min(c[x + 1], d[x]));
        std::uint8_t direction = c[x + 1] == lowest ? kDescentRight : kDescentDown;
        direction = c[x - 1] == lowest ? kDescentLeft : direction;
        direction = u[x] == lowest ? kDescentUp : direction;
        out[x] = lowest < c[x] ? direction : kDescentFlat;
    }
#endif
    for (; x < width; ++x) descentPixel(up, row, down, width, x, code);
}

namespace {

// Whether the code's arrow (plateau, minimum or not) points in the
// direction: bits kPlateauArrow and kMinimumArrow ignored, bit 3
// (kDescentFlat) kept.
constexpr std::uint8_t kArrowBits = 0xff & ~kPlateauArrow & ~kMinimumArrow;

// Four labels or lane masks, in GCC's vector extensions: one source for the
// SSE2 and NEON instructions (shuffles, compares, and/or).
using Lanes = std::int32_t __attribute__((vector_size(16)));

inline Lanes load(const std::int32_t* p)
{
    Lanes v;
    std::memcpy(&v, p, sizeof v);
    return v;
}

inline void store(std::int32_t* p, Lanes v) { std::memcpy(p, &v, sizeof v); }

// a in the lanes of mask m (-1), else b. (The vector ternary would compare m
// with 0 first.)
inline Lanes select(Lanes m, Lanes a, Lanes b) { return (a & m) | (b & ~m); }

// The 4 codes of a block in each lane (byte k = pixel k): lane k's byte k is
// pixel k's code, so one and-compare per direction gives the lane masks,
// without widening the bytes.
inline Lanes codesOf(const std::uint8_t* code)
{
    static_assert(std::endian::native == std::endian::little, "byte k of the word is pixel k");
    std::int32_t c;
    std::memcpy(&c, code, sizeof c);
    return Lanes{c, c, c, c};
}

// -1 in the lanes whose code has an arrow in the direction, else 0.
inline Lanes arrowsIn(Lanes codes, std::uint8_t direction)
{
    constexpr auto byteK = [](std::uint32_t value) {
        return Lanes{static_cast<std::int32_t>(value), static_cast<std::int32_t>(value << 8),
                     static_cast<std::int32_t>(value << 16), static_cast<std::int32_t>(value << 24)};
    };
    return (codes & byteK(kArrowBits)) == byteK(direction);
}

// Stores v with carry in the lanes of m and returns the label the next block
// takes, lane `last` of the stored block in every lane. The chain from block
// to block is this carry alone. On x86-64 it is (carry & m's last lane) |
// (own's last lane), the broadcasts off the chain: one vpternlogd in the
// AVX-512 clone (watershed 1.37 -> 1.21 ms at 780x580), where a select then
// a broadcast took 3 dependent instructions. On ARM a vbsl then a dup, 4
// instructions fewer per block than the and-or.
template <int last>
inline Lanes storeWithCarry(std::int32_t* out, Lanes m, Lanes v, Lanes carry)
{
    constexpr Lanes lastLane{last, last, last, last};
#if defined(__x86_64__)
    const Lanes own = v & ~m;
    store(out, own | (carry & m));
    return (carry & __builtin_shuffle(m, lastLane)) | __builtin_shuffle(own, lastLane);
#else
    v = select(m, carry, v);
    store(out, v);
    return __builtin_shuffle(v, lastLane);
#endif
}

}  // namespace

void sweepRowUpLeftReference(const std::uint8_t* code, const std::int32_t* above, std::int32_t* row, int width)
{
    for (int x = 0; x < width; ++x)
        if ((code[x] & kArrowBits) == kDescentUp) row[x] = above[x];
    for (int x = 0; x < width; ++x)
        if ((code[x] & kArrowBits) == kDescentLeft) row[x] = x > 0 ? row[x - 1] : kUnresolved;
}

void sweepRowReference(const std::uint8_t* code, const std::int32_t* above, std::int32_t* row, int width)
{
    sweepRowUpLeftReference(code, above, row, width);
    for (int x = width - 1; x >= 0; --x)
        if ((code[x] & kArrowBits) == kDescentRight) row[x] = x + 1 < width ? row[x + 1] : kUnresolved;
}

STRIA_X86_CLONES void sweepRowUpLeft(const std::uint8_t* code, const std::int32_t* above, std::int32_t* row, int width)
{
    // A pixel copying its neighbour's label after the neighbour's own copy is
    // a serial chain: as selects per pixel, 3 dependent instructions each.
    // Here a block of 4 resolves its runs by a prefix scan in 2 shuffle
    // steps (lane i takes lane i - 1, then i - 2, while its mask is set), and
    // only the lanes that copy from beyond the block (their mask still set)
    // take the previous block's label (storeWithCarry).
    const int blocks = width & ~3;
    const Lanes outside{kUnresolved, kUnresolved, kUnresolved, kUnresolved};
    Lanes carry = outside;  // the label left of the block, in every lane
    for (int x = 0; x < blocks; x += 4) {
        const Lanes codes = codesOf(code + x);
        Lanes v = select(arrowsIn(codes, kDescentUp), load(above + x), load(row + x));
        Lanes m = arrowsIn(codes, kDescentLeft);
        v = select(m, __builtin_shuffle(v, Lanes{0, 0, 1, 2}), v);
        m &= __builtin_shuffle(m, Lanes{0, 0, 1, 2});
        v = select(m, __builtin_shuffle(v, Lanes{0, 1, 0, 1}), v);
        m &= __builtin_shuffle(m, Lanes{0, 1, 0, 1});
        carry = storeWithCarry<3>(row + x, m, v, carry);
    }
    std::int32_t previous = carry[0];
    for (int x = blocks; x < width; ++x) {
        if ((code[x] & kArrowBits) == kDescentUp) row[x] = above[x];
        if ((code[x] & kArrowBits) == kDescentLeft) row[x] = previous;
        previous = row[x];
    }
}

STRIA_X86_CLONES void sweepRow(const std::uint8_t* code, const std::int32_t* above, std::int32_t* row, int width)
{
    sweepRowUpLeft(code, above, row, width);
    const int blocks = width & ~3;
    // The same from the right (the tail first), lanes mirrored. (Written out
    // twice on purpose: one always_inline scan for both directions, with the
    // shuffle masks as arguments, cost 3 % more instructions in this kernel.)
    std::int32_t next = kUnresolved;
    for (int x = width - 1; x >= blocks; --x) {
        if ((code[x] & kArrowBits) == kDescentRight) row[x] = next;
        next = row[x];
    }
    Lanes carry{next, next, next, next};
    for (int x = blocks - 4; x >= 0; x -= 4) {
        Lanes v = load(row + x);
        Lanes m = arrowsIn(codesOf(code + x), kDescentRight);
        v = select(m, __builtin_shuffle(v, Lanes{1, 2, 3, 3}), v);
        m &= __builtin_shuffle(m, Lanes{1, 2, 3, 3});
        v = select(m, __builtin_shuffle(v, Lanes{2, 3, 2, 3}), v);
        m &= __builtin_shuffle(m, Lanes{2, 3, 2, 3});
        carry = storeWithCarry<0>(row + x, m, v, carry);
    }
}

}  // namespace stria::pipeline
