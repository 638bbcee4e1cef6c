// Stage 1: the colour gradient magnitude that the watershed floods.
//
// Per channel the Sobel differences |dx| + |dy| (halved, so a clean step of
// height h gives about h; the 1-2-1 smoothing across each difference cuts the
// noise to 61% and with it the number of noise basins), the maximum over the three channels, clamped to
// 8 bits. The maximum keeps a stripe edge that changes only one channel as
// strong as one that changes all three. Values at or below gradientFloor are
// flattened to 0 so that the noise inside a stripe does not split it into a
// basin per pixel (see docs/algorithm.md).
#include "pipeline/decoder/simd.hpp"
#include "pipeline/decoder/workspace.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>

namespace stria::pipeline {
namespace {

// The median of a histogram of `count` values, interpolated within its bin
// [m - 0.5, m + 0.5) by the share of the bin's values below the middle one.
double interpolatedMedian(const std::array<int, 256>& histogram, int count)
{
    int m = 0, below = 0;
    while (m < 255 && 2 * (below + histogram[m]) < count) below += histogram[m++];
    return m - 0.5 + (0.5 * count - below) / std::max(histogram[m], 1);
}

// The row-pair frame's floor (DecoderParams::segmentRowPairs): the larger of
// two, each round(factor x measure) - 1 on an interpolated median (the
// integer median's steps were too coarse at this scale):
// - the noise: the camera rows' pair differences (ws.pairNoise), which the
//   texture hardly reaches (one row apart); alone it let the coloured relief
//   at 780x580 split into 8 802 superpixels (7 023 on the camera's rows),
//   so the decode was hardly faster;
// - the along-stripe gradient median of the row-pair frame, which the
//   full-rate decode uses (times 1.1) and which flattens texture as well, but
//   which the doubled row step raises (4.6 where the camera rows had 3 on
//   the low-contrast photo, whose stripes it then merged).
// docs/algorithm.md, "Row pairs", has the measurements behind the factors.
int rowPairFloor(const std::array<int, 256>& pairNoise, const std::array<int, 256>& along, int pixels,
                 const DecoderParams& params)
{
    int samples = 0;
    for (const int c : pairNoise) samples += c;
    const double noise = interpolatedMedian(pairNoise, samples), gradient = interpolatedMedian(along, pixels);
    return std::max(static_cast<int>(std::lround(params.rowPairNoiseFloorFactor * noise)),
                    static_cast<int>(std::lround(params.rowPairAlongFloorFactor * gradient))) -
           1;
}

}  // namespace

// (x86-64: clones for AVX2 and AVX-512 too, STRIA_X86_CLONES: the floor's
// select below in 32 or 64 bytes per step.)
STRIA_X86_CLONES void computeGradient(DecoderWorkspace& ws)
{
    const int w = ws.width, h = ws.height;
    // Along the stripes: image y when the primary direction is closer to x.
    const bool alongY = std::abs(ws.primary[0]) >= std::abs(ws.primary[1]);
    // The kernel's int16 lanes in the scratch, which the watershed fills later.
    auto* lanes = reinterpret_cast<std::int16_t*>(ws.scratch.get());
    AlongCounts alongCounts{};
    for (int y = 0; y < h; ++y)
        gradientRow(ws.frame.row(std::max(y - 1, 0)), ws.frame.row(y), ws.frame.row(std::min(y + 1, h - 1)), w, alongY,
                    ws.gradient.get() + static_cast<std::ptrdiff_t>(y) * w, alongCounts, lanes);
    std::array<int, 256> along;
    for (int l = 0; l < 256; ++l) along[l] = alongCounts[0][l] + alongCounts[1][l] + alongCounts[2][l] + alongCounts[3][l];

    const int n = w * h;
    int median = 0;
    for (int seen = along[0]; 2 * seen < n; seen += along[++median]) {
    }
    int floor = static_cast<int>(std::lround(ws.params.noiseFloorFactor * median)) - 1;
    if (ws.params.segmentRowPairs) floor = rowPairFloor(ws.pairNoise, along, n, ws.params);
    floor = std::max(ws.params.gradientFloor, floor);
    // A select on bytes rather than a branch: the compiler vectorises it.
    const std::uint8_t byteFloor = static_cast<std::uint8_t>(std::clamp(floor, 0, 255));
    std::uint8_t* g = ws.gradient.get();
    for (int p = 0; p < n; ++p) g[p] = g[p] > byteFloor ? g[p] : 0;
}

}  // namespace stria::pipeline
