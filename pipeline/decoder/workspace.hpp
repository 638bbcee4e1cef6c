#pragma once
// The decoder's state: every buffer sized once by Decoder::create() and reused
// by each decode(). One stage per file in this folder; each stage reads and
// writes the workspace and nothing else, so the order in decoder.cpp is the
// whole data flow:
//   gradient.cpp   colour gradient magnitude (8 bit)
//   watershed.cpp  superpixel labels (watershed by steepest descent)
//   regions.cpp    per-superpixel median colour, crosstalk-corrected; centroid
//   graph.cpp      region adjacency graph with border statistics
//   edges.cpp      edge weight, symbol, errors (eq. 1-9), direction (fig. 5)
//   traversal.cpp  stripe positions by unique paths + best-first growth
//   depth.cpp      sub-pixel stripe edges per row, ray/light-plane points

#include "pipeline/decoder.hpp"
#include "pipeline/decoder/arena.hpp"
#include "pipeline/decoder/simd.hpp"

#include <array>
#include <cstdint>
#include <memory>

namespace stria::pipeline {

struct Region {
    std::array<float, 3> color{};     // median R G B after crosstalk correction
    std::array<float, 3> range{};     // eq. 1: largest |change| per channel over all neighbours
    float centroidX = 0, centroidY = 0;
    std::int32_t pixelCount = 0;
    std::int32_t adjacencyBegin = 0;  // incident edges: Workspace::adjacency[begin, begin + degree)
    std::int32_t degree = 0;
    // Decoding state.
    std::int32_t stripe = -1;     // pattern stripe index, -1 = undecoded
    std::int32_t reference = -1;  // decoded neighbour across a real stripe edge (null-edge test, fig. 6)
    std::int32_t component = -1;  // decoding pass that assigned the stripe
    float positionError = 0;      // eq. 10 for the assigned stripe
    std::int32_t tokens = 0;      // token bucket level on the path that reached this region
};

// Direction of an edge seen from its first region `a` (fig. 5).
enum class EdgeDirection : std::int8_t { Backward = -1, Parallel = 0, Forward = 1 };

struct GraphEdge {
    std::int32_t a = 0, b = 0;  // a < b
    std::int32_t borderCount = 0;
    // Sum of unit border normals pointing from a to b (pixel pairs: +-x for a
    // horizontal pair, +-y for a vertical one): the chord of the border line.
    std::int16_t normalX = 0, normalY = 0;
    float primaryGradient = 0, secondaryGradient = 0;  // eq. 8 sums over the border pixels
};

// An edge's features (edges.cpp), apart from its GraphEdge: the traversal
// visits edges along its regions' incidence lists, and 16 aligned bytes bring
// one cache line per visit where a GraphEdge with them (44 bytes) brought one
// or two; its passes over all edges read a third of the bytes.
struct EdgeFeature {
    // Bits 0-24: a ^ b (regions < 2^25, Decoder::create), so one end gives the
    // other; bits 25-26: the direction seen from a, + 1; bits 27-31: bestSymbol.
    std::uint32_t packed = 0;
    float weight = 0;  // eq. 3: L-inf of the raw colour change
    // bestMatch, gradientError and bestSymbol (eq. 7, seen from a to b): set
    // for edges across the stripes only (direction not Parallel), where
    // symbols are tested; else 0, 0 and kNullSymbol.
    // bestMatch = symbolError of bestSymbol (eq. 9 without the gradient
    // term): the traversal tests this symbol on most edges it follows.
    float bestMatch = 0;
    float gradientError = 0;  // eq. 8

    static constexpr int kEndBits = 25;
    static std::uint32_t pack(int a, int b, EdgeDirection direction, SymbolCode bestSymbol)
    {
        return static_cast<std::uint32_t>(a ^ b) | static_cast<std::uint32_t>(static_cast<int>(direction) + 1) << kEndBits |
               static_cast<std::uint32_t>(bestSymbol) << (kEndBits + 2);
    }
    int otherEnd(int from) const { return static_cast<int>(packed & ((1u << kEndBits) - 1)) ^ from; }
    EdgeDirection direction() const { return static_cast<EdgeDirection>(static_cast<int>(packed >> kEndBits & 3) - 1); }
    int directionPlusOne() const { return static_cast<int>(packed >> kEndBits & 3); }  // 0, 1, 2 (seen from a)
    SymbolCode bestSymbol() const { return static_cast<SymbolCode>(packed >> (kEndBits + 2)); }
};

// A pending visit in the best-first propagation: a region is stripe
// `stripe`, reached by an edge with some error.
struct OpenEntry {
    // Heap key (traversal.cpp): the error (eq. 9 for the hypothesised symbol)
    // as order-preserving bits in the high half, the region in the low half.
    std::uint64_t order;
    float positionError;  // eq. 10 term of that edge
    std::int32_t reference;  // the region's reference for later null-edge tests
    std::int16_t stripe;
    std::int16_t tokens;     // token bucket level after this edge
};

struct DecoderWorkspace {
    DecoderWorkspace(const StripePattern& pattern, const DecoderParams& params) : pattern(pattern), params(params) {}

