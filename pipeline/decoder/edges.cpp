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

namespace {

// The three channels and a spare lane, for the per-edge arithmetic of eq. 4-6
// (GCC vector extensions: SSE2 on x86-64, NEON on aarch64), which the
// traversal repeats for every symbol it tests. Each lane does the scalar IEEE
// operation of the per-channel loop it replaces, so the results are the same
// floats (tests/decoder/test_kernels.cpp compares them with those loops);
// sums and maxima over the channels stay scalar, in channel order.
using Lanes = float __attribute__((vector_size(16)));
using LaneMask = std::int32_t __attribute__((vector_size(16)));

Lanes lanesOf(const std::array<float, 3>& c) { return Lanes{c[0], c[1], c[2], 0}; }
Lanes select(LaneMask mask, Lanes a, Lanes b) { return (Lanes)((mask & (LaneMask)a) | (~mask & (LaneMask)b)); }
Lanes absolute(Lanes v) { return (Lanes)((LaneMask)v & 0x7fffffff); }
float largestOfChannels(Lanes v) { return std::max({v[0], v[1], v[2]}); }
// std::min and std::max of two floats as vector selects: GCC compiles the
// scalar forms to branches, and whether symbolError clamps a common change
// is data.
float minOf(float a, float b) { return select(Lanes{b} < Lanes{a}, Lanes{b}, Lanes{a})[0]; }
float maxOf(float a, float b) { return select(Lanes{a} < Lanes{b}, Lanes{b}, Lanes{a})[0]; }

// Per symbol code, what symbolError needs of its channels.
struct SymbolTerms {
    Lanes sign;         // expected sign per channel
    LaneMask constant;  // the channels the symbol keeps constant
    // Per channel, all ones in the lane of its group: 0 falling, 1 constant, 2 rising.
    std::array<LaneMask, 3> group;
    float constantScale;              // 1 / count of the constant channels: 1 or 1/2 (1 if none)
    float fallingScale, risingScale;  // 1 / count of the group: 1 or 1/2 where both exist
    // How the common change is estimated: 1 for the way taken, 0 for the
    // other (multiplying selects without a branch: the symbol of one call
    // says nothing about the next one's).
    float viaConstant, viaMidpoint;
};

constexpr auto kSymbolTerms = [] {
    std::array<SymbolTerms, kSymbolCount> terms{};
    for (int s = 0; s < kSymbolCount; ++s) {
        const std::array<std::int8_t, 3>& sign = kSymbolSigns[s];
        int count[3] = {0, 0, 0};
        std::array<LaneMask, 3> group{};
        for (int c = 0; c < 3; ++c) {
            ++count[sign[c] + 1];
            group[c] = LaneMask{sign[c] < 0 ? -1 : 0, sign[c] == 0 ? -1 : 0, sign[c] > 0 ? -1 : 0, 0};
        }
        terms[s] = {Lanes{static_cast<float>(sign[0]), static_cast<float>(sign[1]), static_cast<float>(sign[2]), 0},
                    LaneMask{sign[0] == 0 ? -1 : 0, sign[1] == 0 ? -1 : 0, sign[2] == 0 ? -1 : 0, 0},
                    group,
                    count[1] == 2 ? 0.5f : 1.0f,
                    count[0] == 2 ? 0.5f : 1.0f,
                    count[2] == 2 ? 0.5f : 1.0f,
                    count[1] > 0 ? 1.0f : 0.0f,
                    count[1] == 0 && count[0] > 0 && count[2] > 0 ? 1.0f : 0.0f};
    }
    return terms;
}();

// Eq. 5-6 with the scales 1 / (1 - t) and 1 / t given.
float scaledMatchError(Lanes c, const SymbolTerms& terms, float onScale, float offScale)
{
    const Lanes e = select(terms.constant, absolute(c) * offScale, (1 - terms.sign * c) * onScale);
    const Lanes square = e * e;
    return std::sqrt(square[0] + square[1] + square[2]);
}

}  // namespace

EqualizedChange equalizedChange(const DecoderWorkspace& ws, int from, int to)
{
    const Lanes f = lanesOf(ws.regions[from].color), t = lanesOf(ws.regions[to].color);
    const Lanes raw = t - f;
    const Lanes half = 0.5f * (f + t);
    Lanes c = raw / select(half < kMinBrightness, Lanes{} + kMinBrightness, half);
    const float norm = largestOfChannels(absolute(c));
    if (norm > 0) c /= norm;
    return {{c[0], c[1], c[2]}, largestOfChannels(absolute(raw)), norm};
}

