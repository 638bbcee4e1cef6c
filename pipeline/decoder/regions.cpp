// Stage 3: superpixel colours and centroids, and the region adjacency
// graph's edges.
//
// The colour of a superpixel is the per-channel median of its pixels
// (marginal ordering, a rank filter robust to noise and to the blurred pixels
// at its border): the value at index size / 2 of its sorted values, then
// corrected for camera crosstalk.
//
// The graph has one vertex per superpixel and one edge per pair of
// superpixels that touch (4-neighbourhood, so it is planar and has at most
// 3V - 6 edges). Each border pixel pair adds to its edge: the count, the unit
// normal pointing from the smaller label to the larger one (their sum is the
// border's chord, used for the direction in fig. 5) and the image gradient
// split into the primary direction (across the stripes) and the secondary one
// (along them) for eq. 8. Edges are found through a short per-vertex list
// (degrees are ~6); buildGraph (graph.cpp) then lays them out as incidence
// lists.
//
// Two raster passes over the labels, without a branch per pixel: the ends of
// the runs of equal labels in a row come from borderMask, and a run's end is
// also a horizontal border pair. The first pass counts each region's pixels,
// sums their coordinates and adds the row's horizontal border pairs at the
// run ends, then its vertical ones (the graph's share of the pass: one mask
// per 64 horizontal neighbours serves both, and the label row is read once).
// The second, with the counts as offsets (a counting sort by label), copies
// each run's pixels, 4 bytes each, into the watershed's order buffer, where
// each region's pixels then lie together (a region's runs arrive in order, so
// its write position moves through one cache line at a time). Each region's
// medians are then selected from its own few hundred bytes, in L1
// (channelMedians, simd.hpp).
#include "pipeline/decoder/simd.hpp"
#include "pipeline/decoder/workspace.hpp"

#include <algorithm>
#include <bit>
#include <cstring>

