#include "firmware/formats/image_file.hpp"

#include "firmware/formats/atomic_file.hpp"

#include <png.h>
#include <tiffio.h>

#include <cerrno>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <memory>

namespace stria::firmware {
namespace {

struct PngError {
    std::string message;
};

void pngErrorHandler(png_structp png, png_const_charp message)
{
    auto* error = static_cast<PngError*>(png_get_error_ptr(png));
    if (error) error->message = message;
    png_longjmp(png, 1);
}

void pngWarningHandler(png_structp, png_const_charp) {}

struct FileCloser {
    void operator()(std::FILE* f) const { std::fclose(f); }
};

// libtiff reports through global handlers; keep the last message per thread.
thread_local std::string tiffLastError;
void tiffErrorHandler(const char* module, const char* fmt, va_list ap)
{
    char buffer[512];
    std::vsnprintf(buffer, sizeof buffer, fmt, ap);
    tiffLastError = std::string(module ? module : "libtiff") + ": " + buffer;
}
void tiffWarningHandler(const char*, const char*, va_list) {}
void installTiffHandlers()
{
    TIFFSetErrorHandler(tiffErrorHandler);
    TIFFSetWarningHandler(tiffWarningHandler);
}

}  // namespace

Result<cv::Mat> readPng(const std::string& path)
{
    std::unique_ptr<std::FILE, FileCloser> file(std::fopen(path.c_str(), "rb"));
    if (!file) return Status::error("cannot read image '" + path + "': " + std::strerror(errno));
    unsigned char signature[8] = {};
    if (std::fread(signature, 1, 8, file.get()) != 8 || png_sig_cmp(signature, 0, 8) != 0)
        return Status::error("image '" + path + "' is not a PNG file");

    PngError error;
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &error, pngErrorHandler, pngWarningHandler);
    png_infop info = png ? png_create_info_struct(png) : nullptr;
    if (!png || !info) {
        png_destroy_read_struct(&png, &info, nullptr);
        return Status::error("cannot read image '" + path + "': out of memory");
    }
    cv::Mat image;
    std::vector<png_bytep> rows;
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_read_struct(&png, &info, nullptr);
        return Status::error("image '" + path + "' is corrupt: " + error.message);
    }
    png_init_io(png, file.get());
    png_set_sig_bytes(png, 8);
    png_read_info(png, info);
    const png_uint_32 width = png_get_image_width(png, info);
    const png_uint_32 height = png_get_image_height(png, info);
    if (width == 0 || height == 0 || width > 1u << 15 || height > 1u << 15) {
        png_destroy_read_struct(&png, &info, nullptr);
        return Status::error("image '" + path + "' has an unsupported size " + std::to_string(width) + "x" +
                             std::to_string(height));
    }
    // Normalise every PNG flavour to 8-bit BGR.
    png_set_expand(png);
    png_set_strip_16(png);
    png_set_strip_alpha(png);
    png_set_gray_to_rgb(png);
    png_set_bgr(png);
    png_read_update_info(png, info);
    if (png_get_rowbytes(png, info) != width * 3) {
        png_destroy_read_struct(&png, &info, nullptr);
        return Status::error("image '" + path + "' has a pixel layout stria cannot convert");
    }
    image.create(static_cast<int>(height), static_cast<int>(width), CV_8UC3);
    rows.resize(height);
    for (png_uint_32 y = 0; y < height; ++y) rows[y] = image.ptr<png_byte>(static_cast<int>(y));
    png_read_image(png, rows.data());
    png_read_end(png, nullptr);
    png_destroy_read_struct(&png, &info, nullptr);
    return image;
}

Result<std::vector<unsigned char>> encodePng(const cv::Mat& image)
{
    // Set before setjmp and never changed, so libpng's longjmp cannot clobber
    // it; the bit depth is read from the image where it is needed (gcc's
    // -Wclobbered flagged a local copy held in a register).
    const int colorType = image.type() == CV_8UC3   ? PNG_COLOR_TYPE_RGB
                          : image.type() == CV_8UC4 ? PNG_COLOR_TYPE_RGBA
                          : (image.type() == CV_8UC1 || image.type() == CV_16UC1) ? PNG_COLOR_TYPE_GRAY
                                                                                   : -1;
    if (colorType < 0)
        return Status::error("cannot write PNG: unsupported image type " + std::to_string(image.type()));
    if (image.empty()) return Status::error("cannot write PNG: the image is empty");
    std::vector<unsigned char> out;
    PngError error;
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &error, pngErrorHandler, pngWarningHandler);
    png_infop info = png ? png_create_info_struct(png) : nullptr;
    if (!png || !info) {
        png_destroy_write_struct(&png, &info);
        return Status::error("cannot write PNG: out of memory");
    }
    std::vector<png_bytep> rows(static_cast<std::size_t>(image.rows));
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        return Status::error("cannot write PNG: " + error.message);
    }
    png_set_write_fn(
        png, &out,
        [](png_structp p, png_bytep data, png_size_t length) {
            auto* buffer = static_cast<std::vector<unsigned char>*>(png_get_io_ptr(p));
            buffer->insert(buffer->end(), data, data + length);
        },
        nullptr);
    png_set_IHDR(png, info, static_cast<png_uint_32>(image.cols), static_cast<png_uint_32>(image.rows),
                 image.depth() == CV_16U ? 16 : 8,
                 colorType, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_set_compression_level(png, 3);  // fast: previews are written on the scanner after every scan
    png_write_info(png, info);
    if (image.channels() >= 3) png_set_bgr(png);
    if (image.depth() == CV_16U) png_set_swap(png);  // cv::Mat holds host (little-endian) order
    for (int y = 0; y < image.rows; ++y) rows[static_cast<std::size_t>(y)] = const_cast<png_bytep>(image.ptr<png_byte>(y));
    png_write_image(png, rows.data());
    png_write_end(png, nullptr);
    png_destroy_write_struct(&png, &info);
    return out;
}

