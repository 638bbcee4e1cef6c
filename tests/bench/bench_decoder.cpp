// Whole-frame decode on simulator frames, with references measured in the
// same run on the same frame: one 3x3 Sobel pass of OpenCV (x derivative,
// CV_16S, on the BGR frame the decoder reads and on its grey version) and the
// DP baseline; and each stage alone. tests/bench/run-benchmarks.sh turns the
// medians into ratios.
#include "tests/bench/bench_frames.hpp"

#include "pipeline/decoder.hpp"
#include "pipeline/dp/dp_decoder.hpp"

#include <benchmark/benchmark.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace stria::bench {
namespace {

// A decode this far off the ground truth is broken, not slow: the benchmark
// reports an error (and the suite exits non-zero) instead of a time. The
// quality targets proper are test_decoder_quality's; these bounds only keep
// a decode that measures wrong depths or next to nothing from being timed.
constexpr double kMaxMedianDepthError = 0.01;  // relative to the true depth
constexpr double kMinCoverage = 0.05;          // points / ideal (row, edge) crossings

double median(std::vector<double> values)
{
    if (values.empty()) return 0;
    auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
    std::nth_element(values.begin(), middle, values.end());
    return *middle;
}

// The process's anonymous memory in transparent huge pages, in bytes
// (AnonHugePages in /proc/self/smaps_rollup; 0 where the kernel has none):
// the decoder asks for them for its workspace (pipeline/decoder/arena.hpp).
double hugePageBytes()
{
    std::ifstream in("/proc/self/smaps_rollup");
    std::string key;
    double kilobytes = 0;
    while (in >> key) {
        if (key == "AnonHugePages:") {
            in >> kilobytes;
            break;
        }
        in.ignore(1 << 10, '\n');
    }
    return 1024 * kilobytes;
}

// Median |z - true z| / true z over the points, at the pixel each was found in.
double medianDepthError(std::span<const pipeline::ScanPoint> points, const cv::Mat& truth)
{
    std::vector<double> errors;
    errors.reserve(points.size());
    for (const pipeline::ScanPoint& p : points) {
        const int x = static_cast<int>(std::lround(p.pixel.x)), y = static_cast<int>(std::lround(p.pixel.y));
        if (x < 0 || y < 0 || x >= truth.cols || y >= truth.rows) continue;
        const float z = truth.at<float>(y, x);
        if (std::isfinite(z)) errors.push_back(std::abs(p.position[2] - z) / z);
    }
    return errors.empty() ? 1.0 : median(std::move(errors));
}

const BenchFrame* frameOrSkip(benchmark::State& state, FrameSize size)
{
    const BenchFrame* frame = benchFrame(size);
    if (!frame) state.SkipWithError("the simulator could not render the frame");
    return frame;
}

// The decoder for the frame's rig, or null (the benchmark reports the error).
std::unique_ptr<pipeline::Decoder> decoderOrSkip(benchmark::State& state, const BenchFrame& frame,
                                                 const pipeline::DecoderParams& params = {})
{
    auto decoder = pipeline::Decoder::create(frame.rig.pattern, frame.rig.rig, params);
    if (!decoder) {
        state.SkipWithError(decoder.message().c_str());
        return nullptr;
    }
    return std::move(*decoder);
}

// rowPairs: DecoderParams::segmentRowPairs (the fast mode), `decodeRowPairs/<size>`.
void decode(benchmark::State& state, FrameSize size, bool rowPairs)
{
    const BenchFrame* frame = frameOrSkip(state, size);
    pipeline::DecoderParams params;
    params.segmentRowPairs = rowPairs;
    std::unique_ptr<pipeline::Decoder> decoder = frame ? decoderOrSkip(state, *frame, params) : nullptr;
    if (!decoder) return;
    const FrameView view = viewOf(frame->rendering.image);
    std::vector<pipeline::StageTimings> timings;
    timings.reserve(100000);
    pipeline::DecodeResult last;
    for (auto _ : state) {
        auto result = decoder->decode(view);
        if (!result) {
            state.SkipWithError(result.message().c_str());
            break;
        }
        last = *result;
        if (timings.size() < timings.capacity()) timings.push_back(result->timings);
    }
    if (timings.empty()) return;

    const double depthError = medianDepthError(last.points, frame->rendering.depth);
    const double coverage = static_cast<double>(last.points.size()) /
                            std::max(1, hal::sim::idealEdgeCrossings(frame->rendering, frame->rig.pattern));
    if (depthError > kMaxMedianDepthError || coverage < kMinCoverage) {
        const std::string why = "the decode is wrong: median depth error " + std::to_string(100 * depthError) +
                                " % (limit " + std::to_string(100 * kMaxMedianDepthError) + "), coverage " +
                                std::to_string(coverage) + " (limit " + std::to_string(kMinCoverage) + "), " +
                                std::to_string(last.points.size()) + " points";
        state.SkipWithError(why.c_str());
        return;
    }
    const double pixels = static_cast<double>(view.width) * view.height;
    auto& c = state.counters;
    c["points"] = static_cast<double>(last.points.size());
    c["superpixels"] = last.superpixels;
    c["graph_edges"] = last.graphEdges;
    c["coverage"] = coverage;
    c["depth_err_rel"] = depthError;
    c["workspace_bytes"] = static_cast<double>(decoder->workspaceBytes());
    c["bytes_per_pixel"] = static_cast<double>(decoder->workspaceBytes()) / pixels;
    c["huge_page_bytes"] = hugePageBytes();
    c["pixels"] = benchmark::Counter(pixels, benchmark::Counter::kIsIterationInvariantRate);
    // Stage medians from the decoder's own clock (StageTimings), in ms.
    const auto stage = [&](const char* name, double pipeline::StageTimings::*field) {
        std::vector<double> values(timings.size());
        std::transform(timings.begin(), timings.end(), values.begin(), [&](const auto& t) { return t.*field; });
        c[name] = median(std::move(values));
    };
    stage("ms_gradient", &pipeline::StageTimings::gradientMs);
    stage("ms_watershed", &pipeline::StageTimings::watershedMs);
    stage("ms_regions", &pipeline::StageTimings::regionsMs);
    stage("ms_graph", &pipeline::StageTimings::graphMs);
    stage("ms_edges", &pipeline::StageTimings::edgesMs);
    stage("ms_traversal", &pipeline::StageTimings::decodeMs);
    stage("ms_depth", &pipeline::StageTimings::depthMs);
    stage("ms_total", &pipeline::StageTimings::totalMs);
}

// One stage alone (Decoder::repeatStage): each iteration first repeats the
// stages before it with the timer paused (later stages reuse their buffers),
// then times the stage. The decoder's StageTimings instead time each stage
// inside a whole decode, between clock reads.
void stageAlone(benchmark::State& state, FrameSize size, pipeline::DecoderStage stage)
{
    const BenchFrame* frame = frameOrSkip(state, size);
    std::unique_ptr<pipeline::Decoder> decoder = frame ? decoderOrSkip(state, *frame) : nullptr;
    if (!decoder) return;
    const FrameView view = viewOf(frame->rendering.image);
    if (auto result = decoder->decode(view); !result) {
        state.SkipWithError(result.message().c_str());
        return;
    }
    for (auto _ : state) {
        state.PauseTiming();
        Status status;
        for (int s = 0; s < static_cast<int>(stage) && status; ++s)
            status = decoder->repeatStage(static_cast<pipeline::DecoderStage>(s), view);
        state.ResumeTiming();
        if (status) status = decoder->repeatStage(stage, view);
        if (!status) {
            state.SkipWithError(status.message().c_str());
            break;
        }
    }
    state.counters["pixels"] = benchmark::Counter(static_cast<double>(view.width) * view.height,
                                                  benchmark::Counter::kIsIterationInvariantRate);
}

void sobel(benchmark::State& state, FrameSize size, bool grey)
{
    const BenchFrame* frame = frameOrSkip(state, size);
    if (!frame) return;
    const cv::Mat& src = grey ? frame->grey : frame->rendering.image;
    cv::Mat dst(src.size(), CV_16SC(src.channels()));
    for (auto _ : state) {
        cv::Sobel(src, dst, CV_16S, 1, 0, 3);
        benchmark::DoNotOptimize(dst.data);
        benchmark::ClobberMemory();
    }
    state.counters["pixels"] =
        benchmark::Counter(static_cast<double>(src.total()), benchmark::Counter::kIsIterationInvariantRate);
}

void dpBaseline(benchmark::State& state, FrameSize size)
{
    const BenchFrame* frame = frameOrSkip(state, size);
    if (!frame) return;
    auto decoder = pipeline::DpDecoder::create(frame->rig.pattern, frame->rig.rig);
    if (!decoder) {
        state.SkipWithError(decoder.message().c_str());
        return;
    }
    const FrameView view = viewOf(frame->rendering.image);
    std::size_t points = 0;
    for (auto _ : state) {
        auto result = (*decoder)->decode(view);
        if (!result) {
            state.SkipWithError(result.message().c_str());
            break;
        }
        points = result->points.size();
    }
    state.counters["points"] = static_cast<double>(points);
}

}  // namespace