namespace stria::pipeline {

std::size_t regionScratchEntries(std::size_t regions)
{
    // Coordinate sums (2 x int64) and a counter (int32) per region.
    return 5 * regions;
}

void computeRegions(DecoderWorkspace& ws)
{
    const int w = ws.width, h = ws.height, count = ws.regionCount;
    const std::int32_t* label = ws.labels.get();
    Region* regions = ws.regions.get();
    for (int r = 0; r < count; ++r) regions[r] = Region{};
    // Compact per-region arrays in the scratch (the Region records are 64
    // bytes apart): coordinate sums, then a counter, first of pixels and
    // then the position of the region's next pixel.
    auto* sums = reinterpret_cast<std::int64_t*>(ws.scratch.get());  // x, y per region
    auto* counter = reinterpret_cast<std::int32_t*>(sums + 2 * static_cast<std::ptrdiff_t>(count));
    std::fill(sums, sums + 2 * static_cast<std::ptrdiff_t>(count), 0);
    std::fill(counter, counter + count, 0);

    // Per region the list of its edges to larger labels, after the sums (the
    // GraphEdge records are 44 bytes apart): the walk touches 8 bytes per
    // edge.
    ws.edgeCount = 0;
    std::int32_t* head = ws.scratch.get() + regionScratchEntries(count);
    std::int32_t* next = head + count;
    std::int32_t* larger = next + ws.maxEdges;
    std::fill(head, head + count, -1);
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
    auto addRun = [&](int x, int end, int y, std::int32_t r) {
        const std::int64_t length = end - x;
        counter[r] += static_cast<std::int32_t>(length);
        sums[2 * r] += (x + end - 1) * length / 2;
        sums[2 * r + 1] += y * length;
    };

    // The first pass: per row its runs with their horizontal border pairs in
    // raster order, then its vertical border pairs.
    for (int y = 0; y < h; ++y) {
        const std::int32_t* row = label + static_cast<std::ptrdiff_t>(y) * w;
        const std::uint8_t* up = ws.frame.row(std::max(y - 1, 0));
        const std::uint8_t* pixels = ws.frame.row(y);
        const std::uint8_t* down = ws.frame.row(std::min(y + 1, h - 1));
        int x = 0;
        for (int x0 = 0; x0 + 1 < w; x0 += 64)
            for (std::uint64_t ends = borderMask(row + x0, row + x0 + 1, std::min(64, w - 1 - x0)); ends;
                 ends &= ends - 1) {
                const int last = x0 + std::countr_zero(ends);
                addRun(x, last + 1, y, row[x]);
                addPair(row[x], row[last + 1], true,
                        last + 2 < w ? horizontalPairGradient(up, pixels, down, last, ws.primary)
                                     : pairGradient(ws.frame, last, y, true, ws.primary));
                x = last + 1;
            }
        addRun(x, w, y, row[x]);
        if (y + 1 < h)
            for (int x0 = 0; x0 < w; x0 += 64)
                for (std::uint64_t bits = borderMask(row + x0, row + x0 + w, std::min(64, w - x0)); bits;
                     bits &= bits - 1) {
                    const int bx = x0 + std::countr_zero(bits);
                    addPair(row[bx], row[bx + w], false,
                            bx > 0 && bx + 2 < w ? verticalPairGradient(pixels, down, bx, ws.primary)
                                                 : pairGradient(ws.frame, bx, y, false, ws.primary));
                }
    }
    std::int32_t offset = 0;
    for (int r = 0; r < count; ++r) {
        regions[r].pixelCount = counter[r];
        const double size = counter[r];
        regions[r].centroidX = static_cast<float>(static_cast<double>(sums[2 * r]) / size);
        regions[r].centroidY = static_cast<float>(static_cast<double>(sums[2 * r + 1]) / size);
        counter[r] = offset;
        offset += regions[r].pixelCount;
    }

    // The second pass: a pixel's 3 bytes and the next one in 4 bytes (the
    // frame's last pixel has no next byte: 3 copied).
    auto* sorted = reinterpret_cast<std::uint32_t*>(ws.pixelOrder);
    for (int y = 0; y < h; ++y) {
        const std::int32_t* row = label + static_cast<std::ptrdiff_t>(y) * w;
        auto copyRun = [&](int x, int end) {
            const std::int32_t r = row[x];
            const std::uint8_t* pixel = ws.frame.row(y) + 3 * x;
            std::uint32_t* out = sorted + counter[r];
            counter[r] += end - x;
            const int whole = y + 1 == h && end == w ? end - 1 : end;
#pragma GCC unroll 4
            for (int i = x; i < whole; ++i, pixel += 3) std::memcpy(out++, pixel, 4);
            if (whole < end) std::memcpy(out, pixel, 3);
        };
        int x = 0;
        for (int x0 = 0; x0 + 1 < w; x0 += 64)
            for (std::uint64_t ends = borderMask(row + x0, row + x0 + 1, std::min(64, w - 1 - x0)); ends;
                 ends &= ends - 1) {
                const int end = x0 + std::countr_zero(ends) + 1;
                copyRun(x, end);
                x = end;
            }
        copyRun(x, w);
    }

    // channelMedians reads up to 3 pixels past a region's last: the last
    // regions take the reference.
    const std::ptrdiff_t n = static_cast<std::ptrdiff_t>(w) * h;
    const cv::Matx33f& m = ws.colorCorrection;
    for (int r = 0; r < count; ++r) {
        const int size = regions[r].pixelCount;
        const std::int32_t first = counter[r] - size;
        const std::array<std::uint8_t, 3> byByte = first + size + 3 <= n ? channelMedians(sorted + first, size)
                                                                          : channelMediansReference(sorted + first, size);
        const cv::Vec3f median(byByte[ws.rgbOffset[0]], byByte[ws.rgbOffset[1]], byByte[ws.rgbOffset[2]]);
        const cv::Vec3f corrected = m * median;
        regions[r].color = {corrected[0], corrected[1], corrected[2]};
    }
}

}  // namespace stria::pipeline
