#include "hal/v4l2/pixel_convert.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>

namespace stria::hal {
namespace {

// BT.601 limited range coefficients times 256 (1.164, 1.596, 0.392, 0.813, 2.017).
constexpr int kLuma = 298, kRedV = 409, kGreenU = 100, kGreenV = 208, kBlueU = 516;

inline std::uint8_t clampByte(int value) { return static_cast<std::uint8_t>(std::clamp(value, 0, 255)); }

inline void yuvToBgr(int y, int u, int v, std::uint8_t* bgr)
{
    const int luma = kLuma * (y - 16) + 128;  // +128 rounds the >> 8
    bgr[0] = clampByte((luma + kBlueU * u) >> 8);
    bgr[1] = clampByte((luma - kGreenU * u - kGreenV * v) >> 8);
    bgr[2] = clampByte((luma + kRedV * v) >> 8);
}

}  // namespace

void convertYuyvToBgr(const FrameView& src, const MutableFrameView& dst)
{
    for (int row = 0; row < src.height; ++row) {
        const std::uint8_t* in = src.row(row);
        std::uint8_t* out = dst.row(row);
        for (int x = 0; x + 1 < src.width; x += 2, in += 4, out += 6) {
            const int u = in[1] - 128, v = in[3] - 128;
            yuvToBgr(in[0], u, v, out);
            yuvToBgr(in[2], u, v, out + 3);
        }
    }
}

void convertRgbToBgr(const FrameView& src, const MutableFrameView& dst)
{
    for (int row = 0; row < src.height; ++row) {
        const std::uint8_t* in = src.row(row);
        std::uint8_t* out = dst.row(row);
        for (int x = 0; x < src.width; ++x, in += 3, out += 3) {
            out[0] = in[2];
            out[1] = in[1];
            out[2] = in[0];
        }
    }
}

void copyBgr(const FrameView& src, const MutableFrameView& dst)
{
    for (int row = 0; row < src.height; ++row) std::memcpy(dst.row(row), src.row(row), std::size_t(src.width) * 3);
}

}  // namespace stria::hal
