// Stage 4: the region adjacency graph.
//
// One vertex per superpixel, one edge per pair of superpixels that touch
// (4-neighbourhood, so the graph is planar and has at most 3V - 6 edges). Each
// border pixel pair adds to its edge: the count, the unit normal pointing from
// the smaller label to the larger one (their sum is the border's chord, used
// for the direction in fig. 5) and the image gradient split into the primary
// direction (across the stripes) and the secondary one (along them) for eq. 8.
// Edges are found through a short per-vertex list (degrees are ~6), then laid
// out as compressed incidence lists for the traversal.
#include "pipeline/decoder/workspace.hpp"

#include <algorithm>
#include <cmath>

namespace stria::pipeline {

// The definition of a border pair's gradient terms (the graph test's
// reference calls it); buildGraph gets the same floats from the kernels
// horizontalPairGradient and verticalPairGradient (simd.hpp), except in the
// first and last columns, which they do not reach.
PairGradient pairGradient(const FrameView& frame, int x, int y, bool horizontal, const cv::Vec2f& primary)
{
    const int w = frame.width, h = frame.height;
    const float px = primary[0], py = primary[1];
    const std::uint8_t* r0 = frame.row(y);
    PairGradient out;
    for (int c = 0; c < 3; ++c) {
        float gx, gy;
        if (horizontal) {
            const std::uint8_t* up = frame.row(std::max(y - 1, 0));
            const std::uint8_t* down = frame.row(std::min(y + 1, h - 1));
            gx = static_cast<float>(r0[3 * (x + 1) + c] - r0[3 * x + c]);
            gy = 0.25f * static_cast<float>(down[3 * x + c] - up[3 * x + c] + down[3 * (x + 1) + c] -
                                            up[3 * (x + 1) + c]);
        } else {
            const std::uint8_t* r1 = frame.row(y + 1);
            const int xl = 3 * std::max(x - 1, 0) + c, xr = 3 * std::min(x + 1, w - 1) + c;
            gy = static_cast<float>(r1[3 * x + c] - r0[3 * x + c]);
            gx = 0.25f * static_cast<float>(r0[xr] - r0[xl] + r1[xr] - r1[xl]);
        }
        out.primary += std::abs(gx * px + gy * py);
        out.secondary += std::abs(-gx * py + gy * px);
    }
    return out;
}

std::size_t graphScratchEntries(std::size_t regions, std::size_t edges)
{
    // A list head per region; the next edge and the larger label per edge.
    return regions + 2 * edges;
}

void buildGraph(DecoderWorkspace& ws)
{
    const int w = ws.width, h = ws.height;
    const std::int32_t* label = ws.labels.get();
    ws.edgeCount = 0;

    // Per region the list of its edges to larger labels, in compact arrays
    // in the scratch (the Region and GraphEdge records are 64 and 44 bytes
    // apart): the walk touches 8 bytes per edge.
    std::int32_t* head = ws.scratch.get();
    std::int32_t* next = head + ws.regionCount;
    std::int32_t* larger = next + ws.maxEdges;
    std::fill(head, head + ws.regionCount, -1);
    auto findOrAddEdge = [&](std::int32_t a, std::int32_t b) -> std::int32_t {
        for (std::int32_t e = head[a]; e >= 0; e = next[e])
            if (larger[e] == b) return e;
        if (ws.edgeCount == ws.maxEdges) {
            ws.truncated = true;
            return -1;
        }
        const std::int32_t e = ws.edgeCount++;
        GraphEdge& edge = ws.edges[e];
        edge = GraphEdge{};
        edge.a = a;
        edge.b = b;
        larger[e] = b;
        next[e] = head[a];
        head[a] = e;
        return e;
    };

    // Adds border pair p-q (q right of p or below it) to its edge.
    // Consecutive vertical pairs along a horizontal border share their labels
    // and edge: the last pair's edge is reused without a list walk.
    std::int32_t lastP = -1, lastQ = -1, lastEdge = -1;
    auto addPair = [&](std::int32_t lp, std::int32_t lq, bool horizontal, const PairGradient& gradient) {
        if (lp != lastP || lq != lastQ) {
            lastP = lp;
            lastQ = lq;
            // Without a branch: which side has the smaller label is unpredictable.
            lastEdge = findOrAddEdge(std::min(lp, lq), std::max(lp, lq));
        }
        if (lastEdge < 0) return;
        const int sign = lp < lq ? 1 : -1;  // +1: the normal from a to b points to +x / +y
        GraphEdge& edge = ws.edges[lastEdge];
        ++edge.borderCount;
        std::int16_t& normal = horizontal ? edge.normalX : edge.normalY;
        if (normal > -32767 && normal < 32767) normal = static_cast<std::int16_t>(normal + sign);
        edge.primaryGradient += gradient.primary;
        edge.secondaryGradient += gradient.secondary;
    };

    // The border pairs of each row in raster order, horizontal then
    // vertical.
    for (int y = 0; y < h; ++y) {
        const std::int32_t* row = label + static_cast<std::ptrdiff_t>(y) * w;
        const std::uint8_t* up = ws.frame.row(std::max(y - 1, 0));
        const std::uint8_t* pixels = ws.frame.row(y);
        const std::uint8_t* down = ws.frame.row(std::min(y + 1, h - 1));
        forEachBorder(row, row + 1, w - 1, [&](int x) {
            addPair(row[x], row[x + 1], true,
                    x + 2 < w ? horizontalPairGradient(up, pixels, down, x, ws.primary)
                              : pairGradient(ws.frame, x, y, true, ws.primary));
        });
        if (y + 1 < h)
            forEachBorder(row, row + w, w, [&](int x) {
                addPair(row[x], row[x + w], false,
                        x > 0 && x + 2 < w ? verticalPairGradient(pixels, down, x, ws.primary)
                                           : pairGradient(ws.frame, x, y, false, ws.primary));
            });
    }

    // Incidence lists (CSR).
    Region* regions = ws.regions.get();
    for (int e = 0; e < ws.edgeCount; ++e) {
        ++regions[ws.edges[e].a].degree;
        ++regions[ws.edges[e].b].degree;
    }
    std::int32_t offset = 0;
    for (int r = 0; r < ws.regionCount; ++r) {
        regions[r].adjacencyBegin = offset;
        offset += regions[r].degree;
        regions[r].degree = 0;
    }
    for (int e = 0; e < ws.edgeCount; ++e) {
        for (std::int32_t v : {ws.edges[e].a, ws.edges[e].b}) {
            Region& r = regions[v];
            ws.adjacency[r.adjacencyBegin + r.degree++] = e;
        }
    }
}

}  // namespace stria::pipeline
