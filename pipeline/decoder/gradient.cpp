// Stage 1: the colour gradient magnitude that the watershed floods.
//
// Per channel the Sobel differences |dx| + |dy| (halved, so a clean step of
// height h gives about h; the 1-2-1 smoothing across each difference cuts the
// noise to 61% and with it the number of noise basins), the maximum over the three channels, clamped to
// 8 bits. The maximum keeps a stripe edge that changes only one channel as
// strong as one that changes all three. Values at or below gradientFloor are
// flattened to 0 so that the noise inside a stripe does not split it into a
// basin per pixel (see docs/algorithm.md).
#include "pipeline/decoder/workspace.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>

namespace stria::pipeline {

void computeGradient(DecoderWorkspace& ws)
{
    const int w = ws.width, h = ws.height;
    // Along the stripes: image y when the primary direction is closer to x.
    const bool alongY = std::abs(ws.primary[0]) >= std::abs(ws.primary[1]);
    std::array<int, 256> along{};
    for (int y = 0; y < h; ++y) {
        const std::uint8_t* up = ws.frame.row(std::max(y - 1, 0));
        const std::uint8_t* row = ws.frame.row(y);
        const std::uint8_t* down = ws.frame.row(std::min(y + 1, h - 1));
        std::uint8_t* out = ws.gradient.get() + static_cast<std::ptrdiff_t>(y) * w;
        for (int x = 0; x < w; ++x) {
            const int left = 3 * std::max(x - 1, 0), right = 3 * std::min(x + 1, w - 1), here = 3 * x;
            int best = 0, bestAlong = 0;
            for (int c = 0; c < 3; ++c) {
                // Sobel: central differences smoothed 1-2-1 across, /4.
                const int gx = std::abs(up[right + c] - up[left + c] + 2 * (row[right + c] - row[left + c]) +
                                        down[right + c] - down[left + c]) / 4;
                const int gy = std::abs(down[left + c] - up[left + c] + 2 * (down[here + c] - up[here + c]) +
                                        down[right + c] - up[right + c]) / 4;
                best = std::max(best, gx + gy);
                bestAlong = std::max(bestAlong, alongY ? gy : gx);
            }
            ++along[std::min(bestAlong, 255)];
            out[x] = static_cast<std::uint8_t>(std::min((best + 1) / 2, 255));
        }
    }

    const int n = w * h;
    int median = 0;
    for (int seen = along[0]; 2 * seen < n; seen += along[++median]) {
    }
    const int floor = std::max(ws.params.gradientFloor,
                               static_cast<int>(std::lround(ws.params.noiseFloorFactor * median)) - 1);
    for (int p = 0; p < n; ++p)
        if (ws.gradient[p] <= floor) ws.gradient[p] = 0;
}

}  // namespace stria::pipeline
