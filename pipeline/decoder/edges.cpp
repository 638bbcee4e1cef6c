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
#include "pipeline/decoder/simd.hpp"
#include "pipeline/decoder/symbol_error.hpp"
#include "pipeline/decoder/workspace.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>

#if defined(__SSE2__)
#include <emmintrin.h>
#elif defined(__aarch64__)
#include <arm_neon.h>
#endif

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
// sums over the channels keep the loops' order (maxima of non-NaN floats
// are the same in any order).
// (The lane helpers shared with the traversal's symbol tests come from
// symbol_error.hpp.)
using symbol_error::Lanes;
using symbol_error::LaneMask;
using symbol_error::absolute;
using symbol_error::lanesOf;
using symbol_error::squareRoot;

Lanes lanesOf(const std::array<float, 3>& c) { return Lanes{c[0], c[1], c[2], 0}; }
LaneMask select(LaneMask mask, LaneMask a, LaneMask b) { return (mask & a) | (~mask & b); }
Lanes select(LaneMask mask, Lanes a, Lanes b) { return (Lanes)select(mask, (LaneMask)a, (LaneMask)b); }
float largestOfChannels(Lanes v) { return std::max({v[0], v[1], v[2]}); }
// a < b ? a : b and a > b ? a : b per lane, which GCC compiles to SSE2's
// minps and maxps (3 instructions fewer than a select by masks).
Lanes lesserOf(Lanes a, Lanes b) { return a < b ? a : b; }
Lanes greaterOf(Lanes a, Lanes b) { return a > b ? a : b; }
using symbol_error::maximumOf;
using symbol_error::minimumOf;
// x where mask, else +0: one and, where a select takes three.
Lanes where(LaneMask mask, Lanes x) { return (Lanes)(mask & (LaneMask)x); }

// Per symbol code, what matchError needs of its channels.
struct SymbolTerms {
    Lanes sign;         // expected sign per channel
    LaneMask constant;  // the channels the symbol keeps constant
};

