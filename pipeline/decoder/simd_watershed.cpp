// Watershed descent kernel (pipeline/decoder/simd.hpp).
#include "pipeline/decoder/simd.hpp"

#include <algorithm>

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

}  // namespace stria::pipeline
