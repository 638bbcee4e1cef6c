#pragma once
// The graph-based single-shot decoder of Schmalz & Angelopoulou, "Robust
// Single-Shot Structured Light": watershed superpixels -> region adjacency
// graph -> edge symbols and errors -> best-first decoding of stripe positions
// -> sub-pixel stripe edges -> ray/light-plane triangulation.
//
// Every buffer is sized once in create() from the calibrated camera size and
// the pattern; decode() performs no heap allocation. Stages live one per file
// under pipeline/decoder/; docs/algorithm.md explains each decision.

#include "pipeline/frame.hpp"
#include "pipeline/pattern.hpp"
#include "pipeline/rig.hpp"
#include "pipeline/status.hpp"

#include <opencv2/core.hpp>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>

namespace stria::pipeline {

struct DecoderParams {
    double t = 1.0 / 3.0;  // symbol threshold on the equalised colour change (eq. 6/7)
    double alpha = 0.2;    // weight of the gradient error in E = Ematch + alpha * Egradient (eq. 9)
    double A = 0.5;        // aggressiveness: edges with error above A are never followed
    double beta = 255.0;   // scale of the position error Q (eq. 10), in colour units
    // The camera's colour crosstalk as MEASURED (the mixing matrix, R G B order:
    // observed = crosstalk * projected, rows sensor R G B, columns light R G B;
    // the simulator's RenderSettings::crosstalk convention). The decoder applies
    // its inverse to every superpixel colour and to the gradient it locates
    // edges with; create() fails if it is singular.
    cv::Matx33f crosstalk = cv::Matx33f::eye();
    // Token bucket: each edge with error below A adds a token (up to
    // tokenBucketSize); an edge with error in [A, tokenErrorLimit) is followed
    // only by spending one, so isolated bad edges are crossed, runs are not.
    int tokenBucketSize = 2;
    double tokenErrorLimit = 1.0;
    // Connected decoded components with fewer superpixels are dropped as
    // false positives (shadows, clutter).
    int minComponentRegions = 6;
    // Null edges (fig. 6): an edge whose weight is below this fraction of the
    // weight of the edge to the region's reference (the neighbour on the next
    // stripe it was decoded from) may join two regions of the same stripe.
    double nullEdgeRatio = 0.25;
    // Gradient magnitudes up to max(gradientFloor, noiseFloorFactor * N - 1),
    // N = median gradient along the stripes (8-bit units, a noise measure), are
    // flattened before the watershed, so the noise inside a stripe does not
    // split it into a basin per pixel (docs/algorithm.md).
    int gradientFloor = 0;
    double noiseFloorFactor = 1.1;
    // Segmentation on row pairs (the fast mode; docs/algorithm.md, "Row
    // pairs"): the stages from the gradient to the traversal run on the frame
    // averaged in pairs of rows (half the pixels, fewer superpixels), the
    // sub-pixel edges and the triangulation still on every camera row, each
    // reading its pair's labels. The floor above is the camera rows' (N
    // measured on every 8th camera row). The stripes must run along the
    // image columns (create() fails otherwise).
    bool segmentRowPairs = false;
    // Capacities (0 = derive from the camera size). When a frame needs more,
    // decode() decodes what fits and sets DecodeResult::truncated.
    int maxSuperpixels = 0;  // default: pixels / 16
    int maxGraphEdges = 0;   // default: 3 * maxSuperpixels (a planar graph has fewer)
    int maxPoints = 0;       // default and maximum: pixels / 6 (the points share a per-pixel buffer)
};

struct ScanPoint {
    cv::Vec3f position;  // mm, camera frame
    cv::Point2f pixel;   // camera pixel: sub-pixel column u, row v
    std::int32_t edge;   // pattern edge index
};

struct StageTimings {
    double gradientMs = 0, watershedMs = 0, regionsMs = 0, graphMs = 0, edgesMs = 0, decodeMs = 0, depthMs = 0,
           totalMs = 0;
};

struct DecodeResult {
    std::span<const ScanPoint> points;  // valid until the next decode()
    int superpixels = 0, graphEdges = 0, decodedRegions = 0;
    bool truncated = false;  // a capacity was reached; decoded as far as it fitted
    StageTimings timings;
};

// The decoder's stages, in the order decode() runs them (StageTimings has one
// field each).
enum class DecoderStage { Gradient, Watershed, Regions, Graph, Edges, Traversal, Depth };
inline constexpr int kDecoderStageCount = 7;
const char* decoderStageName(DecoderStage stage);  // "gradient", "watershed", ...

struct DecoderWorkspace;  // pipeline/decoder/workspace.hpp

class Decoder {
public:
    // Sizes every buffer once from the camera size in rig (the largest frame) and the pattern.
    static Result<std::unique_ptr<Decoder>> create(const StripePattern& pattern, const RigModel& rig,
                                                   const DecoderParams& params = {});
    ~Decoder();
    Decoder(const Decoder&) = delete;
    Decoder& operator=(const Decoder&) = delete;

    // frame: BGR8 or RGB8, exactly the calibrated camera size, else an error
    // naming both sizes. Performs no heap allocation.
    Result<DecodeResult> decode(const FrameView& frame);
    // Runs one stage again on the frame the last decode() decoded (the same
    // view), on the workspace as the stages before it left it. Later stages
    // reuse earlier stages' buffers, so a stage repeats decode()'s work only
    // if the stages before it were repeated first, in order (test_decoder_
    // allocation checks that this gives decode()'s points). For benchmarks
    // that time one stage alone; decode() is the API. Performs no heap
    // allocation. Fails, naming why, if nothing was decoded yet or `frame`
    // is not the view the last decode() was given.
    Status repeatStage(DecoderStage stage, const FrameView& frame);
    // Depth (z, mm) of the last decode into a caller-owned CV_32FC1 of camera
    // size; NaN where nothing was measured. Reallocates `depth` only if its
    // size or type differ.
    void fillDepthMap(cv::Mat& depth) const;
    // Everything allocated by create(), excluding the input frame.
    std::size_t workspaceBytes() const;
    // Whether the kernel took the advice to back the workspace with
    // transparent huge pages (Linux; pipeline/decoder/arena.hpp): false
    // without them, when the workspace is in 4 KB pages (on this project's
    // x86-64 VM no slower when idle; on the boards' small TLBs unmeasured).
    bool workspaceHugePagesAdvised() const;

    const DecoderParams& params() const;
    // Superpixel label per pixel of the last decode (CV_32SC1 view into the
    // workspace, valid until the next decode()); for tests and debugging.
    // With DecoderParams::segmentRowPairs, per pixel of the row-pair frame
    // (camera row y is label row y / 2).
    cv::Mat labels() const;
    // Pattern stripe of superpixel `label` in the last decode (-1 = undecoded).
    int regionStripe(int label) const;

private:
    explicit Decoder(std::unique_ptr<DecoderWorkspace> workspace);
    Status checkFrame(const FrameView& frame) const;
    std::unique_ptr<DecoderWorkspace> ws_;
    FrameView lastFrame_;  // the view the last decode() decoded (repeatStage)
};

}  // namespace stria::pipeline