constexpr auto kSymbolTerms = [] {
    std::array<SymbolTerms, kSymbolCount> terms{};
    for (int s = 0; s < kSymbolCount; ++s) {
        const std::array<std::int8_t, 3>& sign = kSymbolSigns[s];
        terms[s] = {Lanes{static_cast<float>(sign[0]), static_cast<float>(sign[1]), static_cast<float>(sign[2]), 0},
                    LaneMask{sign[0] == 0 ? -1 : 0, sign[1] == 0 ? -1 : 0, sign[2] == 0 ? -1 : 0, 0}};
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

namespace {

// Eq. 4 in lanes: c (lane 3 finite and meaningless), its weight and relative.
struct ChangeLanes {
    Lanes c;
    float weight, relative;
};

[[gnu::always_inline]] inline ChangeLanes equalizedLanes(const DecoderWorkspace& ws, int from, int to)
{
    // The colours by 16-byte loads: the fourth lane is range[0], finite,
    // computed on and ignored.
    static_assert(offsetof(Region, range) == sizeof(Region::color));
    Lanes f, t;
    std::memcpy(&f, ws.regions[from].color.data(), sizeof f);
    std::memcpy(&t, ws.regions[to].color.data(), sizeof t);
    const Lanes raw = t - f;
    const Lanes half = 0.5f * (f + t);
    Lanes c = raw / select(half < kMinBrightness, lanesOf(kMinBrightness), half);
    const float norm = largestOfChannels(absolute(c));
    if (norm > 0) c /= norm;
    return {c, largestOfChannels(absolute(raw)), norm};
}

}  // namespace

EqualizedChange equalizedChange(const DecoderWorkspace& ws, int from, int to)
{
    const ChangeLanes change = equalizedLanes(ws, from, to);
    return {{change.c[0], change.c[1], change.c[2]}, change.weight, change.relative};
}

ExpectedSymbolMatch expectedSymbolMatch(const DecoderWorkspace& ws, int from, int to, SymbolCode symbol, float t,
                                        const MatchScales& scales)
{
    const ChangeLanes change = equalizedLanes(ws, from, to);
    const SymbolTerms& terms = kSymbolTerms[symbol];
    // optimalSymbol's signs, (c >= t) - (c <= -t), against the symbol's.
    const LaneMask sign = (change.c <= -t) - (change.c >= t);
    const LaneMask same = __builtin_convertvector(sign, Lanes) == terms.sign;
#if defined(__SSE2__)
    const bool fits = (_mm_movemask_ps((__m128)same) & 7) == 7;
#else
    const bool fits = (same[0] & same[1] & same[2]) != 0;
#endif
    // matchError's arithmetic, its scales those of MatchScales.
    return {fits, fits ? scaledMatchError(change.c, terms, scales.on, scales.off) : 0.0f, change.weight};
}

float matchError(const std::array<float, 3>& c, SymbolCode symbol, float t)
{
    return scaledMatchError(lanesOf(c), kSymbolTerms[symbol], 1 / (1 - t), 1 / t);  // MatchScales(t)'s
}

float symbolError(const EqualizedChange& change, SymbolCode symbol, float t)
{
    return symbolError(change, symbol, MatchScales(t));
}

namespace {

// The largest common change symbolError removes, from the change's relative
// (eq. 4): std::min(kMaxCommonShare, share) where relative > 0, else 0.
[[gnu::always_inline]] inline Lanes commonBound(Lanes relative)
{
    return where(relative > 0, minimumOf(kMaxAlbedoChange / relative, lanesOf(kMaxCommonShare)));
}

}  // namespace

float symbolError(const EqualizedChange& change, SymbolCode symbol, const MatchScales& scales)
{
    static_assert(offsetof(EqualizedChange, c) == 0 && sizeof(EqualizedChange) >= sizeof(Lanes));
    Lanes c;  // lane 3: weight
    std::memcpy(&c, change.c.data(), sizeof c);
    return symbol_error::symbolErrorLanes(change.c.data(), c, commonBound(lanesOf(change.relative)), symbol, scales);
}

SymbolCode optimalSymbol(const std::array<float, 3>& c, float t)
{
    int s[3];
    for (int ch = 0; ch < 3; ++ch) s[ch] = (c[ch] >= t) - (c[ch] <= -t);  // no branch: the signs are data
    return makeSymbol(s[0], s[1], s[2]);
}

namespace {

// The edge stage's lanes: 4 edges at once, one per lane, each channel in a
// vector of its own. Per lane these are the operations of equalizedChange,
// optimalSymbol, symbolError and the direction test above, in their order, so
// they give the same floats (tests/decoder/test_kernels.cpp compares the stage
// with those functions edge by edge); but the chains of divisions and the
// square root of 4 edges run together, where one edge's chain kept the core
// waiting, and the maxima over the channels are maxima of vectors.
constexpr int kBlock = 4;

Lanes floatsOf(LaneMask v) { return __builtin_convertvector(v, Lanes); }
// std::max({x, y, z}) per lane: the first of the largest.
Lanes largestOf(Lanes x, Lanes y, Lanes z) { return greaterOf(z, greaterOf(y, x)); }

struct SymbolLanes {
    Lanes weight;       // eq. 3
    LaneMask symbol;    // optimalSymbol
    Lanes bestMatch;    // its symbolError
    Lanes rawChange[3]; // |to - from| per channel (eq. 1)
    Lanes change[3];    // equalizedChange's c
    Lanes commonBound;  // and the bound of its common change (EdgeChange)
};

// Eq. 3-7 from colour from to colour to (R G B lanes).
[[gnu::always_inline]] inline SymbolLanes bestSymbolLanes(const Lanes from[3], const Lanes to[3], float t, const MatchScales& scales)
{
    SymbolLanes out;
    Lanes raw[3], c[3];
    for (int ch = 0; ch < 3; ++ch) {
        raw[ch] = to[ch] - from[ch];
        const Lanes half = 0.5f * (from[ch] + to[ch]);
        c[ch] = raw[ch] / select(half < kMinBrightness, lanesOf(kMinBrightness), half);
        out.rawChange[ch] = absolute(raw[ch]);
    }
    out.weight = largestOf(out.rawChange[0], out.rawChange[1], out.rawChange[2]);
    const Lanes relative = largestOf(absolute(c[0]), absolute(c[1]), absolute(c[2]));
    for (Lanes& v : c) v = select(relative > 0, v / relative, v);
    for (int ch = 0; ch < 3; ++ch) out.change[ch] = c[ch];
    // The optimal symbol's signs, (c >= t) - (c <= -t), and the channels
    // falling, constant and rising from those masks (-1 where true).
    LaneMask sign[3], count[3] = {};  // count: falling, constant, rising
    Lanes group[3] = {};              // the channel sums of each group
    for (int ch = 0; ch < 3; ++ch) {
        const LaneMask falling = c[ch] <= -t, rising = c[ch] >= t;
        sign[ch] = falling - rising;
        const LaneMask member[3] = {falling, ~(falling | rising), rising};
        for (int g = 0; g < 3; ++g) {
            group[g] += where(member[g], c[ch]);
            count[g] -= member[g];
        }
    }
    out.symbol = kNullSymbol + 9 * sign[0] + 3 * sign[1] + sign[2];  // makeSymbol
    // symbolError of that symbol: its common change from the counts.
    auto scaleOf = [](LaneMask n) { return 1.0f - where(n == 2, lanesOf(0.5f)); };  // exact: 1 or 0.5
    auto flag = [](LaneMask m) { return where(m, lanesOf(1.0f)); };
    const Lanes viaMidpoint = 0.5f * (group[0] * scaleOf(count[0]) + group[2] * scaleOf(count[2]));
    const Lanes viaConstant = select(count[1] == 3, group[1] / 3.0f, group[1] * scaleOf(count[1]));
    Lanes common = viaConstant * flag(count[1] > 0) + viaMidpoint * flag((count[1] == 0) & (count[0] > 0) & (count[2] > 0));
    // std::min(kMaxCommonShare, share) where relative > 0, then the clamp,
    // in symbolError's operand order.
    const Lanes bound = commonBound(relative);
    out.commonBound = bound;
    common = greaterOf(-bound, lesserOf(bound, common));
    Lanes corrected[3];
    for (int ch = 0; ch < 3; ++ch) corrected[ch] = c[ch] - common;
    const Lanes norm = largestOf(absolute(corrected[0]), absolute(corrected[1]), absolute(corrected[2]));
    const Lanes divisor = select((common != 0) & (norm > 0), norm, lanesOf(1.0f));
    Lanes sum{};
    for (int ch = 0; ch < 3; ++ch) {
        const Lanes x = corrected[ch] / divisor;
        const Lanes e = select(sign[ch] == 0, absolute(x) * scales.off, (1.0f - floatsOf(sign[ch]) * x) * scales.on);
        sum = ch == 0 ? e * e : sum + e * e;
    }
    out.bestMatch = squareRoot(sum);
    return out;
}

}  // namespace

// Cloned for x86-64-v3 and -v4 (STRIA_X86_CLONES, simd.hpp): its 4-lane
// float vectors in VEX encoding (three-operand forms, no register copies;
// vbroadcastss, vpermilps). The same floats: the project builds with
// -ffp-contract=off (no multiply and add fuse), and the square roots are
// sqrtps on every target (squareRoot). bestSymbolLanes is inlined by force
// (the clones had called it, in baseline code). 780x580: edges 3.34 -> 2.20 M
// instructions per decode (the v3 clone, which callgrind runs).
STRIA_X86_CLONES void computeEdgeFeatures(DecoderWorkspace& ws)
{
    // One pass over the edges (three passes streamed them three times); the
    // ranges are maxima, so the order in which the edges raise them does not
    // matter.
    Region* regions = ws.regions.get();
    const float t = static_cast<float>(ws.params.t);
    const MatchScales scales(t);
    for (int e0 = 0; e0 < ws.edgeCount; e0 += kBlock) {
        const int n = std::min(kBlock, ws.edgeCount - e0);
        // Lanes past the last edge repeat it; their results are not stored.
        const GraphEdge* edge[kBlock];
        Region* a[kBlock];
        Region* b[kBlock];
        Lanes from[4], to[4], chord[4], border[4];
        LaneMask ends{};
        for (int i = 0; i < kBlock; ++i) {
            edge[i] = &ws.edges[e0 + std::min(i, n - 1)];
            a[i] = &regions[edge[i]->a];
            b[i] = &regions[edge[i]->b];
            ends[i] = edge[i]->a ^ edge[i]->b;
            // 16 bytes from the colour (R G B, range[0]), the centroids'
            // difference (x, y and two ints' garbage) and the edge's border
            // (count, normal, gradients), transposed: a vector per field.
            std::memcpy(&from[i], a[i]->color.data(), sizeof(Lanes));
            std::memcpy(&to[i], b[i]->color.data(), sizeof(Lanes));
            Lanes fromCentroid, toCentroid;
            std::memcpy(&fromCentroid, &a[i]->centroidX, sizeof(Lanes));
            std::memcpy(&toCentroid, &b[i]->centroidX, sizeof(Lanes));
            chord[i] = toCentroid - fromCentroid;
            std::memcpy(&border[i], &edge[i]->borderCount, sizeof(Lanes));
        }
        static_assert(offsetof(GraphEdge, secondaryGradient) - offsetof(GraphEdge, borderCount) == 12);
        for (Lanes* v : {from, to, chord, border}) transpose4(v);
        // Direction (fig. 5): the border's normal (from a to b); if the
        // border is closed or ragged (its chord is short) the centroids decide
        // instead. Across the stripes if it is within 45 degrees of the
        // primary direction (the border within 45 degrees of the stripes).
        const LaneMask normal = (LaneMask)border[1];
        Lanes nx = floatsOf(normal << 16 >> 16), ny = floatsOf(normal >> 16);  // int16 x, y
        const Lanes count = floatsOf((LaneMask)border[0]);
        const LaneMask ragged = nx * nx + ny * ny < 0.0625f * count * count;  // chord < border length / 4
        nx = select(ragged, chord[0], nx);
        ny = select(ragged, chord[1], ny);
        // Within 45 degrees of the primary direction: |along| / length >= cos 45.
        const Lanes length2 = nx * nx + ny * ny;
        const Lanes along = nx * ws.primary[0] + ny * ws.primary[1];
        const LaneMask across = ~((length2 == 0) | (2.0f * along * along < length2));
        const LaneMask direction = across & ((along <= 0) - (along > 0));  // EdgeDirection
        const SymbolLanes symbols = bestSymbolLanes(from, to, t, scales);
        // Symbols and their errors are only kept across the stripes (the
        // traversal's seeds, paths and links; along them it tests null
        // edges).
        const Lanes primaryGradient = border[2], secondaryGradient = border[3];
        const Lanes ratio = secondaryGradient / primaryGradient;
        const Lanes gradientError = select(primaryGradient > 0, select(kMaxGradientError < ratio, lanesOf(kMaxGradientError), ratio),
                                           lanesOf(kMaxGradientError));
        const LaneMask symbol = select(across, symbols.symbol, LaneMask{} + kNullSymbol);
        Lanes feature[4] = {(Lanes)(ends | (direction + 1) << EdgeFeature::kEndBits | symbol << (EdgeFeature::kEndBits + 2)),
                            symbols.weight, (Lanes)(across & (LaneMask)symbols.bestMatch),
                            (Lanes)(across & (LaneMask)gradientError)};
        transpose4(feature);
        Lanes equalized[4] = {symbols.change[0], symbols.change[1], symbols.change[2], symbols.commonBound};
        transpose4(equalized);
        Lanes change[4] = {symbols.rawChange[0], symbols.rawChange[1], symbols.rawChange[2],
                           lanesOf(-std::numeric_limits<float>::infinity())};
        transpose4(change);
        static_assert(sizeof(EdgeFeature) == sizeof(Lanes) && offsetof(Region, centroidX) == offsetof(Region, range) + 12);
        for (int i = 0; i < n; ++i) {
            std::memcpy(static_cast<void*>(&ws.edgeFeatures[e0 + i]), &feature[i], sizeof(EdgeFeature));
            std::memcpy(static_cast<void*>(&ws.edgeChanges[e0 + i]), &equalized[i], sizeof(EdgeChange));
            // std::max(range, change) per channel, on the 16 bytes from
            // range[0]: the fourth lane is centroidX, which the maximum with
            // -infinity leaves as it is.
            for (Region* r : {a[i], b[i]}) {
                Lanes range;
                std::memcpy(&range, r->range.data(), sizeof range);
                range = greaterOf(change[i], range);
                std::memcpy(r->range.data(), &range, sizeof range);
            }
        }
    }
}

}  // namespace stria::pipeline
