// Stage 5: edge features (section 4.2 of the paper).
//
//   raw change  C^ = colour(b) - colour(a), weight w = |C^|_inf        (eq. 2-3)
//   range       per region and channel, the largest |C^| over its edges (eq. 1)
//   equalised   C = (C^ * Dinv) / |C^ * Dinv|_inf                        (eq. 4)
//               Dinv per channel = 1 / the two regions' mean brightness
//   symbols     per channel -1/0/+1 by threshold t, match error         (eq. 5-7)
//               after removing a texture's common change (symbolError)
//   gradient    E_gradient = sum |d/ds I| / sum |d/dp I| on the border  (eq. 8)
//   error       E = E_match + alpha * E_gradient                         (eq. 9)
//   direction   forward / backward / parallel to the primary direction  (fig. 5)
//
// Dinv departs from the paper's range (eq. 1, still computed: the depth and
// traversal stages use it): the light a surface returns is its albedo times
// the illumination, so a stripe edge changes a channel by a fixed fraction of
// that channel's brightness whatever the texture, while a region's range is
// inflated by any strong texture edge around it, which pushes its stripe
// edges below t (photo albedo at contrast 0.3: inliers 33% -> 42%). The mean
// of the two regions is symmetric, so an edge gets the same symbol (reversed)
// from either side.
#include "pipeline/decoder/workspace.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

