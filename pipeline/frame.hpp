#pragma once
// Borrowed views over frame memory that someone else owns (a camera buffer
// mapped at configure time, a cv::Mat, a test array). A view never frees.

#include <cstddef>
#include <cstdint>

namespace stria {

enum class PixelFormat : std::uint8_t {
    Bgr8,   // 3 bytes per pixel, B G R (OpenCV's order); the decoder's input layout
    Rgb8,   // 3 bytes per pixel, R G B
    Yuyv,   // 4:2:2 packed, 2 bytes per pixel (UVC cameras)
    Gray8,  // 1 byte per pixel
};

constexpr int bytesPerPixel(PixelFormat format)
{
    switch (format) {
    case PixelFormat::Bgr8:
    case PixelFormat::Rgb8: return 3;
    case PixelFormat::Yuyv: return 2;
    case PixelFormat::Gray8: return 1;
    }
    return 0;
}

const char* pixelFormatName(PixelFormat format);

struct FrameView {
    const std::uint8_t* data = nullptr;
    int width = 0;
    int height = 0;
    std::ptrdiff_t stride = 0;  // bytes from one row to the next
    PixelFormat format = PixelFormat::Bgr8;

    bool empty() const { return data == nullptr || width <= 0 || height <= 0; }
    const std::uint8_t* row(int y) const { return data + y * stride; }
};

struct MutableFrameView {
    std::uint8_t* data = nullptr;
    int width = 0;
    int height = 0;
    std::ptrdiff_t stride = 0;
    PixelFormat format = PixelFormat::Bgr8;

    bool empty() const { return data == nullptr || width <= 0 || height <= 0; }
    std::uint8_t* row(int y) const { return data + y * stride; }
    operator FrameView() const { return {data, width, height, stride, format}; }  // NOLINT
};

}  // namespace stria