BENCHMARK_CAPTURE(decode, 780x580, FrameSize::Small, false)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(decode, 1388x1038, FrameSize::Large, false)->Unit(benchmark::kMillisecond);
// Not decode_rowpairs/: Google Benchmark names a capture function/capture.
void decodeRowPairs(benchmark::State& state, FrameSize size) { decode(state, size, true); }
BENCHMARK_CAPTURE(decodeRowPairs, 780x580, FrameSize::Small)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(decodeRowPairs, 1388x1038, FrameSize::Large)->Unit(benchmark::kMillisecond);
// stage/<stage>_<size> for the seven stages at both sizes.
const bool kStageBenchmarksRegistered = [] {
    for (const auto& [size, sizeName] : {std::pair{FrameSize::Small, "780x580"}, std::pair{FrameSize::Large, "1388x1038"}})
        for (int s = 0; s < pipeline::kDecoderStageCount; ++s) {
            const auto stage = static_cast<pipeline::DecoderStage>(s);
            const std::string name = std::string("stage/") + pipeline::decoderStageName(stage) + "_" + sizeName;
            benchmark::RegisterBenchmark(name.c_str(), stageAlone, size, stage)->Unit(benchmark::kMillisecond);
        }
    return true;
}();
BENCHMARK_CAPTURE(sobel, bgr_780x580, FrameSize::Small, false)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(sobel, grey_780x580, FrameSize::Small, true)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(sobel, bgr_1388x1038, FrameSize::Large, false)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(sobel, grey_1388x1038, FrameSize::Large, true)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(dpBaseline, 780x580, FrameSize::Small)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(dpBaseline, 1388x1038, FrameSize::Large)->Unit(benchmark::kMillisecond);

}  // namespace stria::bench
