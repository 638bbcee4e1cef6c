// Stage 1: the colour gradient magnitude that the watershed floods.
//
// Per channel the central differences |dx| + |dy| (halved, so a clean step of
// height h gives about h), the maximum over the three channels, clamped to
// 8 bits. The maximum keeps a stripe edge that changes only one channel as
// strong as one that changes all three. Values at or below gradientFloor are
// flattened to 0 so that the noise inside a stripe does not split it into a
// basin per pixel (see docs/algorithm.md).
#include "pipeline/decoder/workspace.hpp"

#include <algorithm>
#include <cstdlib>

namespace stria::pipeline {

void computeGradient(DecoderWorkspace& ws)
{
    const int w = ws.width, h = ws.height;
    const int floor = ws.params.gradientFloor;
    for (int y = 0; y < h; ++y) {
        const std::uint8_t* up = ws.frame.row(std::max(y - 1, 0));
        const std::uint8_t* row = ws.frame.row(y);
        const std::uint8_t* down = ws.frame.row(std::min(y + 1, h - 1));
        std::uint8_t* out = ws.gradient.get() + static_cast<std::ptrdiff_t>(y) * w;
        for (int x = 0; x < w; ++x) {
            const int left = 3 * std::max(x - 1, 0), right = 3 * std::min(x + 1, w - 1), here = 3 * x;
            int best = 0;
            for (int c = 0; c < 3; ++c) {
                const int g = std::abs(row[right + c] - row[left + c]) + std::abs(down[here + c] - up[here + c]);
                best = std::max(best, g);
            }
            best = (best + 1) / 2;
            out[x] = static_cast<std::uint8_t>(best <= floor ? 0 : std::min(best, 255));
        }
    }
}

}  // namespace stria::pipeline
