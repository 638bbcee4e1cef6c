// Stage 3: superpixel colours and centroids.
//
// The colour of a superpixel is the per-channel median of its pixels
// (marginal ordering, a rank filter robust to noise and to the blurred pixels
// at its border): the value at index size / 2 of its sorted values, then
// corrected for camera crosstalk.
//
// Two raster passes over the runs of equal labels in each row (their ends
// from forEachBorder, without a branch per pixel, whose masks the first pass
// stores for the second and for the graph and depth stages): the first counts each
// region's pixels and sums their coordinates; the second, with the counts as
// offsets (a counting sort by label), copies each run's pixels, 4 bytes each
// (as value ^ kRegionByteBias: 0x80 for SSE2's signed compares, 0 on
// NEON), into the watershed's order buffer, where each region's pixels then
// lie together, kRegionPad free entries after each region's (a region's runs arrive in
// order, so its write position moves through one cache line at a time).
// Each region's medians are then selected from its own few hundred bytes,
// in L1 (channelMedians, simd.hpp).
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

// Each region's sorted pixels are followed by kRegionGap free entries: the
// copy writes whole blocks of 4 pixels from a run's first, up to 3 past the
// run's end, and the median search reads a region's last block whole, up to
// kRegionPad entries past its last pixel (where it finds the value 0, written
// after the copy): 7 on x86-64 (the AVX2 searches' blocks of 8 pixels; the
// order buffer 1.19 -> 1.44 entries per pixel at the default capacity), 3
// elsewhere.
namespace {
constexpr int kRegionGap = kRegionPad;
static_assert(kRegionGap >= 3);

// The copy pass: each run's pixels, a pixel's 3 bytes and the next one in 4
// bytes (the frame's last pixel has no next byte: 3 copied), each byte ^
// kRegionByteBias (x86: 0x80, channelMedians compares them as signed bytes;
// NEON: 0, no xor), to its region's next
// positions, from next[r] (the address of its next entry, as an integer:
// advanced by the run's length; with an offset into the buffer each run took
// 2 instructions more).
//
// Four pixels of 3 bytes at from (16 bytes read) to 4 bytes each, by one
// byte shuffle (SSSE3 pshufb in the x86-64-v3 version, tbl on AArch64): 3
// instructions per 4 pixels (with the tighter run loop, 780x580 copy pass
// 5.5 -> 2.7 M instructions per decode). Without one (SSE2), two pixels per 8-byte load
// and store, their 4 bytes apart by a shift (little-endian), 14 instructions:
// half the loads and stores of a 4-byte copy per pixel (copy phase 780x580
// 0.56 -> 0.53 ms, 1388x1038 1.66 -> 1.42 ms).
using Bytes16 = std::uint8_t __attribute__((vector_size(16)));
[[gnu::always_inline]] inline void fourPixelsShuffled(std::uint32_t* to, const std::uint8_t* from)
{
    Bytes16 bytes;
    std::memcpy(&bytes, from, 16);
    bytes = __builtin_shuffle(bytes, Bytes16{0, 1, 2, 3, 3, 4, 5, 6, 6, 7, 8, 9, 9, 10, 11, 12}) ^ kRegionByteBias;
    std::memcpy(to, &bytes, 16);
}
[[gnu::always_inline]] inline void fourPixelsShifted(std::uint32_t* to, const std::uint8_t* from)
{
    static_assert(std::endian::native == std::endian::little);
    auto twoPixels = [](std::uint32_t* to, const std::uint8_t* from) {
        std::uint64_t bytes;
        std::memcpy(&bytes, from, 8);
        bytes = ((bytes & 0xffffffffu) | (bytes >> 24) << 32) ^ kRegionByteBias * 0x0101010101010101u;
        std::memcpy(to, &bytes, 8);
    };
    twoPixels(to, from);
    twoPixels(to + 2, from + 6);
}

// threeBlocks: a third block without a loop (where the frame's runs average
// more than 8 pixels: the loop's exit was then mispredicted on most runs).
template <bool shuffled, bool threeBlocks>
[[gnu::always_inline]] inline void copyRuns(const DecoderWorkspace& ws, std::int64_t* next)
{
    const int w = ws.width, h = ws.height;
    const std::uint16_t* const positions = ws.borderPositions;
    const std::int32_t* const starts = ws.borderStarts.get();
    // Rows whose next row has 25 bytes or more (the whole blocks read up to
    // 25 bytes past a row's end; 37 with the third block).
    const int blockRows = w >= (threeBlocks ? 13 : 9) ? h - 1 : 0;
    for (int y = 0; y < h; ++y) {
        const std::int32_t* row = ws.labels.get() + static_cast<std::ptrdiff_t>(y) * w;
        const std::uint8_t* pixels = ws.frame.row(y);
        std::ptrdiff_t x = 0;
        if (y >= blockRows) {
            auto run = [&](std::ptrdiff_t end) {
                auto* out = reinterpret_cast<std::uint32_t*>(next[row[x]]);
                next[row[x]] = reinterpret_cast<std::int64_t>(out + (end - x));
                const std::ptrdiff_t whole = y + 1 == h && end == w ? end - 1 : end;
                const std::uint8_t* pixel = pixels + 3 * x;
                auto copy = [&](int bytes) {
                    std::uint32_t value = 0;
                    std::memcpy(&value, pixel, bytes);
                    value ^= kRegionByteBias * 0x01010101u;
                    std::memcpy(out++, &value, 4);
                };
                for (std::ptrdiff_t i = x; i < whole; ++i, pixel += 3) copy(4);
                if (whole < end) copy(3);
                x = end;
            };
            for (const std::uint16_t* p = positions + starts[y]; p != positions + starts[y + 1]; ++p)
                run(std::ptrdiff_t{*p} + 1);
            run(w);
            continue;
        }
        auto run = [&](std::ptrdiff_t end) {
            const std::ptrdiff_t r = row[x], length = end - x;
            auto* out = reinterpret_cast<std::uint32_t*>(next[r]);
            next[r] = reinterpret_cast<std::int64_t>(out + length);
            // The region's next cache line, which one of its next runs will
            // write (a row or two later): the first write to each line was a
            // miss to L3 or memory (the buffer is 4 bytes per pixel).
            __builtin_prefetch(out + length + 16, 1);
            // Whole blocks of 4: up to 3 pixels past the run land in the
            // region's own later positions, which its later runs overwrite,
            // or in the gap after it (kRegionGap: before the gaps, a run
            // near its region's end took the pixel loop, a branch that was
            // mispredicted 9 k times per 780x580 decode).
            // The first two blocks without a loop, the second into a sink
            // where the run has at most 4 pixels (selected, not branched on:
            // run lengths are noise to a branch predictor, and a loop's exit
            // was mispredicted on most runs; 780x580: -18 k mispredictions,
            // copy phase 0.59 -> 0.51 ms). They read at most 25 bytes past
            // the row's end (inside the next row). Runs of more than 8 pixels
            // loop over the rest. Where runs average more than 8 pixels
            // (1388x1038: ~9.4), a third block the same way, into the sink
            // where the run has at most 8 pixels (37 bytes past the row's
            // end), and the loop from 12.
            const std::uint8_t* pixel = pixels + 3 * x;
            auto block = [&](std::uint32_t* to, int i) {
                if constexpr (shuffled)
                    fourPixelsShuffled(to, pixel + 3 * i);
                else
                    fourPixelsShifted(to, pixel + 3 * i);
            };
            std::uint32_t sink[4];
            std::uint32_t* second = length > 4 ? out + 4 : sink;
            // Hidden from GCC, which would otherwise see the sink's stores
            // as dead and branch around the second block.
            hide(second);
            block(out, 0);
            block(second, 4);
            int i = 8;
            if constexpr (threeBlocks) {
                std::uint32_t* third = length > 8 ? out + 8 : sink;
                hide(third);
                block(third, 8);
                i = 12;
            }
            // The loop's bound also hidden: GCC would otherwise branch on
            // length > 8 for both the third block and the loop.
            std::ptrdiff_t loopEnd = length;
            hide(loopEnd);
            if constexpr (kRegionGap >= 7) {
                // Two blocks per step where the gap takes 7 entries past a
                // run (x86-64): half the loop's steps, fewer of its exits
                // mispredicted (1388x1038: -5.3 k per decode, 780x580 -1.7 k;
                // +0.04 and +0.01 M instructions, the runs whose last block
                // of 4 was the step's first).
                for (; i < loopEnd; i += 8) {
                    block(out + i, i);
                    block(out + i + 4, i + 4);
                }
            } else {
                for (; i < loopEnd; i += 4) block(out + i, i);
            }
            x = end;
        };
        // The first pass's list of the row's borders (the reference:
        // forEachBorder(row, row + 1, w - 1, visit), a loop per 64-bit word).
        const std::uint16_t* const positionsEnd = positions + starts[y + 1];
        for (const std::uint16_t* p = positions + starts[y]; p != positionsEnd; ++p) run(std::ptrdiff_t{*p} + 1);
        run(w);
    }
}

#if defined(__x86_64__)
// SSE2 has no byte shuffle: the x86-64-v3 version (picked at run time by
// GCC's function multiversioning, an ifunc) has SSSE3's.
[[gnu::target("default")]] void copyRunsVersion(const DecoderWorkspace& ws, std::int64_t* next, bool threeBlocks)
{
    threeBlocks ? copyRuns<false, true>(ws, next) : copyRuns<false, false>(ws, next);
}
[[gnu::target("arch=x86-64-v3")]] void copyRunsVersion(const DecoderWorkspace& ws, std::int64_t* next,
                                                       bool threeBlocks)
{
    threeBlocks ? copyRuns<true, true>(ws, next) : copyRuns<true, false>(ws, next);
}
#else
void copyRunsVersion(const DecoderWorkspace& ws, std::int64_t* next, bool threeBlocks)
{
#if defined(__aarch64__)
    constexpr bool shuffled = true;
#else
    constexpr bool shuffled = false;
#endif
    threeBlocks ? copyRuns<shuffled, true>(ws, next) : copyRuns<shuffled, false>(ws, next);
}
#endif
}  // namespace