Status writePng(const std::string& path, const cv::Mat& image)
{
    auto bytes = encodePng(image);
    if (!bytes) return bytes.status().withContext("'" + path + "': ");
    return writeFileAtomically(path, *bytes);
}

Status writeTiffFloat(const std::string& path, const cv::Mat& image)
{
    if (image.type() != CV_32FC1 || image.empty())
        return Status::error("cannot write '" + path + "': a depth TIFF needs a non-empty 32-bit float image");
    installTiffHandlers();
    auto file = AtomicFile::create(path);
    if (!file) return file.status();
    TIFF* tiff = TIFFOpen(file->temporaryPath().c_str(), "w");
    if (!tiff) return Status::error("cannot write '" + path + "': " + tiffLastError);
    TIFFSetField(tiff, TIFFTAG_IMAGEWIDTH, static_cast<std::uint32_t>(image.cols));
    TIFFSetField(tiff, TIFFTAG_IMAGELENGTH, static_cast<std::uint32_t>(image.rows));
    TIFFSetField(tiff, TIFFTAG_SAMPLESPERPIXEL, 1);
    TIFFSetField(tiff, TIFFTAG_BITSPERSAMPLE, 32);
    TIFFSetField(tiff, TIFFTAG_SAMPLEFORMAT, SAMPLEFORMAT_IEEEFP);
    TIFFSetField(tiff, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_MINISBLACK);
    TIFFSetField(tiff, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
    TIFFSetField(tiff, TIFFTAG_COMPRESSION, COMPRESSION_NONE);
    TIFFSetField(tiff, TIFFTAG_ROWSPERSTRIP, TIFFDefaultStripSize(tiff, 0));
    bool ok = true;
    for (int y = 0; y < image.rows && ok; ++y)
        ok = TIFFWriteScanline(tiff, const_cast<float*>(image.ptr<float>(y)), static_cast<std::uint32_t>(y), 0) == 1;
    ok = ok && TIFFFlush(tiff) == 1;
    TIFFClose(tiff);
    if (!ok) return Status::error("cannot write '" + path + "': " + (tiffLastError.empty() ? std::string(std::strerror(errno)) : tiffLastError));
    return file->commit();
}

Result<cv::Mat> readTiffFloat(const std::string& path)
{
    installTiffHandlers();
    tiffLastError.clear();
    TIFF* tiff = TIFFOpen(path.c_str(), "r");
    if (!tiff) return Status::error("cannot read '" + path + "': " + tiffLastError);
    std::uint32_t width = 0, height = 0;
    std::uint16_t samples = 1, bits = 0, format = SAMPLEFORMAT_UINT;
    TIFFGetField(tiff, TIFFTAG_IMAGEWIDTH, &width);
    TIFFGetField(tiff, TIFFTAG_IMAGELENGTH, &height);
    TIFFGetFieldDefaulted(tiff, TIFFTAG_SAMPLESPERPIXEL, &samples);
    TIFFGetFieldDefaulted(tiff, TIFFTAG_BITSPERSAMPLE, &bits);
    TIFFGetFieldDefaulted(tiff, TIFFTAG_SAMPLEFORMAT, &format);
    if (samples != 1 || bits != 32 || format != SAMPLEFORMAT_IEEEFP || width == 0 || height == 0) {
        TIFFClose(tiff);
        return Status::error("'" + path + "' is not a single-channel 32-bit float TIFF");
    }
    cv::Mat image(static_cast<int>(height), static_cast<int>(width), CV_32FC1);
    for (std::uint32_t y = 0; y < height; ++y) {
        if (TIFFReadScanline(tiff, image.ptr<float>(static_cast<int>(y)), y, 0) != 1) {
            TIFFClose(tiff);
            return Status::error("'" + path + "' is corrupt: " + tiffLastError);
        }
    }
    TIFFClose(tiff);
    return image;
}

}  // namespace stria::firmware
