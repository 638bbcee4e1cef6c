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
#include <bit>
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

namespace {

// `a` where `mask` is all ones, `b` where it is zero. symbolError selects
// with it rather than branching: the symbol of one call says nothing about
// the next one's, and with bools from a table GCC emits a branch per
// channel (callgrind's branch model: 40 000 mispredictions per 780x580
// decode in the branching form).
float pick(std::uint32_t mask, float a, float b)
{
    return std::bit_cast<float>((std::bit_cast<std::uint32_t>(a) & mask) | (std::bit_cast<std::uint32_t>(b) & ~mask));
}

std::uint32_t maskOf(bool condition) { return 0u - static_cast<std::uint32_t>(condition); }

// Per symbol code, what symbolError needs of its channels, as floats and masks.
struct SymbolTerms {
    std::array<float, 3> sign;  // expected sign per channel
    std::array<std::uint32_t, 3> falling, constant, rising;  // the channel's group
    float constantScale;        // 1 / count of the constant channels: 1 or 1/2 (1 if none)
    float fallingScale, risingScale;  // 1 / count of the group: 1 or 1/2 where both exist
    std::uint32_t viaConstant, viaMidpoint;  // how the common change is estimated
};

constexpr auto kSymbolTerms = [] {
    std::array<SymbolTerms, kSymbolCount> terms{};
    for (int s = 0; s < kSymbolCount; ++s) {
        SymbolTerms& st = terms[s];
        int count[3] = {0, 0, 0};
        for (int c = 0; c < 3; ++c) {
            const int sign = kSymbolSigns[s][c];
            st.sign[c] = static_cast<float>(sign);
            st.falling[c] = sign < 0 ? ~0u : 0u;
            st.constant[c] = sign == 0 ? ~0u : 0u;
            st.rising[c] = sign > 0 ? ~0u : 0u;
            ++count[sign + 1];
        }
        st.constantScale = count[1] == 2 ? 0.5f : 1.0f;
        st.fallingScale = count[0] == 2 ? 0.5f : 1.0f;
        st.risingScale = count[2] == 2 ? 0.5f : 1.0f;
        st.viaConstant = count[1] > 0 ? ~0u : 0u;
        st.viaMidpoint = count[1] == 0 && count[0] > 0 && count[2] > 0 ? ~0u : 0u;
    }
    return terms;
}();

// matchError with the scales 1 / (1 - t) and 1 / t given.
float scaledMatchError(const std::array<float, 3>& c, const SymbolTerms& terms, float onScale, float offScale)
{
    float sum = 0;
    for (int ch = 0; ch < 3; ++ch) {
        const float e = pick(terms.constant[ch], std::abs(c[ch]) * offScale, (1 - terms.sign[ch] * c[ch]) * onScale);
        sum += e * e;
    }
    return std::sqrt(sum);
}

}  // namespace

float matchError(const std::array<float, 3>& c, SymbolCode symbol, float t)
{
    return scaledMatchError(c, kSymbolTerms[symbol], 1 / (1 - t), 1 / t);
}

float symbolError(const EqualizedChange& change, SymbolCode symbol, float t)
{
    const std::array<float, 3>& c = change.c;
    const SymbolTerms& terms = kSymbolTerms[symbol];
    // The common change, estimated from the channels the symbol keeps
    // constant, else as the midpoint of the rising and the falling ones; a
    // symbol that moves every channel the same way leaves none to estimate.
    // The sums add +0 for the channels outside a group, which leaves them
    // unchanged; a count of 2 halves exactly, so it multiplies (a count of
    // 3 is the null symbol, which no stripe edge has).
    float falling = 0, constant = 0, rising = 0;
    for (int ch = 0; ch < 3; ++ch) {
        falling += pick(terms.falling[ch], c[ch], 0.0f);
        constant += pick(terms.constant[ch], c[ch], 0.0f);
        rising += pick(terms.rising[ch], c[ch], 0.0f);
    }
    const float viaMidpoint = 0.5f * (falling * terms.fallingScale + rising * terms.risingScale);
    const float viaConstant = symbol == kNullSymbol ? constant / 3 : constant * terms.constantScale;
    float common = pick(terms.viaConstant, viaConstant, pick(terms.viaMidpoint, viaMidpoint, 0.0f));
    // Held within +-bound (std::min and std::clamp's order of comparisons).
    const float share = kMaxAlbedoChange / change.relative;
    const float bound = pick(maskOf(change.relative > 0), pick(maskOf(share < kMaxCommonShare), share, kMaxCommonShare), 0.0f);
    common = pick(maskOf(common < -bound), -bound, pick(maskOf(bound < common), bound, common));
    // Without a common change c is matched as it is (subtracting a zero and
    // dividing by 1 leave it so, up to the sign of zeros, which the match
    // ignores); else the corrected change is normalised again.
    std::array<float, 3> corrected{c[0] - common, c[1] - common, c[2] - common};
    const float norm = std::max({std::abs(corrected[0]), std::abs(corrected[1]), std::abs(corrected[2])});
    const float divisor = pick(maskOf(common != 0) & maskOf(norm > 0), norm, 1.0f);
    for (float& v : corrected) v /= divisor;
    return scaledMatchError(corrected, terms, 1 / (1 - t), 1 / t);
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
        feature.bestMatch = symbolError(change, bestSymbol, t);
    }
}

}  // namespace stria::pipeline
