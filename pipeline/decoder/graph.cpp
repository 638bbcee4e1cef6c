// Stage 4: the region adjacency graph's incidence lists.
//
// computeRegions (regions.cpp) finds the edges and their border statistics in
// its raster pass over the labels; this stage lays them out as compressed
// incidence lists (CSR) for the traversal, each region's edges in increasing
// order.
#include "pipeline/decoder/workspace.hpp"

#include <algorithm>
#include <cmath>

namespace stria::pipeline {

// The definition of a border pair's gradient terms (the graph test's
// reference calls it); computeRegions gets the same floats from the kernels
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
    // computeRegions' edge lists: a head per region; the next edge and the
    // larger label per edge.
    return regions + 2 * edges;
}

void buildGraph(DecoderWorkspace& ws)
{
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
