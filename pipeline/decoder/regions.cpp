// Stage 3: superpixel colours and centroids.
//
// The colour of a superpixel is the per-channel median of its pixels
// (marginal ordering, a rank filter robust to noise and to the blurred pixels
// at its border): the value at index size / 2 of its sorted values, then
// corrected for camera crosstalk.
//
// Linear time, no per-region sorting: per channel, the labels of all pixels
// are counting-sorted by the pixel's value into pixelOrder (reusing the
// watershed's order buffer); sweeping that order from value 0 up, a region's
// median is the value at which its (size / 2 + 1)-th pixel arrives. The sweep
// touches one int32 counter per region (L1-resident) and the sorted labels in
// sequence. Pixel counts and coordinate sums come from one raster pass over
// the runs of equal labels in each row, together with the three value
// histograms the counting sorts start from.
#include "pipeline/decoder/simd.hpp"
#include "pipeline/decoder/workspace.hpp"

#include <algorithm>
#include <array>

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
    // then, per channel, of the pixels left before the median.
    auto* sums = reinterpret_cast<std::int64_t*>(ws.scratch.get());  // x, y per region
    auto* counter = reinterpret_cast<std::int32_t*>(sums + 2 * static_cast<std::ptrdiff_t>(count));
    std::fill(sums, sums + 2 * static_cast<std::ptrdiff_t>(count), 0);
    std::fill(counter, counter + count, 0);

    std::array<ValueHistogram, 3> histogram{};
    for (int y = 0; y < h; ++y) {
        const std::int32_t* row = label + static_cast<std::ptrdiff_t>(y) * w;
        for (int x = 0; x < w;) {
            const std::int32_t r = row[x];
            int end = x + 1;
            while (end < w && row[end] == r) ++end;
            const std::int64_t length = end - x;
            counter[r] += static_cast<std::int32_t>(length);
            sums[2 * r] += (x + end - 1) * length / 2;
            sums[2 * r + 1] += y * length;
            x = end;
        }
        channelHistograms(ws.frame.row(y), w, ws.rgbOffset, histogram);
    }
    for (int r = 0; r < count; ++r) {
        regions[r].pixelCount = counter[r];
        const double size = counter[r];
        regions[r].centroidX = static_cast<float>(static_cast<double>(sums[2 * r]) / size);
        regions[r].centroidY = static_cast<float>(static_cast<double>(sums[2 * r + 1]) / size);
    }

    std::int32_t* byValue = ws.pixelOrder;
    for (int c = 0; c < 3; ++c) {
        std::array<std::int32_t, 257> start;
        start[0] = 0;
        for (int v = 0; v < 256; ++v) start[v + 1] = start[v] + histogram[c][v];
        std::array<std::int32_t, 256> cursor;
        std::copy(start.begin(), start.begin() + 256, cursor.begin());
        for (int y = 0; y < h; ++y)
            scatterLabelsByValue(ws.frame.row(y) + ws.rgbOffset[c], label + static_cast<std::ptrdiff_t>(y) * w, w,
                                 cursor.data(), byValue);
        for (int r = 0; r < count; ++r) counter[r] = regions[r].pixelCount / 2 + 1;
        for (int v = 0; v < 256; ++v) {
#pragma GCC unroll 4
            for (int i = start[v]; i < start[v + 1]; ++i)
                if (--counter[byValue[i]] == 0) regions[byValue[i]].color[c] = static_cast<float>(v);
        }
    }

    const cv::Matx33f& m = ws.colorCorrection;
    for (int r = 0; r < count; ++r) {
        const std::array<float, 3>& median = regions[r].color;
        const cv::Vec3f corrected = m * cv::Vec3f(median[0], median[1], median[2]);
        regions[r].color = {corrected[0], corrected[1], corrected[2]};
    }
}

}  // namespace stria::pipeline
