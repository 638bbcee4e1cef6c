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

#include <algorithm>
#include <array>

namespace stria::pipeline {

std::size_t queueScratchEntries(std::size_t pixels)
{
    // Every level's chain has at most one partly filled block.
    // (+1 block: the prefetch reads kAhead entries past a position.)
    return (pixels / (kQueueBlock - 1) + 258) * kQueueBlock;
}

void computeWatershed(DecoderWorkspace& ws)
{
    const int w = ws.width, h = ws.height, n = w * h;
    const std::uint8_t* g = ws.gradient.get();
    std::int32_t* label = ws.labels.get();
    std::int32_t* order = ws.pixelOrder;
    std::int32_t* blocks = ws.scratch.get();
    constexpr int kLink = kQueueBlock - 1, kAhead = 8;
    constexpr std::int32_t kBorder = -2, kPixel = 0x7fffffff;

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
#pragma GCC unroll 4
        for (int p = 0; p < n; ++p) order[fill[g[p]]++] = p;
    }
    // Unlabelled pixels hold -1, or kBorder on the image border; a queue
    // entry carries that in its sign bit, so a pop needs no coordinates
    // unless the pixel is on the border.
    std::fill(label, label + n, -1);
    for (int x = 0; x < w; ++x) label[x] = label[n - w + x] = kBorder;
    for (int y = 0; y < h; ++y) label[y * w] = label[y * w + w - 1] = kBorder;

    // Queue of a level: entries from head to tail, both positions in blocks.
    // Every level starts with its own block, so a push needs no test for a
    // first block.
    std::array<std::int32_t, 256> head, tail;
    for (int l = 0; l < 256; ++l) head[l] = tail[l] = l * kQueueBlock;
    std::int32_t freeBlock = 256;
    // p's label before it was labelled tells whether it is on the border.
    auto push = [&](int level, std::int32_t p, std::int32_t unlabelled) {
        std::int32_t& t = tail[level];
        blocks[t++] = unlabelled == kBorder ? p | ~kPixel : p;
        if (t % kQueueBlock == kLink) {
            const std::int32_t block = freeBlock++ * kQueueBlock;
            blocks[t] = block;
            t = block;
        }
    };
    const double inverseWidth = 1.0 / w;
    auto drain = [&](int level) {
        std::int32_t& hd = head[level];
        while (hd != tail[level]) {
            if (hd % kQueueBlock == kLink) {
                hd = blocks[hd];
                continue;
            }
            // Prefetch the labels and levels around the pixel kAhead entries
            // on: the flood wanders over the image and its reads miss the
            // caches (1388x1038: the stage took 44-47 ms without, 37-40 with
            // the labels, 33-35 with the levels too, under load).
            // The entry there may be stale (past the tail or a link): it is
            // only a hint, clamped into the image.
            const std::int32_t ahead = std::min(blocks[hd + kAhead] & kPixel, n - 1);
            __builtin_prefetch(label + std::max(ahead - w, 0));
            __builtin_prefetch(label + ahead);
            __builtin_prefetch(label + std::min(ahead + w, n - 1));
            __builtin_prefetch(g + std::max(ahead - w, 0));
            __builtin_prefetch(g + std::min(ahead + w, n - 1));
            const std::int32_t entry = blocks[hd++];
            const std::int32_t p = entry & kPixel, l = label[p];
            auto visit = [&](std::int32_t q) {
                const std::int32_t old = label[q];
                if (old >= 0) return;
                label[q] = l;
                push(g[q] > level ? g[q] : level, q, old);
            };
            if (entry >= 0) {
                visit(p - 1);
                visit(p + 1);
                visit(p - w);
                visit(p + w);
                continue;
            }
            // (p + 0.5) / w is at least 0.5 / w from an integer: the double
            // quotient truncates exactly, and faster than an integer division.
            const int y = static_cast<int>((p + 0.5) * inverseWidth), x = p - y * w;
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
            const std::int32_t p = order[i], old = label[p];
            if (old >= 0) continue;
            if (regions == ws.maxRegions) {
                ws.truncated = true;
                continue;  // flooded later from a neighbouring basin
            }
            label[p] = regions++;
            push(level, p, old);
            drain(level);
        }
    }
    // The first pixel always starts a basin and the image is connected, so
    // every pixel is labelled even when the capacity was reached.
    ws.regionCount = regions;
}

}  // namespace stria::pipeline
