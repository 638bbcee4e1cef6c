// Stage 5: edge features (section 4.2 of the paper).
//
//   raw change  C^ = colour(b) - colour(a), weight w = |C^|_inf        (eq. 2-3)
//   range       per region and channel, the largest |C^| over its edges (eq. 1)
//   equalised   C = (C^ * Dinv) / |C^ * Dinv|_inf                        (eq. 4)
//   symbols     per channel -1/0/+1 by threshold t, match error         (eq. 5-7)
//   gradient    E_gradient = sum |d/ds I| / sum |d/dp I| on the border  (eq. 8)
//   error       E = E_match + alpha * E_gradient                         (eq. 9)
//   direction   forward / backward / parallel to the primary direction  (fig. 5)
//
// Dinv of an edge uses the mean of its two regions' ranges: the paper defines
// the range per region but applies it per edge; the mean is symmetric, so an
// edge gets the same symbol (reversed) from either side.
#include "pipeline/decoder/workspace.hpp"

#include <algorithm>
#include <cmath>

namespace stria::pipeline {
namespace {

// Channels that never change by more than this (in digits) carry no signal:
// their range is held at this floor so that noise is not blown up to +-1.
constexpr float kMinRange = 4.0f;
// Fig. 5: the border's chord must be within 45 degrees of the stripe edges'
// direction (normal within 45 degrees of the primary direction) to count as
// crossing the stripes.
constexpr float kCos45 = 0.70710678f;
constexpr float kMaxGradientError = 10.0f;

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
        const float range = std::max(0.5f * (f.range[c] + t.range[c]), kMinRange);
        out.c[c] = raw / range;
        norm = std::max(norm, std::abs(out.c[c]));
    }
    if (norm > 0)
        for (float& c : out.c) c /= norm;
    return out;
}

float matchError(const std::array<float, 3>& c, SymbolCode symbol, float t)
{
    float sum = 0;
    for (int ch = 0; ch < 3; ++ch) {
        const int s = symbolChannel(symbol, ch);
        const float e = s < 0 ? (1 + c[ch]) / (1 - t) : s > 0 ? (1 - c[ch]) / (1 - t) : std::abs(c[ch]) / t;
        sum += e * e;
    }
    return std::sqrt(sum);
}

SymbolCode optimalSymbol(const std::array<float, 3>& c, float t)
{
    int s[3];
    for (int ch = 0; ch < 3; ++ch) s[ch] = c[ch] <= -t ? -1 : c[ch] >= t ? 1 : 0;
    return makeSymbol(s[0], s[1], s[2]);
}

void computeEdgeFeatures(DecoderWorkspace& ws)
{
    Region* regions = ws.regions.get();
    for (int e = 0; e < ws.edgeCount; ++e) {
        GraphEdge& edge = ws.edges[e];
        // Direction: the border's normal (from a to b); if the border is
        // closed or ragged (its chord is short) the centroids decide instead.
        float nx = static_cast<float>(edge.normalX), ny = static_cast<float>(edge.normalY);
        if (std::hypot(nx, ny) < 0.25f * static_cast<float>(edge.borderCount)) {
            nx = regions[edge.b].centroidX - regions[edge.a].centroidX;
            ny = regions[edge.b].centroidY - regions[edge.a].centroidY;
        }
        const float length = std::hypot(nx, ny);
        const float along = length > 0 ? (nx * ws.primary[0] + ny * ws.primary[1]) / length : 0.0f;
        edge.direction = along >= kCos45    ? EdgeDirection::Forward
                         : along <= -kCos45 ? EdgeDirection::Backward
                                            : EdgeDirection::Parallel;
    }
    for (int e = 0; e < ws.edgeCount; ++e) {
        const GraphEdge& edge = ws.edges[e];
        for (int c = 0; c < 3; ++c) {
            const float change = std::abs(regions[edge.b].color[c] - regions[edge.a].color[c]);
            regions[edge.a].range[c] = std::max(regions[edge.a].range[c], change);
            regions[edge.b].range[c] = std::max(regions[edge.b].range[c], change);
        }
    }
    const float t = static_cast<float>(ws.params.t), alpha = static_cast<float>(ws.params.alpha);
    for (int e = 0; e < ws.edgeCount; ++e) {
        GraphEdge& edge = ws.edges[e];
        const EqualizedChange change = equalizedChange(ws, edge.a, edge.b);
        edge.weight = change.weight;
        edge.gradientError = edge.primaryGradient > 0
                                 ? std::min(edge.secondaryGradient / edge.primaryGradient, kMaxGradientError)
                                 : kMaxGradientError;
        edge.bestSymbol = optimalSymbol(change.c, t);
        edge.bestError = matchError(change.c, edge.bestSymbol, t) + alpha * edge.gradientError;
    }
}

}  // namespace stria::pipeline
