// Stage 2: superpixels by a watershed of the gradient magnitude.
//
// Meyer's flooding with a hierarchical queue (one FIFO per gradient level),
// seeded on the fly: pixels are visited in order of gradient level (a counting
// sort into pixelOrder, raster order within a level); after the queue of level
// L has drained, any pixel of level L that is still unlabelled cannot be
// reached from an existing basin through pixels <= L, so it lies on a new
// regional minimum and starts a new basin. Plateaus are split between basins
// breadth-first (FIFO), which is deterministic and geodesically fair. Every
// pixel gets a label; there are no watershed lines (a border is any pair of
// 4-neighbours with different labels). When maxRegions basins exist, new
// minima are left to be flooded by their neighbours and the frame is marked
// truncated.
//
// Speed: each FIFO is a chain of blocks of kQueueBlock entries in
// Workspace::scratch (the last slot links to the next block), so popping reads
// memory in sequence; a linked list through the pixels made every pop a
// dependent cache miss (the stage took a third of the decode). Each pixel is
// pushed exactly once and a level is never pushed to after it has drained, so
// blocks are handed out in turn and never recycled: queueScratchEntries()
// bounds the total.
#include "pipeline/decoder/workspace.hpp"

#include <array>

namespace stria::pipeline {

std::size_t queueScratchEntries(std::size_t pixels)
{
    // Every level's chain has at most one partly filled block.
    return (pixels / (kQueueBlock - 1) + 257) * kQueueBlock;
}

void computeWatershed(DecoderWorkspace& ws)
{
    const int w = ws.width, h = ws.height, n = w * h;
    const std::uint8_t* g = ws.gradient.get();
    std::int32_t* label = ws.labels.get();
    std::int32_t* order = ws.pixelOrder;
    std::int32_t* blocks = ws.scratch.get();
    constexpr int kLink = kQueueBlock - 1;

    // Level histogram in four interleaved copies: most pixels share level 0,
    // and one counter would make each increment wait for the previous one.
    std::array<std::array<std::int32_t, 256>, 4> counts{};
    int p = 0;
    for (; p + 4 <= n; p += 4)
        for (int k = 0; k < 4; ++k) ++counts[k][g[p + k]];
    for (; p < n; ++p) ++counts[0][g[p]];
    std::array<std::int32_t, 257> start{};
    for (int l = 0; l < 256; ++l) start[l + 1] = start[l] + counts[0][l] + counts[1][l] + counts[2][l] + counts[3][l];
    {
        std::array<std::int32_t, 256> fill;
        for (int l = 0; l < 256; ++l) fill[l] = start[l];
        for (int p = 0; p < n; ++p) order[fill[g[p]]++] = p;
    }
    for (int p = 0; p < n; ++p) label[p] = -1;

    // Queue of a level: entries from head to tail, both positions in blocks;
    // -1 until the level's first push.
    std::array<std::int32_t, 256> head, tail;
    head.fill(-1);
    tail.fill(-1);
    std::int32_t freeBlock = 0;
    auto push = [&](int level, std::int32_t p) {
        std::int32_t& t = tail[level];
        if (t < 0) {
            t = head[level] = freeBlock++ * kQueueBlock;
        } else if (t % kQueueBlock == kLink) {
            const std::int32_t block = freeBlock++ * kQueueBlock;
            blocks[t] = block;
            t = block;
        }
        blocks[t++] = p;
    };
    const double inverseWidth = 1.0 / w;
    auto drain = [&](int level) {
        std::int32_t& hd = head[level];
        while (hd != tail[level]) {
            if (hd % kQueueBlock == kLink) {
                hd = blocks[hd];
                continue;
            }
            const std::int32_t p = blocks[hd++];
            // (p + 0.5) / w is at least 0.5 / w from an integer: the double
            // quotient truncates exactly, and faster than an integer division.
            const int y = static_cast<int>((p + 0.5) * inverseWidth), x = p - y * w;
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
