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
    // Row pairs (DecoderParams::segmentRowPairs): ws.frame is the camera
    // frame averaged in pairs of rows (2y and 2y + 1, rounding up; an odd
    // last row alone), written here one pair row ahead of the row whose
    // gradient reads it, so that it is read from the cache (1388x1038, 2.2
    // MB). GCC vectorises the average (pavgb, vpavgb, urhadd).
    const bool pairs = ws.params.segmentRowPairs;
    const FrameView& camera = ws.cameraFrame;
    const int bytes = 3 * w;
    auto averagePair = [&](int y) {
        const std::uint8_t* a = camera.row(2 * y);
        const std::uint8_t* b = camera.row(std::min(2 * y + 1, camera.height - 1));
        std::uint8_t* out = ws.pairPixels + static_cast<std::ptrdiff_t>(y) * bytes;
        for (int i = 0; i < bytes; ++i) out[i] = static_cast<std::uint8_t>((unsigned{a[i]} + unsigned{b[i]} + 1) >> 1);
    };
    if (pairs) averagePair(0);
    for (int y = 0; y < h; ++y) {
        if (pairs && y + 1 < h) averagePair(y + 1);
        gradientRow(ws.frame.row(std::max(y - 1, 0)), ws.frame.row(y), ws.frame.row(std::min(y + 1, h - 1)), w, alongY,
                    ws.gradient.get() + static_cast<std::ptrdiff_t>(y) * w, alongCounts, lanes);
    }
    // Row pairs (DecoderParams::segmentRowPairs): the floor the camera's
    // rows would have, from their along-stripe gradient on every
    // kFloorRowStep-th camera row (the rows' magnitudes into the gradient
    // buffer past the pair rows, then ignored). The row-pair frame's own
    // median is no noise measure: its along-stripe step spans 4 camera
    // rows, so texture and shading raise it (relief 5.7 -> 7.5, tube 6.4 ->
    // 12.6) while the averaging lowers the noise (docs/algorithm.md, "Row pairs").
    int samples = w * h;
    if (pairs) {
        alongCounts = {};
        samples = 0;
        for (int y = 1; y + 1 < camera.height; y += kFloorRowStep, samples += w)
            gradientRow(camera.row(y - 1), camera.row(y), camera.row(y + 1), w, alongY,
                        ws.gradient.get() + static_cast<std::ptrdiff_t>(h) * w, alongCounts, lanes);
    }
    std::array<int, 256> along;
    for (int l = 0; l < 256; ++l) along[l] = alongCounts[0][l] + alongCounts[1][l] + alongCounts[2][l] + alongCounts[3][l];

    int median = 0;
    for (int seen = along[0]; 2 * seen < samples; seen += along[++median]) {
    }
    const int floor = std::max(ws.params.gradientFloor,
                               static_cast<int>(std::lround(ws.params.noiseFloorFactor * median)) - 1);
    // A select on bytes rather than a branch: the compiler vectorises it.
    const std::uint8_t byteFloor = static_cast<std::uint8_t>(std::clamp(floor, 0, 255));
    const int n = w * h;
    std::uint8_t* g = ws.gradient.get();
    for (int p = 0; p < n; ++p) g[p] = g[p] > byteFloor ? g[p] : 0;
}

}  // namespace stria::pipeline