std::size_t regionOrderEntries(std::size_t pixels, std::size_t regions)
{
    return pixels + kRegionGap * regions;
}

// Cloned for x86-64-v3 and -v4 (STRIA_X86_CLONES, simd.hpp): its run and
// colour loops in VEX three-operand forms with BMI1/2 (shrx, blsr, tzcnt),
// and the sampled runs' count by popcnt (the baseline calls libgcc's
// __popcountdi2). The same floats: the project builds with
// -ffp-contract=off (no multiply and add fuse); the kernels it calls are
// per-target already. 780x580: regions 2.24 -> 2.11 M instructions per
// decode without its kernels (the v3 clone, which callgrind runs).
STRIA_X86_CLONES void computeRegions(DecoderWorkspace& ws)
{
    const int w = ws.width, h = ws.height, count = ws.regionCount;
    const std::int32_t* label = ws.labels.get();
    Region* regions = ws.regions.get();
    for (int r = 0; r < count; ++r) regions[r] = Region{};
    // Compact per-region arrays in the scratch (the Region records are 64
    // bytes apart): coordinate sums (then, in the first of each region's 2
    // slots, the address of its next pixel in the sorted buffer), then its
    // pixel counter.
    auto* sums = reinterpret_cast<std::int64_t*>(ws.scratch.get());  // x, y per region
    auto* counter = reinterpret_cast<std::int32_t*>(sums + 2 * static_cast<std::ptrdiff_t>(count));
    std::fill(sums, sums + 2 * static_cast<std::ptrdiff_t>(count), 0);
    std::fill(counter, counter + count, 0);

    // The first pass: each run's length and coordinate sums to its region's.
    // It stores the rows' borders as lists of their columns
    // (ws.borderPositions, flattened from borderMask's 64-bit masks by
    // appendBitPositions: kBorderGroup per word without a branch), which it,
    // the copy pass and the graph and depth stages walk in one loop per row.
    // The reference is forEachBorder(row, row + 1, w - 1, visit), a loop per
    // word, whose exit a branch predictor missed on most words.
    std::uint16_t* const positions = ws.borderPositions;
    std::int32_t* const starts = ws.borderStarts.get();
    std::uint16_t* positionsEnd = positions;
    for (int y = 0; y < h; ++y) {
        const std::int32_t* row = label + static_cast<std::ptrdiff_t>(y) * w;
        const std::int64_t y64 = y;
        std::ptrdiff_t x = 0;
        auto run = [&](std::ptrdiff_t end) {
            const std::ptrdiff_t r = row[x], length = end - x;
            counter[r] += static_cast<std::int32_t>(length);
            sums[2 * r] += (x + end - 1) * length;  // twice the x sum (halved once per region)
            sums[2 * r + 1] += y64 * length;
            x = end;
        };
        std::uint16_t* const rowPositions = positionsEnd;
        starts[y] = static_cast<std::int32_t>(rowPositions - positions);
        for (int i0 = 0; i0 < w - 1; i0 += 64) {
            const std::uint64_t bits = borderMask(row + i0, row + i0 + 1, std::min(64, w - 1 - i0));
            positionsEnd = appendBitPositions<kBorderGroup>(bits, static_cast<std::uint16_t>(i0), positionsEnd);
        }
        for (const std::uint16_t* p = rowPositions; p != positionsEnd; ++p) run(std::ptrdiff_t{*p} + 1);
        run(w);
    }
    starts[h] = static_cast<std::int32_t>(positionsEnd - positions);
    auto* sorted = reinterpret_cast<std::uint32_t*>(ws.pixelOrder);
    std::int64_t* next = sums;  // next[r] overwrites sums[r], read at r / 2
    std::uint32_t* first = sorted;
    for (int r = 0; r < count; ++r) {
        regions[r].pixelCount = counter[r];
        const double size = counter[r];
        regions[r].centroidX = static_cast<float>(static_cast<double>(sums[2 * r] / 2) / size);
        regions[r].centroidY = static_cast<float>(static_cast<double>(sums[2 * r + 1]) / size);
        next[r] = reinterpret_cast<std::int64_t>(first);
        first += counter[r] + kRegionGap;
    }

    // The runs of every 8th row, from their lists (only the copy's choice
    // of blocks depends on it: a sample suffices; a count per run in the
    // first pass took 0.08 M instructions per 780x580 decode, this 0.01 M).
    std::int64_t sampledRuns = 0, sampledPixels = 0;
    for (int y = 0; y < h; y += 8) {
        sampledRuns += 1 + starts[y + 1] - starts[y];
        sampledPixels += w;
    }
    copyRunsVersion(ws, next, sampledPixels > 8 * sampledRuns);

    // Regions of up to 255 pixels four at a time (channelMediansOfFourAlike
    // and channelMediansOfFour overlap their searches), larger ones alone. They count a region's last
    // block whole, up to kRegionPad entries into its gap: the gap's entries get
    // the value 0 (bytes kRegionByteBias), which no search counts (without them each
    // pass masked the last block's lanes, 5 instructions per region and
    // pass: 780x580 medians of four 2.99 -> 2.78 M instructions per
    // decode, with the jumps' bounds checks). Written kPadAhead regions before the
    // region's search: loads of a block just stored in parts wait for the
    // stores (a failed store forward).
    const cv::Matx33f& m = ws.colorCorrection;
    auto setColor = [&](int r, const std::array<std::uint8_t, 3>& byByte) {
        const cv::Vec3f median(byByte[ws.rgbOffset[0]], byByte[ws.rgbOffset[1]], byByte[ws.rgbOffset[2]]);
        const cv::Vec3f corrected = m * median;
        regions[r].color = {corrected[0], corrected[1], corrected[2]};
    };
    // The same for a group of four, region j in lane j (GCC vector
    // extensions: SSE2 and NEON): the same floats as setColor, whose product
    // m * median sums 0 + m(i, 0) v0 + m(i, 1) v1 + m(i, 2) v2 in this order
    // (91 instructions per group with the call, where setColor's took 179:
    // 780x580 -0.23 M instructions per decode).
    using Floats = float __attribute__((vector_size(16)));
    using Ints = std::int32_t __attribute__((vector_size(16)));
    std::array<std::array<Floats, 3>, 3> mLanes;
    for (int i = 0; i < 3; ++i)
        for (int k = 0; k < 3; ++k) mLanes[i][k] = Floats{} + m(i, k);
    const std::array<int, 3> shifts{8 * ws.rgbOffset[0], 8 * ws.rgbOffset[1], 8 * ws.rgbOffset[2]};
    auto setColorsOfFour = [&](const std::array<int, 4>& r, const std::array<std::uint32_t, 4>& byDword) {
        Ints dwords;
        std::memcpy(&dwords, byDword.data(), sizeof dwords);
        std::array<Floats, 3> median, corrected;
        for (int k = 0; k < 3; ++k) median[k] = __builtin_convertvector((dwords >> shifts[k]) & 0xff, Floats);
        for (int i = 0; i < 3; ++i)
            corrected[i] = ((Floats{} + mLanes[i][0] * median[0]) + mLanes[i][1] * median[1]) + mLanes[i][2] * median[2];
        for (int j = 0; j < 4; ++j) regions[r[j]].color = {corrected[0][j], corrected[1][j], corrected[2][j]};
    };
    // Regions of up to 255 pixels wait in a bucket per block count (1-64)
    // for a group of four (channelMediansOfFourAlike walks their blocks
    // together, one jump per pass for the four); those left over at the end
    // go four at a time to channelMediansOfFour, the last up to 3 alone
    // (780x580 regions 9.38 -> 9.17 M instructions per decode; 1388x1038
    // 23.98 -> 23.71 M, their indirect jumps' mispredictions 9.1 -> 2.6 k).
    struct Bucket {
        std::array<const std::uint32_t*, 4> pixels;
        std::array<int, 4> counts, regions;
        int waiting = 0;
        // Adds a region; true when the bucket then holds four (the caller
        // takes them and sets waiting to 0).
        bool add(const std::uint32_t* regionPixels, int count, int region)
        {
            pixels[waiting] = regionPixels;
            counts[waiting] = count;
            regions[waiting] = region;
            return ++waiting == 4;
        }
    };
    std::array<Bucket, 64> buckets;
    auto pad = [&](int r) {
        constexpr std::uint64_t zeros = kRegionByteBias * 0x0101010101010101u;
        auto* end = reinterpret_cast<std::uint32_t*>(next[r]);
        // kRegionPad entries: 3 in 8 + 4 bytes, 7 in 16 + 8 + 4.
        for (int i = 0; i + 1 < kRegionPad; i += 2) std::memcpy(end + i, &zeros, 8);
        std::memcpy(end + kRegionPad - 1, &zeros, 4);
    };
    constexpr int kPadAhead = 8;
    for (int r = 0; r < std::min(count, kPadAhead); ++r) pad(r);
    for (int r = 0; r < count; ++r) {
        pad(std::min(r + kPadAhead, count - 1));
        const int size = counter[r];
        const std::uint32_t* pixels = reinterpret_cast<const std::uint32_t*>(next[r]) - size;
        if (size > 255) {
            setColor(r, channelMedians(pixels, size));
        } else {
            Bucket& bucket = buckets[(size - 1) / 4];
            if (bucket.add(pixels, size, r)) {
                setColorsOfFour(bucket.regions, channelMediansOfFourAlike(bucket.pixels, bucket.counts));
                bucket.waiting = 0;
            }
        }
    }
    Bucket left;
    for (const Bucket& bucket : buckets)
        for (int j = 0; j < bucket.waiting; ++j) {
            if (left.add(bucket.pixels[j], bucket.counts[j], bucket.regions[j])) {
                setColorsOfFour(left.regions, channelMediansOfFour(left.pixels, left.counts));
                left.waiting = 0;
            }
        }
    for (int j = 0; j < left.waiting; ++j) setColor(left.regions[j], channelMedians(left.pixels[j], left.counts[j]));
}

}  // namespace stria::pipeline
