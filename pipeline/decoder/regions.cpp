// Stage 3: superpixel colours and centroids.
//
// The colour of a superpixel is the per-channel median of its pixels
// (marginal ordering, a rank filter robust to noise and to the blurred pixels
// at its border), then corrected for camera crosstalk. Pixels are grouped by
// label with a counting sort into pixelOrder (reusing the watershed's order
// buffer); each channel's median is found by selection (nth_element) on a
// byte copy in the scratch buffer, which is linear and allocation-free.
#include "pipeline/decoder/workspace.hpp"

#include <algorithm>

namespace stria::pipeline {

void computeRegions(DecoderWorkspace& ws)
{
    const int w = ws.width, n = ws.width * ws.height, count = ws.regionCount;
    const std::int32_t* label = ws.labels.get();
    Region* regions = ws.regions.get();
    for (int r = 0; r < count; ++r) regions[r] = Region{};

    for (int p = 0; p < n; ++p) ++regions[label[p]].pixelCount;
    // Counting sort by label; adjacencyBegin serves as the fill cursor (the
    // graph stage sets it properly later).
    std::int32_t offset = 0;
    for (int r = 0; r < count; ++r) {
        regions[r].adjacencyBegin = offset;
        offset += regions[r].pixelCount;
    }
    std::int32_t* order = ws.pixelOrder;
    for (int p = 0; p < n; ++p) order[regions[label[p]].adjacencyBegin++] = p;

    auto* bytes = reinterpret_cast<std::uint8_t*>(ws.scratch.get());
    const cv::Matx33f& m = ws.colorCorrection;
    const std::int32_t* pixels = order;
    for (int r = 0; r < count; ++r) {
        Region& region = regions[r];
        const int size = region.pixelCount;
        // One pass over the pixels: coordinate sums and the three channels
        // copied to consecutive runs of the scratch (3 x size <= 4 x pixels).
        long long sx = 0, sy = 0;
        std::uint8_t* channel[3] = {bytes, bytes + size, bytes + 2 * size};
        for (int i = 0; i < size; ++i) {
            const int y = pixels[i] / w, x = pixels[i] - y * w;
            sx += x;
            sy += y;
            const std::uint8_t* px = ws.frame.row(y) + 3 * x;
            for (int c = 0; c < 3; ++c) channel[c][i] = px[ws.rgbOffset[c]];
        }
        region.centroidX = static_cast<float>(static_cast<double>(sx) / size);
        region.centroidY = static_cast<float>(static_cast<double>(sy) / size);
        cv::Vec3f median;
        for (int c = 0; c < 3; ++c) {
            std::nth_element(channel[c], channel[c] + size / 2, channel[c] + size);
            median[c] = channel[c][size / 2];
        }
        const cv::Vec3f corrected = m * median;
        region.color = {corrected[0], corrected[1], corrected[2]};
        region.adjacencyBegin = 0;
        pixels += size;
    }
}

}  // namespace stria::pipeline