    StripePattern pattern;
    DecoderParams params;
    // The segmentation frame's size: the camera's, or with
    // params.segmentRowPairs its row pairs' (height (cameraHeight + 1) / 2);
    // the stages up to the traversal see only it. The depth stage works on
    // the camera's rows, camera row y reading label row y / 2 with row pairs.
    int width = 0, height = 0;
    int cameraHeight = 0;
    // With params.segmentRowPairs: the frame averaged in row pairs (BGR or
    // RGB as the input, stride 3 x width), in the labels buffer past the
    // label rows, which then fill (at most) its first half.
    std::uint8_t* pairPixels = nullptr;
    cv::Matx33f colorCorrection;  // inverse of params.crosstalk (R G B)
    cv::Vec2f primary{1, 0};      // unit image direction of increasing projector column (epipolar)

    // Owns the memory of every ArenaArray below (arena.hpp): one block,
    // allocated by Decoder::create() (allocateWorkspace).
    WorkspaceArena arena;

    // Per pixel.
    ArenaArray<std::uint8_t> gradient;
    // In the gradient buffer (free after the watershed; 2 B/px, sized for
    // borderPositionEntries(width, height): one per pixel at most): each
    // label row's horizontal borders (x where label x differs from label
    // x + 1) as lists of their columns x, row y's in increasing order from
    // borderStarts[y] to borderStarts[y + 1] (height + 1 starts). Written by
    // the regions stage's first pass (appendBitPositions), walked by its copy
    // pass, the graph's horizontal pairs and depth's label changes in one
    // loop per row, where a loop per 64-bit word mispredicted its exit on
    // most words.
    std::uint16_t* borderPositions = nullptr;
    ArenaArray<std::int32_t> borderStarts;
    ArenaArray<std::int32_t> labels;
    // One buffer, five uses in turn: the watershed's plateau queue and
    // union-find parents, then pixels sorted by label (regions), then the
    // graph's hash table of label pairs, then the edges' changes (edgeChanges
    // below), then the output points (depth). Points are 24 bytes, so
    // maxPoints = pixels / 6 fits exactly.
    ArenaArray<std::byte> orderAndPoints;
    // Its size in int32 entries: max(watershedOrderEntries, regionOrderEntries, graphTableEntries, 4 maxEdges).
    std::size_t orderEntries = 0;
    std::int32_t* pixelOrder = nullptr;
    ScanPoint* points = nullptr;
    // Also in the order buffer, from the edge stage until depth: each edge's
    // equalised change from a to b (edges.cpp), which the traversal's symbol
    // tests read instead of computing it again (orderEntries >= 4 maxEdges).
    struct EdgeChange* edgeChanges = nullptr;
    // Gradient row lanes, watershed descent codes, region sums, the graph
    // edges' label pairs, then the traversal's seed sort keys and links and its
    // regions' stripes and components, then the depth stage's region stripes.
    ArenaArray<std::int32_t> scratch;
    // A row's bit positions as lists (appendBitPositions, simd.hpp), for the
    // watershed's bit loops: bitPositionEntries(width).
    ArenaArray<std::int32_t> bitPositions;

