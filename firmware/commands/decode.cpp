// stria decode: one camera frame -> point cloud (and depth map, preview).
#include "firmware/cli.hpp"
#include "firmware/formats/calibration_file.hpp"
#include "firmware/formats/image_file.hpp"
#include "firmware/formats/pattern_file.hpp"
#include "firmware/formats/ply_file.hpp"
#include "firmware/formats/preview.hpp"
#include "pipeline/decoder.hpp"
#include "pipeline/dp/dp_decoder.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <vector>

namespace stria::firmware {
namespace {

constexpr const char* kUsage = R"(usage:
  stria decode --calib CALIB.yaml --pattern PATTERN.yaml --image IN.png --ply OUT.ply
               [--depth OUT.tiff] [--preview OUT.png] [--stats] [--repeat N] [--ascii]
               [--method graph|dp] [--row-pairs] [--raw-format bgr8|rgb8|yuyv --raw-size WxH]

Decodes one frame of the stripe pattern into a point cloud with the graph-based
decoder (Schmalz & Angelopoulou). The image must have exactly the calibrated
camera size: an 8-bit PNG, or with --raw-format a raw frame dump (--raw-size
gives its size; YUYV is converted to BGR).
Outputs: --ply x y z (mm, camera frame), u v (camera pixel), edge (pattern edge),
binary little-endian unless --ascii; --depth a 32-bit float TIFF of z in mm (NaN =
no data); --preview a colour-coded depth PNG with a scale bar. All outputs are
written only if the whole decode succeeds, each atomically.
--stats prints counts, workspace memory and per-stage times (median over
--repeat N decodes of the same frame).
--method dp decodes with the scanline DP baseline of Zhang et al. instead, for
comparison (docs/evaluation.md); --stats then prints its points and total time.
--row-pairs segments the frame averaged in pairs of rows (the fast mode of the
graph decoder, docs/algorithm.md "Row pairs"; the edges are still located on
every camera row); the board file's decoder.row_pairs sets it for scans.)";

int run(std::span<const std::string> argv);
const Command kDecode{"decode", "decode a camera frame into a point cloud", kUsage, run};

Result<cv::Mat> readRawFrame(const std::string& path, const std::string& format, const std::string& size)
{
    int w = 0, h = 0;
    char x = 0;
    if (std::sscanf(size.c_str(), "%d%c%d", &w, &x, &h) != 3 || x != 'x' || w <= 0 || h <= 0 || w > 16384 ||
        h > 16384)
        return Status::error("--raw-size '" + size + "' is not WIDTHxHEIGHT (e.g. 780x580)");
    const int bpp = format == "yuyv" ? 2 : 3;
    if (format != "bgr8" && format != "rgb8" && format != "yuyv")
        return Status::error("--raw-format '" + format + "' is not one of bgr8, rgb8, yuyv");
    if (format == "yuyv" && w % 2 != 0) return Status::error("--raw-size: YUYV needs an even width, not " + size);
    std::ifstream in(path, std::ios::binary);
    if (!in) return Status::error("raw frame '" + path + "': cannot open");
    const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::size_t expected = static_cast<std::size_t>(w) * h * bpp;
    if (bytes.size() != expected)
        return Status::error("raw frame '" + path + "' has " + std::to_string(bytes.size()) + " bytes but " + format +
                             " " + size + " needs " + std::to_string(expected));
    cv::Mat raw(h, w, bpp == 2 ? CV_8UC2 : CV_8UC3, const_cast<char*>(bytes.data()));
    cv::Mat bgr;
    if (format == "yuyv") cv::cvtColor(raw, bgr, cv::COLOR_YUV2BGR_YUYV);
    else if (format == "rgb8") cv::cvtColor(raw, bgr, cv::COLOR_RGB2BGR);
    else bgr = raw.clone();
    return bgr;
}

double median(std::vector<double> v)
{
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
}

int run(std::span<const std::string> argv)
{
    Args args(argv, {"calib", "pattern", "image", "ply", "depth", "preview", "repeat", "method", "raw-format", "raw-size"},
              {"stats", "ascii", "row-pairs"});
    if (!args.ok()) return usageError(kDecode, args.error());
    if (!args.positional().empty()) return usageError(kDecode, "unexpected argument '" + args.positional()[0] + "'");
    if (!args.require({"calib", "pattern", "image", "ply"})) return usageError(kDecode, args.error());
    const long repeat = args.integer("repeat", 1);
    if (!args.ok()) return usageError(kDecode, args.error());
    if (repeat < 1 || repeat > 100000) return usageError(kDecode, "--repeat must be between 1 and 100000");
    const std::string method = args.valueOr("method", "graph");
    if (method != "graph" && method != "dp")
        return usageError(kDecode, "--method '" + method + "' is not one of graph, dp");
    if (method == "dp" && args.has("row-pairs")) return usageError(kDecode, "--row-pairs is for --method graph only");
    if (args.has("raw-format") != args.has("raw-size"))
        return usageError(kDecode, "--raw-format and --raw-size go together");

    auto rig = loadCalibrationFile(*args.value("calib"));
    if (!rig) return failure("decode", rig.message());
    auto pattern = loadPatternFile(*args.value("pattern"));
    if (!pattern) return failure("decode", pattern.message());
    const std::string imagePath = *args.value("image");
    auto image = args.has("raw-format") ? readRawFrame(imagePath, *args.value("raw-format"), *args.value("raw-size"))
                                        : readPng(imagePath);
    if (!image) return failure("decode", image.message());
    const cv::Mat& frame = *image;
    const pipeline::LensModel& camera = rig->camera();
    if (frame.cols != camera.width || frame.rows != camera.height)
        return failure("decode", "image '" + imagePath + "' is " + std::to_string(frame.cols) + "x" +
                                     std::to_string(frame.rows) + " but calibration '" + *args.value("calib") +
                                     "' is for a " + std::to_string(camera.width) + "x" +
                                     std::to_string(camera.height) + " camera");

    std::unique_ptr<pipeline::Decoder> graph;
    std::unique_ptr<pipeline::DpDecoder> dp;
    if (method == "dp") {
        auto created = pipeline::DpDecoder::create(*pattern, *rig);
        if (!created) return failure("decode", created.message());
        dp = std::move(*created);
    } else {
        pipeline::DecoderParams params;
        params.segmentRowPairs = args.has("row-pairs");
        auto created = pipeline::Decoder::create(*pattern, *rig, params);
        if (!created) return failure("decode", created.message());
        graph = std::move(*created);
    }
    const FrameView view{frame.data, frame.cols, frame.rows, static_cast<std::ptrdiff_t>(frame.step),
                         PixelFormat::Bgr8};
    std::vector<pipeline::StageTimings> timings;
    Result<pipeline::DecodeResult> result = Status::error("not decoded");
    for (long i = 0; i < repeat; ++i) {
        result = dp ? dp->decode(view) : graph->decode(view);
        if (!result) return failure("decode", result.message());
        timings.push_back(result->timings);
    }

    // Everything is computed before anything is written; each file is atomic.
    cv::Mat depth;
    if (args.has("depth") || args.has("preview")) dp ? dp->fillDepthMap(depth) : graph->fillDepthMap(depth);
    if (Status s = writePly(*args.value("ply"), result->points, args.has("ascii")); !s) return failure("decode", s.message());
    if (args.has("depth"))
        if (Status s = writeTiffFloat(*args.value("depth"), depth); !s) return failure("decode", s.message());
    if (args.has("preview"))
        if (Status s = writePng(*args.value("preview"), depthPreview(depth)); !s) return failure("decode", s.message());

    std::printf("decoded %s: %zu points%s -> %s\n", imagePath.c_str(), result->points.size(),
                result->truncated ? " (truncated: a capacity was reached)" : "", args.value("ply")->c_str());
    if (args.has("stats") && dp) {
        std::vector<double> totals;
        for (const auto& t : timings) totals.push_back(t.totalMs);
        std::printf("DP baseline: points %zu, total %.2f ms (median of %ld)\n", result->points.size(), median(totals),
                    repeat);
    } else if (args.has("stats")) {
        const std::size_t bytes = graph->workspaceBytes();
        std::printf("superpixels %d, graph edges %d, decoded regions %d, points %zu%s (segmented on %s)\n",
                    result->superpixels, result->graphEdges, result->decodedRegions, result->points.size(),
                    result->truncated ? ", truncated" : "",
                    graph->params().segmentRowPairs ? "row pairs" : "the camera's rows");
        std::printf("workspace %zu bytes (%.1f bytes/pixel for %dx%d, %s)\n", bytes,
                    static_cast<double>(bytes) / (static_cast<double>(frame.cols) * frame.rows), frame.cols, frame.rows,
                    graph->workspaceHugePagesAdvised() ? "huge pages" : "4 KB pages");
        auto stage = [&](const char* name, double pipeline::StageTimings::*member) {
            std::vector<double> v;
            for (const auto& t : timings) v.push_back(t.*member);
            std::printf("  %-10s %8.2f ms\n", name, median(v));
        };
        std::printf("stage times, median of %ld decode%s:\n", repeat, repeat > 1 ? "s" : "");
        stage("gradient", &pipeline::StageTimings::gradientMs);
        stage("watershed", &pipeline::StageTimings::watershedMs);
        stage("regions", &pipeline::StageTimings::regionsMs);
        stage("graph", &pipeline::StageTimings::graphMs);
        stage("edges", &pipeline::StageTimings::edgesMs);
        stage("decode", &pipeline::StageTimings::decodeMs);
        stage("depth", &pipeline::StageTimings::depthMs);
        stage("total", &pipeline::StageTimings::totalMs);
    }
    return kExitOk;
}

}  // namespace

STRIA_COMMAND(decode, kDecode);

}  // namespace stria::firmware
