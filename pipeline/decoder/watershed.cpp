// Stage 2: superpixels by a watershed of the gradient magnitude.
//
// Meyer's flooding with a hierarchical queue (one FIFO per gradient level,
// linked through Workspace::scratch), seeded on the fly: pixels are visited in
// order of gradient level (a counting sort into pixelOrder, raster order
// within a level); after the queue of level L has drained, any pixel of
// level L that is still unlabelled cannot be reached from an existing basin
// through pixels <= L, so it lies on a new regional minimum and starts a new
// basin. Plateaus are split between basins breadth-first (FIFO), which is
// deterministic and geodesically fair. Every pixel gets a label; there are no
// watershed lines (a border is any pair of 4-neighbours with different labels).
// When maxRegions basins exist, new minima are left to be flooded by their
// neighbours and the frame is marked truncated.
#include "pipeline/decoder/workspace.hpp"

#include <array>

namespace stria::pipeline {

void computeWatershed(DecoderWorkspace& ws)
{
    const int w = ws.width, h = ws.height, n = w * h;
    const std::uint8_t* g = ws.gradient.get();
    std::int32_t* label = ws.labels.get();
    std::int32_t* order = ws.pixelOrder;
    std::int32_t* next = ws.scratch.get();

    std::array<std::int32_t, 257> start{};
    for (int p = 0; p < n; ++p) ++start[g[p] + 1];
    for (int l = 0; l < 256; ++l) start[l + 1] += start[l];
    {
        std::array<std::int32_t, 256> fill;
        for (int l = 0; l < 256; ++l) fill[l] = start[l];
        for (int p = 0; p < n; ++p) order[fill[g[p]]++] = p;
    }
    for (int p = 0; p < n; ++p) label[p] = -1;

    std::array<std::int32_t, 256> head, tail;
    head.fill(-1);
    tail.fill(-1);
    auto push = [&](int level, std::int32_t p) {
        next[p] = -1;
        if (tail[level] < 0) head[level] = p;
        else next[tail[level]] = p;
        tail[level] = p;
    };
    auto drain = [&](int level) {
        while (head[level] >= 0) {
            const std::int32_t p = head[level];
            head[level] = next[p];
            if (head[level] < 0) tail[level] = -1;
            const int x = p % w, y = p / w;
            const std::int32_t l = label[p];
            auto visit = [&](std::int32_t q) {
                if (label[q] >= 0) return;
                label[q] = l;
                push(g[q] > level ? g[q] : level, q);
            };
            if (x > 0) visit(p - 1);
            if (x + 1 < w) visit(p + 1);
            if (y > 0) visit(p - w);
            if (y + 1 < h) visit(p + w);
        }
    };

    int regions = 0;
    for (int level = 0; level < 256; ++level) {
        drain(level);
        for (int i = start[level]; i < start[level + 1]; ++i) {
            const std::int32_t p = order[i];
            if (label[p] >= 0) continue;
            if (regions == ws.maxRegions) {
                ws.truncated = true;
                continue;  // flooded later from a neighbouring basin
            }
            label[p] = regions++;
            push(level, p);
            drain(level);
        }
    }
    // The first pixel always starts a basin and the image is connected, so
    // every pixel is labelled even when the capacity was reached.
    ws.regionCount = regions;
}

}  // namespace stria::pipeline
