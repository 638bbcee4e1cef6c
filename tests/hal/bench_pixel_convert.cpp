// YUYV -> BGR conversion of a UVC frame (V4l2Camera::capture's only per-frame
// work), against OpenCV's cvtColor(COLOR_YUV2BGR_YUYV) on the same buffers as
// the reference. Run: bench_pixel_convert; compare the two rows per size.
#include "hal/v4l2/pixel_convert.hpp"

#include <benchmark/benchmark.h>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include <cstdint>
#include <vector>

namespace {

struct Buffers {
    Buffers(int width, int height) : width(width), height(height), yuyv(std::size_t(width) * height * 2), bgr(std::size_t(width) * height * 3)
    {
        std::uint32_t state = 12345;
        for (std::uint8_t& byte : yuyv) byte = std::uint8_t((state = state * 1664525u + 1013904223u) >> 24);
    }
    int width, height;
    std::vector<std::uint8_t> yuyv, bgr;
};

void stria(benchmark::State& state)
{
    Buffers b(int(state.range(0)), int(state.range(1)));
    const stria::FrameView src{b.yuyv.data(), b.width, b.height, std::ptrdiff_t(b.width) * 2, stria::PixelFormat::Yuyv};
    const stria::MutableFrameView dst{b.bgr.data(), b.width, b.height, std::ptrdiff_t(b.width) * 3,
                                      stria::PixelFormat::Bgr8};
    for (auto _ : state) {
        stria::hal::convertYuyvToBgr(src, dst);
        benchmark::DoNotOptimize(b.bgr.data());
    }
    state.SetItemsProcessed(state.iterations() * b.width * b.height);
}

void opencvReference(benchmark::State& state)
{
    cv::setNumThreads(int(state.range(2)));  // 1: one core, like stria's conversion; 0: OpenCV's default pool
    Buffers b(int(state.range(0)), int(state.range(1)));
    const cv::Mat src(b.height, b.width, CV_8UC2, b.yuyv.data());
    cv::Mat dst(b.height, b.width, CV_8UC3, b.bgr.data());
    for (auto _ : state) {
        cv::cvtColor(src, dst, cv::COLOR_YUV2BGR_YUYV);
        benchmark::DoNotOptimize(b.bgr.data());
    }
    state.SetItemsProcessed(state.iterations() * b.width * b.height);
}

BENCHMARK(stria)->Args({640, 480})->Args({1280, 720});
BENCHMARK(opencvReference)->Args({640, 480, 1})->Args({1280, 720, 1})->Args({640, 480, 0})->Args({1280, 720, 0});

}  // namespace