namespace stria::pipeline {
namespace {

// Below this brightness (digits) a channel's relative change is mostly noise:
// the divisor is held at this floor so that noise in dark channels is not
// blown up to +-1 (8, 12, 40 measured: fewer inliers on the relief scenes).
constexpr float kMinBrightness = 20.0f;
constexpr float kMaxGradientError = 10.0f;
// A texture edge changes all channels of the returned light by the same
// factor: in the equalised change it adds a common offset to the stripe
// symbol, which symbolError removes before matching, up to this share of the
// largest channel change (at half, symbols become ambiguous: R+ = G-B- + a
// common rise) and up to this change of the brightness (the albedo step
// between neighbouring superpixels a texture plausibly makes; at full contrast
// the stripe step is large and little slack is given). Photo texture at
// contrast 0.3: inliers 42% -> 86% (docs/algorithm.md, section 5).
constexpr float kMaxCommonShare = 0.3f;
constexpr float kMaxAlbedoChange = 0.15f;

}  // namespace

EqualizedChange equalizedChange(const DecoderWorkspace& ws, int from, int to)
{
    const Region& f = ws.regions[from];
    const Region& t = ws.regions[to];
    EqualizedChange out;
    float norm = 0;
    for (int c = 0; c < 3; ++c) {
        const float raw = t.color[c] - f.color[c];
        out.weight = std::max(out.weight, std::abs(raw));
        out.c[c] = raw / std::max(0.5f * (f.color[c] + t.color[c]), kMinBrightness);
        norm = std::max(norm, std::abs(out.c[c]));
    }
    out.relative = norm;
    if (norm > 0)
        for (float& c : out.c) c /= norm;
    return out;
}

float matchError(const std::array<float, 3>& c, SymbolCode symbol, float t)
{
    const std::array<std::int8_t, 3>& signs = kSymbolSigns[symbol];
    const float onScale = 1 / (1 - t), offScale = 1 / t;
    float sum = 0;
    for (int ch = 0; ch < 3; ++ch) {
        const float e = signs[ch] == 0 ? std::abs(c[ch]) * offScale : (1 - signs[ch] * c[ch]) * onScale;
        sum += e * e;
    }
    return std::sqrt(sum);
}

float symbolError(const EqualizedChange& change, SymbolCode symbol, float t)
{
    const std::array<float, 3>& c = change.c;
    // The common change, estimated from the channels the symbol keeps
    // constant, else as the midpoint of the rising and the falling ones; a
    // symbol that moves every channel the same way leaves none to estimate.
    const std::array<std::int8_t, 3>& signs = kSymbolSigns[symbol];
    float sum[3] = {0, 0, 0};  // channels expected falling, constant, rising
    int count[3] = {0, 0, 0};
    for (int ch = 0; ch < 3; ++ch) {
        sum[signs[ch] + 1] += c[ch];
        ++count[signs[ch] + 1];
    }
    float common = 0;
    if (count[1] > 0) common = sum[1] / static_cast<float>(count[1]);
    else if (count[0] > 0 && count[2] > 0)
        common = 0.5f * (sum[0] / static_cast<float>(count[0]) + sum[2] / static_cast<float>(count[2]));
    const float bound =
        change.relative > 0 ? std::min(kMaxCommonShare, kMaxAlbedoChange / change.relative) : 0.0f;
    common = std::clamp(common, -bound, bound);
    if (common == 0) return matchError(c, symbol, t);
    std::array<float, 3> corrected{c[0] - common, c[1] - common, c[2] - common};
    const float norm = std::max({std::abs(corrected[0]), std::abs(corrected[1]), std::abs(corrected[2])});
    if (norm > 0)
        for (float& v : corrected) v /= norm;
    return matchError(corrected, symbol, t);
}

SymbolCode optimalSymbol(const std::array<float, 3>& c, float t)
{
    int s[3];
    for (int ch = 0; ch < 3; ++ch) s[ch] = (c[ch] >= t) - (c[ch] <= -t);  // no branch: the signs are data
    return makeSymbol(s[0], s[1], s[2]);
}

void computeEdgeFeatures(DecoderWorkspace& ws)
{
    // One pass over the edges (they are ~1 MB at 780x580: three passes
    // streamed them three times); the ranges are maxima, so the order in
    // which the edges raise them does not matter.
    Region* regions = ws.regions.get();
    const float t = static_cast<float>(ws.params.t), alpha = static_cast<float>(ws.params.alpha);
    for (int e = 0; e < ws.edgeCount; ++e) {
        GraphEdge& edge = ws.edges[e];
        Region& a = regions[edge.a];
        Region& b = regions[edge.b];
        // Direction (fig. 5): the border's normal (from a to b); if the
        // border is closed or ragged (its chord is short) the centroids decide
        // instead. Across the stripes if it is within 45 degrees of the
        // primary direction (the border within 45 degrees of the stripes).
        float nx = static_cast<float>(edge.normalX), ny = static_cast<float>(edge.normalY);
        const float count = static_cast<float>(edge.borderCount);
        if (nx * nx + ny * ny < 0.0625f * count * count) {  // chord < border length / 4
            nx = b.centroidX - a.centroidX;
            ny = b.centroidY - a.centroidY;
        }
        // Within 45 degrees of the primary direction: |along| / length >= cos 45.
        const float length2 = nx * nx + ny * ny;
        const float along = nx * ws.primary[0] + ny * ws.primary[1];
        // Arithmetic, not branches: the direction of one edge says nothing
        // about the next one's.
        const bool parallel = length2 == 0 || 2 * along * along < length2;
        edge.direction = static_cast<EdgeDirection>(!parallel * (2 * (along > 0) - 1));
        for (int c = 0; c < 3; ++c) {
            const float change = std::abs(b.color[c] - a.color[c]);
            a.range[c] = std::max(a.range[c], change);
            b.range[c] = std::max(b.range[c], change);
        }
        const EqualizedChange change = equalizedChange(ws, edge.a, edge.b);
        edge.weight = change.weight;
        // Symbols and their errors are only tested across the stripes (the
        // traversal's seeds, paths and links; along them it tests null
        // edges): an edge along them keeps the defaults.
        if (edge.direction == EdgeDirection::Parallel) continue;
        edge.gradientError = edge.primaryGradient > 0
                                 ? std::min(edge.secondaryGradient / edge.primaryGradient, kMaxGradientError)
                                 : kMaxGradientError;
        edge.bestSymbol = optimalSymbol(change.c, t);
        edge.bestMatch = symbolError(change, edge.bestSymbol, t);
        edge.bestError = edge.bestMatch + alpha * edge.gradientError;
    }
}

}  // namespace stria::pipeline
