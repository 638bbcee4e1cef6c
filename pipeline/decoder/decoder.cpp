// Decoder: sizes the workspace once, then runs the stages in order on each frame.
#include "pipeline/decoder/workspace.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>

namespace stria::pipeline {
namespace {

using Clock = std::chrono::steady_clock;

double millisecondsSince(Clock::time_point& start)
{
    const Clock::time_point now = Clock::now();
    const double ms = std::chrono::duration<double, std::milli>(now - start).count();
    start = now;
    return ms;
}

std::string sizeName(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

// Row pairs (DecoderParams::segmentRowPairs): the label rows, (h + 1) / 2 of
// them, then the averaged frame, 3 bytes a pixel, and 64 bytes that the
// kernels' wide loads may read past its last pixel: within the labels
// buffer's 4 bytes a camera pixel for every h >= 8.
std::size_t pairRows(int h) { return static_cast<std::size_t>(h + 1) / 2; }
std::size_t pairLabelEntries(int w, int h)
{
    const std::size_t pixels = static_cast<std::size_t>(w) * pairRows(h);
    return pixels + (3 * pixels + 64 + sizeof(std::int32_t) - 1) / sizeof(std::int32_t);
}

// The frame the stages up to the traversal segment: the camera's, or its row
// pairs (which the gradient stage averages into ws.pairPixels as it goes).
FrameView segmentationFrame(const DecoderWorkspace& ws, const FrameView& frame)
{
    if (!ws.params.segmentRowPairs) return frame;
    return {ws.pairPixels, frame.width, ws.height, 3 * static_cast<std::ptrdiff_t>(frame.width), frame.format};
}

Status validateParams(const DecoderParams& p)
{
    if (!(p.t > 0 && p.t < 1)) return Status::error("decoder parameter t is " + std::to_string(p.t) + ": it must be in (0, 1)");
    if (!(p.alpha >= 0)) return Status::error("decoder parameter alpha is " + std::to_string(p.alpha) + ": it must be >= 0");
    if (!(p.A > 0)) return Status::error("decoder parameter A is " + std::to_string(p.A) + ": it must be > 0");
    if (!(p.beta > 0)) return Status::error("decoder parameter beta is " + std::to_string(p.beta) + ": it must be > 0");
    if (p.tokenBucketSize < 0 || p.minComponentRegions < 1 || p.gradientFloor < 0 || p.maxSuperpixels < 0 ||
        p.maxGraphEdges < 0 || p.maxPoints < 0 || !(p.nullEdgeRatio >= 0) || !(p.noiseFloorFactor >= 0))
        return Status::error("decoder parameters: tokenBucketSize, gradientFloor, noiseFloorFactor, nullEdgeRatio and the capacities "
                             "must be >= 0 and minComponentRegions >= 1");
    return Status::ok();
}

// Unit image direction in which the projector column increases: the epipolar
// line through the image centre (towards or away from the projector's image
// in the camera), oriented with the light planes' normals.
cv::Vec2f primaryDirection(const RigModel& rig, const StripePattern& pattern)
{
    const LensModel& cam = rig.camera();
    const cv::Vec3d e = cam.K * rig.projectorCentreInCamera();
    const double cx = (cam.width - 1) / 2.0, cy = (cam.height - 1) / 2.0;
    cv::Vec2d d(e[0] - e[2] * cx, e[1] - e[2] * cy);
    if (cv::norm(d) < 1e-12) d = {1, 0};
    d /= cv::norm(d);
    const Plane plane = rig.lightPlaneForColumn(pattern.edgeColumn(pattern.edgeCount() / 2));
    const double along = plane.normal[0] * d[0] / cam.K(0, 0) + plane.normal[1] * d[1] / cam.K(1, 1);
    if (along < 0) d = -d;
    return {static_cast<float>(d[0]), static_cast<float>(d[1])};
}

}  // namespace

std::size_t scratchEntries(int width, int height, int maxRegions, int maxEdges)
{
    const std::size_t gradientLanes = 6 * static_cast<std::size_t>(width);  // 12 x width int16
    return std::max({gradientLanes, watershedScratchEntries(width, height), regionScratchEntries(maxRegions),
                     graphScratchEntries(maxRegions, maxEdges)});
}

void reserveFrameBuffers(DecoderWorkspace& ws)
{
    const int w = ws.width, h = ws.height;
    const std::size_t n = static_cast<std::size_t>(w) * h;
    WorkspaceArena& arena = ws.arena;
    // The gradient, then (from the regions to the depth stage) the border
    // lists; with row pairs, one camera row's magnitudes past the pair rows' (gradient.cpp).
    arena.reserve(ws.gradient, std::max({n, static_cast<std::size_t>(w) * (pairRows(h) + 1),
                                         sizeof(std::uint16_t) * borderPositionEntries(w, h)}));
    arena.reserve(ws.labels, ws.params.segmentRowPairs ? std::max(n, pairLabelEntries(w, h)) : n);
    ws.orderEntries = std::max<std::size_t>({watershedOrderEntries(w, h), regionOrderEntries(n, ws.maxRegions),
                                             graphTableEntries(ws.maxRegions, ws.maxEdges),
                                             sizeof(EdgeChange) / sizeof(std::int32_t) * ws.maxEdges});
    arena.reserve(ws.orderAndPoints, ws.orderEntries * sizeof(std::int32_t));
    arena.reserve(ws.scratch, scratchEntries(w, h, ws.maxRegions, ws.maxEdges));
    arena.reserve(ws.bitPositions, bitPositionEntries(w));
    arena.reserve(ws.borderStarts, static_cast<std::size_t>(h) + 1);
    arena.reserve(ws.regions, static_cast<std::size_t>(ws.maxRegions));
    arena.reserve(ws.edges, static_cast<std::size_t>(ws.maxEdges));
    arena.reserve(ws.edgeFeatures, static_cast<std::size_t>(ws.maxEdges));
    arena.reserve(ws.adjacency, 2 * static_cast<std::size_t>(ws.maxEdges));
}

std::size_t allocateWorkspace(DecoderWorkspace& ws)
{
    const std::size_t bytes = ws.arena.allocate();
    ws.borderPositions = reinterpret_cast<std::uint16_t*>(ws.gradient.get());
    ws.pixelOrder = reinterpret_cast<std::int32_t*>(ws.orderAndPoints.get());
    ws.points = reinterpret_cast<ScanPoint*>(ws.orderAndPoints.get());
    ws.edgeChanges = reinterpret_cast<EdgeChange*>(ws.orderAndPoints.get());
    return bytes;
}

std::size_t allocateFrameBuffers(DecoderWorkspace& ws)
{
    ws.cameraHeight = ws.height;
    reserveFrameBuffers(ws);
    return allocateWorkspace(ws);
}

Decoder::Decoder(std::unique_ptr<DecoderWorkspace> workspace) : ws_(std::move(workspace)) {}
Decoder::~Decoder() = default;

Result<std::unique_ptr<Decoder>> Decoder::create(const StripePattern& pattern, const RigModel& rig,
                                                 const DecoderParams& params)
{
    if (Status s = validateParams(params); !s) return s;
    const LensModel& cam = rig.camera();
    if (pattern.projectorColumnsUsed() > rig.projector().width)
        return Status::error("the pattern needs " + std::to_string(pattern.projectorColumnsUsed()) +
                             " projector columns but the calibrated projector is only " +
                             std::to_string(rig.projector().width) + " wide");
    if (pattern.stripeCount() > std::numeric_limits<std::int16_t>::max())
        return Status::error("the pattern has " + std::to_string(pattern.stripeCount()) +
                             " stripes: the decoder supports at most 32767");
    const cv::Matx33d mixing = params.crosstalk;
    if (std::abs(cv::determinant(mixing)) < 1e-6)
        return Status::error("the crosstalk matrix is singular (determinant " +
                             std::to_string(cv::determinant(mixing)) + "): it cannot be corrected");

    if (cam.width > 65536)
        return Status::error("the camera is " + std::to_string(cam.width) +
                             " pixels wide: the decoder supports at most 65536 (16-bit border columns)");
    auto ws = std::make_unique<DecoderWorkspace>(pattern, params);
    const int w = cam.width, h = cam.height;
    const std::size_t n = static_cast<std::size_t>(w) * h;
    ws->width = w;
    ws->height = h;
    ws->colorCorrection = cv::Matx33f(mixing.inv());
    ws->primary = primaryDirection(rig, pattern);
    if (params.segmentRowPairs && std::abs(ws->primary[1]) > std::abs(ws->primary[0]))
        return Status::error("decoder: segmentation on row pairs needs stripes along the image columns, but this rig's "
                             "stripes run along the rows (its baseline is closer to the image's y axis)");
    ws->maxRegions = params.maxSuperpixels > 0 ? params.maxSuperpixels : std::max<int>(16, static_cast<int>(n / 16));
    ws->maxEdges = params.maxGraphEdges > 0 ? params.maxGraphEdges : 3 * ws->maxRegions;
    ws->maxPoints = params.maxPoints > 0 ? params.maxPoints : std::max<int>(16, static_cast<int>(n / 6));
    if (ws->maxRegions > (1 << EdgeFeature::kEndBits))
        return Status::error("decoder: " + std::to_string(ws->maxRegions) + " superpixels: at most " +
                             std::to_string(1 << EdgeFeature::kEndBits) + " are supported");

    // Every array in one block (ws->arena, arena.hpp), planned, then allocated.
    WorkspaceArena& arena = ws->arena;
    reserveFrameBuffers(*ws);
    ws->maxPoints = std::min<int>(ws->maxPoints, static_cast<int>(n * sizeof(std::int32_t) / sizeof(ScanPoint)));
    arena.reserve(ws->edgeOrder, static_cast<std::size_t>(ws->maxEdges));
    ws->maxOpen = std::max(16, ws->maxEdges / 2);
    arena.reserve(ws->open, static_cast<std::size_t>(ws->maxOpen) + 1);  // and the heap's sentinel (traversal.cpp)
    arena.reserve(ws->candidates, static_cast<std::size_t>(pattern.edgeCount()));
    arena.reserve(ws->pathVertices, 2 * static_cast<std::size_t>(pattern.window() + 1) + 1);
    arena.reserve(ws->componentSize, static_cast<std::size_t>(ws->maxRegions));
    arena.reserve(ws->lightPlanes, static_cast<std::size_t>(pattern.edgeCount()));
    ws->rayGridWidth = std::max(2, (w - 1 + ws->rayGridStep - 1) / ws->rayGridStep + 1);
    ws->rayGridHeight = std::max(2, (h - 1 + ws->rayGridStep - 1) / ws->rayGridStep + 1);
    arena.reserve(ws->rayGrid, static_cast<std::size_t>(ws->rayGridWidth) * ws->rayGridHeight);
    std::size_t& bytes = ws->allocatedBytes;
    bytes = allocateWorkspace(*ws);
    // Sized for the camera's rows above; the stages up to the traversal see the segmentation frame's.
    ws->cameraHeight = h;
    if (params.segmentRowPairs) {
        ws->height = static_cast<int>(pairRows(h));
        ws->pairPixels = reinterpret_cast<std::uint8_t*>(ws->labels.get() + static_cast<std::size_t>(w) * ws->height);
    }

    setFirstStepSymbols(*ws);
    for (int k = 0; k < pattern.edgeCount(); ++k) ws->lightPlanes[k] = rig.lightPlaneForColumn(pattern.edgeColumn(k));
    for (int gy = 0; gy < ws->rayGridHeight; ++gy)
        for (int gx = 0; gx < ws->rayGridWidth; ++gx)
            ws->rayGrid[gy * ws->rayGridWidth + gx] =
                cv::Vec2f(cam.undistortPixel({static_cast<double>(gx * ws->rayGridStep),
                                               static_cast<double>(gy * ws->rayGridStep)}));
    bytes += sizeof(DecoderWorkspace);
    return std::unique_ptr<Decoder>(new Decoder(std::move(ws)));
}

Status Decoder::checkFrame(const FrameView& frame) const
{
    const DecoderWorkspace& ws = *ws_;
    if (frame.empty()) return Status::error("decode: the frame is empty");
    if (frame.format != PixelFormat::Bgr8 && frame.format != PixelFormat::Rgb8)
        return Status::error(std::string("decode: the frame is ") + pixelFormatName(frame.format) +
                             ", the decoder needs BGR8 or RGB8");
    if (frame.width != ws.width || frame.height != ws.cameraHeight)
        return Status::error("decode: the frame is " + sizeName(frame.width, frame.height) +
                             " but the camera is calibrated for " + sizeName(ws.width, ws.cameraHeight));
    if (frame.stride < 3 * static_cast<std::ptrdiff_t>(frame.width))
        return Status::error("decode: the frame's stride " + std::to_string(frame.stride) + " is below 3 x width");
    return Status::ok();
}

Result<DecodeResult> Decoder::decode(const FrameView& frame)
{
    DecoderWorkspace& ws = *ws_;
    lastFrame_ = {};
    if (Status status = checkFrame(frame); !status) return status;
    ws.cameraFrame = frame;
    ws.rgbOffset = frame.format == PixelFormat::Bgr8 ? std::array<int, 3>{2, 1, 0} : std::array<int, 3>{0, 1, 2};
    ws.truncated = false;

    DecodeResult result;
    StageTimings& t = result.timings;
    const Clock::time_point begin = Clock::now();
    Clock::time_point lap = begin;
    ws.frame = segmentationFrame(ws, frame);
    computeGradient(ws);
    t.gradientMs = millisecondsSince(lap);
    computeWatershed(ws);
    t.watershedMs = millisecondsSince(lap);
    computeRegions(ws);
    t.regionsMs = millisecondsSince(lap);
    buildGraph(ws);
    t.graphMs = millisecondsSince(lap);
    computeEdgeFeatures(ws);
    t.edgesMs = millisecondsSince(lap);
    decodeStripes(ws);
    t.decodeMs = millisecondsSince(lap);
    ws.frame = frame;
    computePoints(ws);
    t.depthMs = millisecondsSince(lap);
    t.totalMs = std::chrono::duration<double, std::milli>(lap - begin).count();

    result.points = std::span<const ScanPoint>(ws.points, static_cast<std::size_t>(ws.pointCount));
    result.superpixels = ws.regionCount;
    result.graphEdges = ws.edgeCount;
    result.decodedRegions = ws.decodedRegions;
    result.truncated = ws.truncated;
    ws.frame = ws.cameraFrame = {};
    lastFrame_ = frame;
    return result;
}

Status Decoder::repeatStage(DecoderStage stage, const FrameView& frame)
{
    if (lastFrame_.empty()) return Status::error("repeatStage: no frame was decoded yet (or the last decode failed)");
    if (frame.data != lastFrame_.data || frame.width != lastFrame_.width || frame.height != lastFrame_.height ||
        frame.stride != lastFrame_.stride || frame.format != lastFrame_.format)
        return Status::error("repeatStage: the frame is not the one the last decode() decoded");
    DecoderWorkspace& ws = *ws_;
    ws.cameraFrame = frame;
    ws.frame = stage == DecoderStage::Depth ? frame : segmentationFrame(ws, frame);
    switch (stage) {
    case DecoderStage::Gradient: computeGradient(ws); break;
    case DecoderStage::Watershed: computeWatershed(ws); break;
    case DecoderStage::Regions: computeRegions(ws); break;
    case DecoderStage::Graph: buildGraph(ws); break;
    case DecoderStage::Edges: computeEdgeFeatures(ws); break;
    case DecoderStage::Traversal: decodeStripes(ws); break;
    case DecoderStage::Depth: computePoints(ws); break;
    }
    ws.frame = ws.cameraFrame = {};
    return Status::ok();
}

const char* decoderStageName(DecoderStage stage)
{
    switch (stage) {
    case DecoderStage::Gradient: return "gradient";
    case DecoderStage::Watershed: return "watershed";
    case DecoderStage::Regions: return "regions";
    case DecoderStage::Graph: return "graph";
    case DecoderStage::Edges: return "edges";
    case DecoderStage::Traversal: return "traversal";
    case DecoderStage::Depth: return "depth";
    }
    return "unknown";
}

void Decoder::fillDepthMap(cv::Mat& depth) const
{
    const DecoderWorkspace& ws = *ws_;
    depth.create(ws.cameraHeight, ws.width, CV_32FC1);
    for (int y = 0; y < ws.cameraHeight; ++y) {
        float* row = depth.ptr<float>(y);
        std::fill(row, row + ws.width, std::numeric_limits<float>::quiet_NaN());
    }
    for (int i = 0; i < ws.pointCount; ++i) {
        const ScanPoint& p = ws.points[i];
        const int x = static_cast<int>(std::lround(p.pixel.x)), y = static_cast<int>(std::lround(p.pixel.y));
        if (x >= 0 && x < ws.width && y >= 0 && y < ws.cameraHeight) depth.at<float>(y, x) = p.position[2];
    }
}

std::size_t Decoder::workspaceBytes() const { return ws_->allocatedBytes; }
bool Decoder::workspaceHugePagesAdvised() const { return ws_->arena.hugePagesAdvised(); }
const DecoderParams& Decoder::params() const { return ws_->params; }

cv::Mat Decoder::labels() const { return cv::Mat(ws_->height, ws_->width, CV_32SC1, ws_->labels.get()); }

int Decoder::regionStripe(int label) const
{
    return label >= 0 && label < ws_->regionCount ? ws_->regions[label].stripe : -1;
}

}  // namespace stria::pipeline
