#include "pipeline/frame.hpp"

namespace stria {

const char* pixelFormatName(PixelFormat format)
{
    switch (format) {
    case PixelFormat::Bgr8: return "BGR8";
    case PixelFormat::Rgb8: return "RGB8";
    case PixelFormat::Yuyv: return "YUYV";
    case PixelFormat::Gray8: return "GRAY8";
    }
    return "unknown";
}

}  // namespace stria