    // Graph.
    int maxRegions = 0, maxEdges = 0, maxPoints = 0;
    ArenaArray<Region> regions;
    ArenaArray<GraphEdge> edges;
    ArenaArray<EdgeFeature> edgeFeatures;  // per edge (edges.cpp)
    ArenaArray<std::int32_t> adjacency;  // 2 * maxEdges incident edge indices (CSR)
    ArenaArray<std::int32_t> edgeOrder;  // edges sorted by eq. 9's error (seeding order)
    int maxOpen = 0;
    ArenaArray<OpenEntry> open;          // heap, maxOpen entries after a sentinel
    int openCount = 0;
    ArenaArray<std::int32_t> candidates;  // seeding: candidate pattern positions (edgeCount);
                                                 // depth: each edge's point in the current row
    ArenaArray<std::int32_t> pathVertices;  // seeding: the path, window + 1 regions
    // Seeding: per seed symbol and path end (1: left, 0: right), the symbols
    // the first step of a unique-path search needs there: those of the
    // stripe edges beyond each of the symbol's pattern edges, each once, in
    // the pattern's order, and all of them as a mask (traversal.cpp). Most
    // searches end in their first step, whose candidates are all of the seed
    // symbol's edges: these depend on the pattern alone, so they are listed
    // at start-up (setFirstStepSymbols), not per search.
    struct FirstStepSymbols {
        std::array<SymbolCode, kSymbolCount> symbols{};
        int count = 0;
        std::uint32_t seen = 0;
    };
    std::array<std::array<FirstStepSymbols, 2>, kSymbolCount> firstStep{};
    ArenaArray<std::int32_t> componentSize;  // per pass (<= maxRegions)

    // Geometry.
    ArenaArray<Plane> lightPlanes;  // per pattern edge
    int rayGridStep = 4, rayGridWidth = 0, rayGridHeight = 0;
    ArenaArray<cv::Vec2f> rayGrid;  // undistorted normalised coordinates every rayGridStep px

    // Per-frame counts.
    int regionCount = 0, edgeCount = 0, pointCount = 0, passCount = 0, decodedRegions = 0;
    bool truncated = false;
    FrameView frame;        // the frame the current stage works on: the camera's or its row pairs
    FrameView cameraFrame;  // the camera's frame (decode() and repeatStage())
    std::array<int, 3> rgbOffset{2, 1, 0};  // byte offset of R, G, B within a pixel