float matchError(const std::array<float, 3>& c, SymbolCode symbol, float t)
{
    const MatchScales scales(t);
    return scaledMatchError(lanesOf(c), kSymbolTerms[symbol], scales.on, scales.off);
}

float symbolError(const EqualizedChange& change, SymbolCode symbol, float t)
{
    return symbolError(change, symbol, MatchScales(t));
}

float symbolError(const EqualizedChange& change, SymbolCode symbol, const MatchScales& scales)
{
    const Lanes c = lanesOf(change.c);
    const SymbolTerms& terms = kSymbolTerms[symbol];
    // The common change, estimated from the channels the symbol keeps
    // constant, else as the midpoint of the rising and the falling ones; a
    // symbol that moves every channel the same way leaves none to estimate.
    // The group sums (one lane each) add +0 for the channels outside the
    // group, which leaves them unchanged; a count of 2 halves exactly, so it
    // multiplies (a count of 3 is the null symbol, which no stripe edge has).
    Lanes groups{};
    for (int ch = 0; ch < 3; ++ch) groups += select(terms.group[ch], Lanes{} + c[ch], Lanes{});
    const float falling = groups[0], constant = groups[1], rising = groups[2];
    const float viaMidpoint = 0.5f * (falling * terms.fallingScale + rising * terms.risingScale);
    const float viaConstant = symbol == kNullSymbol ? constant / 3 : constant * terms.constantScale;
    // x * 1 + y * 0 is x (up to the sign of a zero, which nothing below tells apart).
    float common = viaConstant * terms.viaConstant + viaMidpoint * terms.viaMidpoint;
    // Held within +-bound: std::clamp(common, -bound, bound) (bound >= 0).
    const float bound = change.relative > 0 ? minOf(kMaxCommonShare, kMaxAlbedoChange / change.relative) : 0.0f;
    common = maxOf(minOf(common, bound), -bound);
    // Without a common change c is matched as it is (subtracting a zero and
    // dividing by 1 leave it so, up to the sign of zeros, which the match
    // ignores); else the corrected change is normalised again.
    const Lanes corrected = c - common;
    const float norm = largestOfChannels(absolute(corrected));
    const float divisor = common != 0 && norm > 0 ? norm : 1.0f;
    return scaledMatchError(corrected / divisor, terms, scales.on, scales.off);
}

SymbolCode optimalSymbol(const std::array<float, 3>& c, float t)
{
    int s[3];
    for (int ch = 0; ch < 3; ++ch) s[ch] = (c[ch] >= t) - (c[ch] <= -t);  // no branch: the signs are data
    return makeSymbol(s[0], s[1], s[2]);
}

void computeEdgeFeatures(DecoderWorkspace& ws)
{
    // One pass over the edges (three passes streamed them three times); the
    // ranges are maxima, so the order in which the edges raise them does not
    // matter.
    Region* regions = ws.regions.get();
    const float t = static_cast<float>(ws.params.t);
    const MatchScales scales(t);
    for (int e = 0; e < ws.edgeCount; ++e) {
        const GraphEdge& edge = ws.edges[e];
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
        const auto direction = static_cast<EdgeDirection>(!parallel * (2 * (along > 0) - 1));
        for (int c = 0; c < 3; ++c) {
            const float change = std::abs(b.color[c] - a.color[c]);
            a.range[c] = std::max(a.range[c], change);
            b.range[c] = std::max(b.range[c], change);
        }
        const EqualizedChange change = equalizedChange(ws, edge.a, edge.b);
        EdgeFeature& feature = ws.edgeFeatures[e];
        feature.weight = change.weight;
        // Symbols and their errors are only tested across the stripes (the
        // traversal's seeds, paths and links; along them it tests null
        // edges).
        if (direction == EdgeDirection::Parallel) {
            feature.packed = EdgeFeature::pack(edge.a, edge.b, direction, kNullSymbol);
            feature.bestMatch = 0;
            feature.gradientError = 0;
            continue;
        }
        const SymbolCode bestSymbol = optimalSymbol(change.c, t);
        feature.packed = EdgeFeature::pack(edge.a, edge.b, direction, bestSymbol);
        feature.gradientError = edge.primaryGradient > 0
                                    ? std::min(edge.secondaryGradient / edge.primaryGradient, kMaxGradientError)
                                    : kMaxGradientError;
        feature.bestMatch = symbolError(change, bestSymbol, scales);
    }
}

}  // namespace stria::pipeline