    std::size_t allocatedBytes = 0;  // by create(): Decoder::workspaceBytes()
};

// DecoderWorkspace::borderPositions: each row's borders (fewer than width:
// columns 0 to width - 2) and the kBorderGroup junk entries appendBitPositions
// may write past the last. uint16 columns: widths up to 65536.
inline constexpr int kBorderGroup = 16;
// With row pairs, the gradient's floor is measured on every kFloorRowStep-th camera row (gradient.cpp).
inline constexpr int kFloorRowStep = 8;
inline std::size_t borderPositionEntries(int width, int height)
{
    return static_cast<std::size_t>(std::max(width - 1, 0)) * static_cast<std::size_t>(height) + kBorderGroup;
}

// DecoderWorkspace::bitPositions: three lists (the watershed's step 3), each
// of half a row's 64-bit words' pixels and the 8 junk entries
// appendBitPositions may write past a list's last; or one list of a whole row
// (step 4) and up to 16.
inline std::size_t bitPositionEntries(int width) { return 3 * (32 * static_cast<std::size_t>((width + 63) / 64) + 8); }

// Watershed: the scratch entries it needs (a descent code byte per pixel).
std::size_t watershedScratchEntries(int width, int height);
// The order buffer entries the watershed's union-find takes (a parent and a
// first pixel per provisional label: at most about one per two pixels).
std::size_t watershedOrderEntries(int width, int height);
// Region statistics and graph construction: the scratch entries they need.
std::size_t regionScratchEntries(std::size_t regions);
// The order buffer entries the region stage's sorted pixels take (a gap
// after each region's).
std::size_t regionOrderEntries(std::size_t pixels, std::size_t regions);
std::size_t graphScratchEntries(std::size_t regions, std::size_t edges);
// The graph's hash table of label pairs, in the order buffer (int32 entries;
// the buffer holds max(regionOrderEntries, this)).
std::size_t graphTableEntries(std::size_t regions, std::size_t edges);
// The scratch every stage's share fits in (decoder.cpp): the gradient kernel's
// row lanes, the watershed's codes, the region sums, the graph edges' label pairs;
// the traversal's seed keys and link pairs (2 entries per edge) and depth's
// region stripes fit in the graph's share.
std::size_t scratchEntries(int width, int height, int maxRegions, int maxEdges);
// Plans the per-pixel buffers and the graph's (gradient and border lists,
// labels, the order buffer, scratch, regions, edges, edge features, incidence
// lists) in ws.arena for ws.width x ws.height pixels, ws.maxRegions and
// ws.maxEdges, and sets orderEntries: the one sizing that create() and the
// stage tests share (decoder.cpp).
void reserveFrameBuffers(DecoderWorkspace& ws);
// Allocates ws.arena with what was planned in it and sets the views into the
// order buffer and the gradient buffer (pixelOrder, points, edgeChanges,
// borderPositions); returns the arena's bytes.
std::size_t allocateWorkspace(DecoderWorkspace& ws);
// reserveFrameBuffers, then allocateWorkspace (the stage tests' workspace).
std::size_t allocateFrameBuffers(DecoderWorkspace& ws);

// Per symbol code, the expected sign (-1, 0, +1) of each channel:
// symbolChannel from a table (its base-3 digits are slow to take apart in the
// per-edge and per-point loops).
inline constexpr auto kSymbolSigns = [] {
    std::array<std::array<std::int8_t, 3>, kSymbolCount> signs{};
    for (int s = 0; s < kSymbolCount; ++s)
        for (int c = 0; c < 3; ++c) signs[s][c] = static_cast<std::int8_t>(symbolChannel(static_cast<SymbolCode>(s), c));
    return signs;
}();

// Eq. 8's terms for one border pixel pair, (x, y)-(x + 1, y) if horizontal,
// else (x, y)-(x, y + 1): the image gradient at its middle, summed over the
// channels as |component along primary| and |component across it| (graph.cpp;
// the stage's kernels in simd.hpp give the same floats).
PairGradient pairGradient(const FrameView& frame, int x, int y, bool horizontal, const cv::Vec2f& primary);

// The stages, in order.
void computeGradient(DecoderWorkspace& ws);
void computeWatershed(DecoderWorkspace& ws);
void computeRegions(DecoderWorkspace& ws);
void buildGraph(DecoderWorkspace& ws);
void computeEdgeFeatures(DecoderWorkspace& ws);
void decodeStripes(DecoderWorkspace& ws);
// At start-up: ws.firstStep from ws.pattern (traversal.cpp).
void setFirstStepSymbols(DecoderWorkspace& ws);
void computePoints(DecoderWorkspace& ws);

// Shared by the edge and traversal stages (eq. 4-7).
struct EqualizedChange {
    std::array<float, 3> c{};  // R G B, max |c| = 1
    float weight = 0;          // L-inf of the raw change
    float relative = 0;        // L-inf of the brightness-relative change before normalising
};
EqualizedChange equalizedChange(const DecoderWorkspace& ws, int from, int to);
float matchError(const std::array<float, 3>& c, SymbolCode symbol, float t);
SymbolCode optimalSymbol(const std::array<float, 3>& c, float t);
// matchError of `symbol` after removing the change common to all channels
// that a texture edge adds, as far as it is plausible (edges.cpp).
float symbolError(const EqualizedChange& change, SymbolCode symbol, float t);
// The same with eq. 5-6's scales 1 / (1 - t) and 1 / t computed once by a
// stage that tests many symbols (two divisions fewer per test).
struct MatchScales {
    explicit MatchScales(float t) : on(1 / (1 - t)), off(1 / t)
    {
        for (int s = 0; s < kSymbolCount; ++s)
            for (int c = 0; c < 3; ++c) channel[s][c] = kSymbolSigns[s][c] == 0 ? off : on;
    }
    float on, off;
    // Per symbol code, each channel's scale: off where the symbol keeps the
    // channel constant, else on (the fourth: 0).
    alignas(16) std::array<std::array<float, 4>, kSymbolCount> channel{};
};
float symbolError(const EqualizedChange& change, SymbolCode symbol, const MatchScales& scales);
// The traversal's null-edge test in one pass: for c = equalizedChange(ws,
// from, to).c, whether optimalSymbol(c, t) is `symbol`, and if so
// matchError(c, symbol, t) (scales = MatchScales(t)); and the change's weight.
struct ExpectedSymbolMatch {
    bool fits = false;
    float error = 0;
    float weight = 0;
};
ExpectedSymbolMatch expectedSymbolMatch(const DecoderWorkspace& ws, int from, int to, SymbolCode symbol, float t,
                                        const MatchScales& scales);
// An edge's equalised change from a to b (DecoderWorkspace::edgeChanges),
// and the largest common change symbolError removes from it:
// std::min(0.3f, 0.15f / relative), 0 where relative is 0 (edges.cpp; the
// same from either end), which the traversal's tests of other symbols need
// and the edge stage has at hand.
struct EdgeChange {
    std::array<float, 3> c{};
    float commonBound = 0;
};
// symbolError of an EdgeChange: symbol_error.hpp (inline, for the traversal).

}  // namespace stria::pipeline
