// Stage 6: decoding stripe positions on the region adjacency graph (section 4.3).
//
// Passes, each started from the best unused edge (edges sorted by error):
//  1. Unique path: the seed edge's optimal symbol gives the candidate
//     positions (StripePattern::edgesWithSymbol). The path grows at either end
//     by the lowest-error qualifying edge (right direction, error < A for the
//     symbol some candidate needs there); candidates needing another symbol
//     drop out, until one remains (at the latest after window() edges).
//  2. Best-first propagation from the path's regions with a heap keyed by edge
//     error. A neighbour is a stripe further (forward/backward edge that is
//     not weak, expected pattern symbol, possibly not the optimal one) or,
//     along the stripes, the same stripe (null edge, fig. 6: weak parallel
//     edge, and the virtual edge from the reference region has the same
//     symbol). Edges above A pass only on a token from the bucket, which good
//     edges refill. A region reached again with another stripe keeps the one
//     with the lower position error Q (eq. 10).
// Afterwards three checks drop false positives: regions whose edges across the
// stripes mostly contradict their stripe, regions without window() confirmed
// stripe edges around them (the window property, locally; a black stripe,
// which a shadow imitates, needs one on each side), and components
// (regions decoded by one pass) with fewer than minComponentRegions regions.
#include "pipeline/decoder/symbol_error.hpp"
#include "pipeline/decoder/workspace.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <utility>

namespace stria::pipeline {
namespace {

// A decoded region is dropped when the border it shares with neighbours that
// contradict its stripe is more than this many times the border of those that
// confirm it (see rejectContradictedRegions).
constexpr int kContradictionRatio = 2;
// ... and a weak edge along the stripes to a region of another stripe counts
// this many times its border: along the stripes the stripe does not change,
// so it contradicts one of the two directly, whereas a misfit across the
// stripes is what every occlusion border running along them shows (fan
// outliers 0.198 -> 0.15 %, inliers 76.2 -> 75.0 %; docs/algorithm.md).
constexpr int kAlongStripeWeight = 2;

// A null edge's error adds its border's mean gradient (per pixel pair, summed
// over channels) relative to the reference edge's weight, times this: the
// paper's gradient term (eq. 8) for edges that should show no change. Two
// surfaces of similar colour meeting at a depth step show the misaligned
// stripes along their border; a stripe split by the watershed shows noise.
constexpr float kNullBorderWeight = 0.5f;

#if defined(__aarch64__)
// AArch64 list appends of 4 edges (no movemask, no compress store): the
// lanes' sign bits as a 4-bit mask (cmlt, and with {1, 2, 4, 8}, addv), then
// per mask a tbl that moves the set lanes of the 4 indices to the front
// (forward lists) or to the back in reverse (backward lists, rest[-i]), one
// 16-byte store and the count from a table. The scalar appends (one store
// and one add per edge, the mask's bit extracted per lane) took ~11 and the
// bits from GCC's lane moves ~9 instructions per 4 edges and list. The
// store writes all 4 lanes: the lanes past the count are the next entries'
// places (overwritten or past the list's end), the list's buffer must hold
// them.
struct LaneAppendTables {
    std::uint8_t forward[16][16];
    std::uint8_t backward[16][16];
    std::uint8_t count[16];
};
constexpr LaneAppendTables makeLaneAppendTables()
{
    LaneAppendTables t{};
    for (int bits = 0; bits < 16; ++bits) {
        for (int i = 0; i < 16; ++i) t.forward[bits][i] = t.backward[bits][i] = 0xff;  // (tbl: 0)
        int n = 0;
        for (int k = 0; k < 4; ++k) {
            if (!(bits >> k & 1)) continue;
            for (int b = 0; b < 4; ++b) {
                t.forward[bits][4 * n + b] = static_cast<std::uint8_t>(4 * k + b);
                t.backward[bits][4 * (3 - n) + b] = static_cast<std::uint8_t>(4 * k + b);
            }
            ++n;
        }
        t.count[bits] = static_cast<std::uint8_t>(n);
    }
    return t;
}
inline constexpr LaneAppendTables kLaneAppend = makeLaneAppendTables();

// Bit k set where lane k's sign bit is.
[[gnu::always_inline]] inline unsigned laneSignBits(int32x4_t lanes)
{
    const uint32x4_t weights = {1, 2, 4, 8};
    return vaddvq_u32(vandq_u32(vcltzq_s32(lanes), weights));
}
// list[0, count) = the indices' lanes set in bits, in lane order; returns count.
[[gnu::always_inline]] inline std::ptrdiff_t appendLanes(std::int32_t* list, int32x4_t indices, unsigned bits)
{
    const uint8x16_t moved = vqtbl1q_u8(vreinterpretq_u8_s32(indices), vld1q_u8(kLaneAppend.forward[bits]));
    vst1q_u8(reinterpret_cast<std::uint8_t*>(list), moved);
    return kLaneAppend.count[bits];
}
// list[0], list[-1], .., list[1 - count] = the same; list[-3, 0] written.
[[gnu::always_inline]] inline std::ptrdiff_t appendLanesBackward(std::int32_t* list, int32x4_t indices, unsigned bits)
{
    const uint8x16_t moved = vqtbl1q_u8(vreinterpretq_u8_s32(indices), vld1q_u8(kLaneAppend.backward[bits]));
    vst1q_u8(reinterpret_cast<std::uint8_t*>(list - 3), moved);
    return kLaneAppend.count[bits];
}
#endif

struct Hypothesis {
    float error = 0;
    float positionError = 0;
    int stripe = -1;
    int reference = -1;
};

// The helpers down to stripeSymbol select by arithmetic, not branches: which
// end of an edge a walk comes from (`from` is a or b), and which way along
// the pattern, is data (callgrind's branch model: 29 000 fewer mispredictions
// per 780x580 decode, with the seed count in run()). The features are stored
// as seen from a, the smaller end; `to` is the other end.
EdgeDirection directionFrom(const EdgeFeature& edge, int from, int to)
{
    return static_cast<EdgeDirection>(static_cast<int>(edge.direction()) * (2 * (from < to) - 1));
}

// The edge's optimal symbol seen from `from`. Its error, edge.bestMatch, holds
// from either side: the change from b is the negated change from a, and
// symbolError of the negated change and the reversed symbol is the same
// arithmetic on negated values, so the same float.
SymbolCode bestSymbolFrom(const EdgeFeature& edge, int from, int to)
{
    const bool fromA = from < to;
    const SymbolCode symbol = edge.bestSymbol();
    return static_cast<SymbolCode>(fromA * symbol + !fromA * reversedSymbol(symbol));
}

// The least float not below x: a float is below x exactly when it is below
// this one (a float below x is below it; one not below x is not below it,
// the least such; NaN stays NaN), so a float compared with a double limit
// compares with this float instead, without a conversion each time.
float leastFloatNotBelow(double x)
{
    const float f = static_cast<float>(x);  // the nearest float
    return f < x ? std::nextafter(f, std::numeric_limits<float>::infinity()) : f;
}

// The same for x >= 0 (or NaN), without a branch (x is data): the next float
// up from a float >= +0 is the one of its bits + 1.
float leastFloatNotBelowNonNegative(double x)
{
    const float f = static_cast<float>(x);
    const float up = std::bit_cast<float>(std::bit_cast<std::uint32_t>(f) + 1);
    return f < x ? up : f;
}

// Pattern symbol seen when walking from stripe `from` to the neighbouring stripe `to`.
SymbolCode stripeSymbol(const StripePattern& pattern, int from, int to)
{
    const SymbolCode symbol = pattern.edgeSymbol(std::min(from, to));
    const bool up = to > from;
    return static_cast<SymbolCode>(up * symbol + !up * reversedSymbol(symbol));
}

// Whether stripe `here` has a neighbour beyond it at a path's left (right)
// end; if so, symbol = the pattern symbol walking onto it.
bool symbolBeyond(const StripePattern& pattern, int here, bool left, SymbolCode& symbol)
{
    const int next = here + (left ? -1 : 1);
    if (next < 0 || next >= pattern.stripeCount()) return false;
    symbol = stripeSymbol(pattern, here, next);
    return true;
}

class Traversal {
public:
    explicit Traversal(DecoderWorkspace& ws)
        : ws_(ws), features_(ws.edgeFeatures.get()), t_(static_cast<float>(ws.params.t)), scales_(t_),
          alpha_(static_cast<float>(ws.params.alpha)), A_(static_cast<float>(ws.params.A)),
          beta_(static_cast<float>(ws.params.beta)), tokenErrorLimit_(leastFloatNotBelow(ws.params.tokenErrorLimit))
    {
    }

    void run()
    {
        Region* regions = ws_.regions.get();
        // The regions' stripes also in a compact copy, kept equal to the
        // records': the propagation and the checks look up a neighbour's
        // stripe per edge, and the 64-byte records would bring a cache line
        // each (the copy is 28 KB at 780x580). In the scratch after the seed
        // keys and the link pairs of rejectShortRuns, and after it the
        // regions' components, for rejectSmallComponents' two passes over
        // all regions (from the records: ~7.5 k more L1 misses per 780x580
        // decode). graphScratchEntries: 2 entries per region and per edge.
        stripes_ = ws_.scratch.get() + 2 * static_cast<std::ptrdiff_t>(ws_.maxEdges);
        components_ = stripes_ + ws_.maxRegions;
        for (int r = 0; r < ws_.regionCount; ++r) {
            regions[r].stripe = -1;
            regions[r].component = -1;
            regions[r].reference = regions[r].tokens = 0;  // no dead ends known (findUniquePath)
            stripes_[r] = -1;
            components_[r] = -1;
        }
        // The seeds: the edges across the stripes with bestError < A, listed
        // without a branch (which edges qualify is data). 4 edges per step,
        // their features transposed to a field per vector (16 bytes each:
        // packed bits, weight, bestMatch, gradientError): bestError's
        // arithmetic (the same float per lane) and both tests in lanes, then
        // the list written as by the scalar loop after it, which takes the
        // last edgeCount % 4 and is the reference (19 -> 12 instructions
        // per edge). The count is a std::ptrdiff_t and edgeCount read once:
        // GCC sign-extended an int for each store and reloaded edgeCount
        // after it (the int32 list may alias it).
        std::ptrdiff_t seeds = 0;
        const int edgeCount = ws_.edgeCount;
        int e = 0;
        static_assert(sizeof(EdgeFeature) == sizeof(Float4));
        const Float4 alpha4 = Float4{} + alpha_, a4 = Float4{} + A_;
        std::int32_t* order = ws_.edgeOrder.get();
        auto load = [&](int i) {
            Float4 v;
            std::memcpy(&v, features_ + i, sizeof(v));
            return v;
        };
#if defined(__aarch64__)
        // One ld4 loads the 4 features a field per vector; appendLanes
        // writes the list (features_ in a local: GCC reloaded it after
        // each store to the list).
        const EdgeFeature* features = features_;
        int32x4_t indices = {0, 1, 2, 3};
        for (; e + 4 <= edgeCount; e += 4, indices = vaddq_s32(indices, vdupq_n_s32(4))) {
            const float32x4x4_t f = vld4q_f32(reinterpret_cast<const float*>(features + e));
            using Mask = std::int32_t __attribute__((vector_size(16)));
            const Float4 v[4] = {f.val[0], f.val[1], f.val[2], f.val[3]};
            const Mask along = ((Mask)v[0] >> EdgeFeature::kEndBits & 3) == 1;
            const Mask qualifies = ~along & (v[2] + alpha4 * v[3] < a4);
            seeds += appendLanes(order + seeds, indices, laneSignBits(qualifies));
        }
#endif
        for (; e + 4 <= edgeCount; e += 4) {
            Float4 v[4] = {load(e), load(e + 1), load(e + 2), load(e + 3)};
            transpose4(v);
            using Mask = std::int32_t __attribute__((vector_size(16)));
            const Mask along = ((Mask)v[0] >> EdgeFeature::kEndBits & 3) == 1;  // (the bits, not a conversion)
            const Mask qualifies = ~along & (v[2] + alpha4 * v[3] < a4);  // (lanes: -1 where true)
#if defined(__SSE2__)
            unsigned bits = static_cast<unsigned>(_mm_movemask_ps((__m128)qualifies));
#else
            unsigned bits = 0;
            for (int k = 0; k < 4; ++k) bits |= (static_cast<unsigned>(qualifies[k]) & 1u) << k;
#endif
            for (int k = 0; k < 4; ++k) {
                order[seeds] = e + k;
                seeds += bits >> k & 1;
            }
        }
        for (; e < edgeCount; ++e) {  // (directionPlusOne() == 1: along the stripes)
            order[seeds] = e;
            seeds += (features_[e].directionPlusOne() != 1) & (bestError(features_[e]) < A_);
        }
        sortSeeds(static_cast<int>(seeds));
        ws_.open[0].order = 0;  // the open heap's sentinel (pushOpen), after the sort used the storage
        ws_.passCount = 0;
        for (int i = 0; i < seeds; ++i) {
            const GraphEdge& edge = ws_.edges[ws_.edgeOrder[i]];
            if (stripes_[edge.a] >= 0 || stripes_[edge.b] >= 0) continue;
            if (!findUniquePath(ws_.edgeOrder[i])) continue;
            propagate();
            ++ws_.passCount;
        }
        const int linkCount = weighEvidence();
        rejectContradictedRegions();
        rejectShortRuns(linkCount);
        rejectSmallComponents();
    }

private:
    // Eq. 9 for the edge's optimal symbol (parallel edges: 0).
    float bestError(const EdgeFeature& edge) const { return edge.bestMatch + alpha_ * edge.gradientError; }

    // Eq. 5-6 for `symbol` on `edge` walked from `from` to `to`: the edge
    // stage's error if it is the optimal symbol, else from the edge's stored
    // change (seen from a, so the symbol reversed when walking from b).
    float symbolMatch(const EdgeFeature& edge, int from, int to, SymbolCode symbol) const
    {
        // (The symbol seen from a against the optimal one, which is stored
        // as seen from a: bestSymbolFrom's comparison, one reversal fewer.)
        const SymbolCode symbolFromA = from < to ? symbol : reversedSymbol(symbol);
        if (edge.bestSymbol() == symbolFromA) return edge.bestMatch;
        return symbolError(ws_.edgeChanges[&edge - features_], symbolFromA, scales_);
    }

    // Eq. 9 for `symbol` on `edge` walked from `from` to `to`, and eq. 10
    // into positionError if given.
    float edgeError(int from, int to, const EdgeFeature& edge, SymbolCode symbol, float* positionError) const
    {
        const float match = symbolMatch(edge, from, to, symbol);
        if (positionError) *positionError = beta_ * match / std::max(edge.weight, 1.0f) + edge.gradientError;
        return match + alpha_ * edge.gradientError;
    }

    // A seed's sort key: its error's bits made order-preserving, then its
    // index. May alias: it lives in the int32 scratch and in the heap's
    // storage.
    struct __attribute__((may_alias)) SeedKey {
        std::uint64_t value;
    };
    static constexpr int kRadixBits = 11;  // 3 passes sort the 32 bits of an error

    // Orders edgeOrder[0, count) by bestError, then by index, as 64-bit keys
    // in the scratch (free after the graph stage; graphScratchEntries gives
    // it 2 entries per edge). A stable radix sort by the error bits, least
    // significant digit first, keeps the index order (ascending as the seeds
    // were collected) among equal errors: the order of sorting the whole
    // keys, without a comparison sort's unpredictable branches (std::sort:
    // 24 000 mispredictions per 780x580 frame). The passes alternate with
    // the open heap's storage, free before the first pass: it holds
    // max(16, maxEdges / 2) entries of 24 bytes (decoder.cpp), room for
    // maxEdges keys.
    void sortSeeds(int count)
    {
        static_assert(sizeof(OpenEntry) >= 2 * sizeof(SeedKey) + 4);
        SeedKey* keys = reinterpret_cast<SeedKey*>(ws_.scratch.get());
        SeedKey* other = reinterpret_cast<SeedKey*>(ws_.open.get());
        // The three digits' counts in the pass that makes the keys (counts
        // do not depend on the order, so the passes need not count again).
        constexpr int kPasses = (32 + kRadixBits - 1) / kRadixBits;
        auto digit = [](const SeedKey& key, int pass) {
            return (key.value >> (32 + pass * kRadixBits)) & ((1u << kRadixBits) - 1);
        };
        std::array<std::array<std::int32_t, 1 << kRadixBits>, kPasses> starts{};
        for (int i = 0; i < count; ++i) {
            const int e = ws_.edgeOrder[i];
            keys[i].value = orderKey(bestError(features_[e]), e);
            for (int pass = 0; pass < kPasses; ++pass) ++starts[pass][digit(keys[i], pass)];
        }
        for (int pass = 0; pass < kPasses; ++pass) {
            std::array<std::int32_t, 1 << kRadixBits>& start = starts[pass];
            if (count > 0 && start[digit(keys[0], pass)] == count) continue;  // one digit: the order stays
            std::int32_t sum = 0;
            for (std::int32_t& s : start) sum += std::exchange(s, sum);
            for (int i = 0; i < count; ++i) other[start[digit(keys[i], pass)]++] = keys[i];
            std::swap(keys, other);
        }
        for (int i = 0; i < count; ++i) ws_.edgeOrder[i] = static_cast<std::int32_t>(keys[i].value & 0xffffffffu);
    }

    // An error and an index (edge or region) as one 64-bit key in the order
    // (error, index): the error's bits made an unsigned integer in the order
    // of the floats (not NaN; -0 as +0) in the high half, the index in the
    // low half.
    static std::uint64_t orderKey(float error, std::int32_t index)
    {
        const std::uint32_t bits = std::bit_cast<std::uint32_t>(error + 0.0f);
        const std::uint32_t ordered = bits & 0x80000000u ? ~bits : bits | 0x80000000u;
        return static_cast<std::uint64_t>(ordered) << 32 | static_cast<std::uint32_t>(index);
    }

    // Calls visit(e, to) for each edge e of region `from` (to: its other
    // end) for which keep(edge, to) holds, in incidence order, until visit
    // returns false (then returns false). Which edges qualify is decided
    // first, for a chunk of edges at a time, without a branch: it depends on
    // the neighbours' stripes, which is data to a branch predictor, and the
    // edge features, read at random, load together.
    template <class Keep, class Visit>
    [[gnu::always_inline]] bool forEachEdgeWhere(int from, Keep&& keep, Visit&& visit) const
    {
        const Region& r = ws_.regions[from];
        constexpr int kChunk = 64;
        std::array<std::int32_t, kChunk> kept;
        for (int chunk = 0; chunk < r.degree; chunk += kChunk) {
            const int chunkEnd = std::min(r.degree, chunk + kChunk);
            std::ptrdiff_t keptCount = 0;  // (no sign extension per edge)
            for (int i = chunk; i < chunkEnd; ++i) {
                const int e = ws_.adjacency[r.adjacencyBegin + i];
                const EdgeFeature& edge = features_[e];
                kept[keptCount] = e;
                keptCount += keep(edge, edge.otherEnd(from));
            }
            for (std::ptrdiff_t k = 0; k < keptCount; ++k)
                if (!visit(kept[k], features_[kept[k]].otherEnd(from))) return false;
        }
        return true;
    }

    // A region on the growing path (findUniquePath), in stripes_ only.
    static constexpr std::int32_t kOnPath = 0x7fffffff;

    // The symbols known to extend no path at the left (right) end of an
    // undecoded region: bit s set when no edge to an undecoded neighbour in
    // that direction had an error below A for symbol s, in the first step of
    // a search that failed there. Most seeds fail in that step (780x580: 730
    // of 800 searches per decode), and their ends are often the ends of
    // earlier seeds. The set of undecoded neighbours only shrinks during the
    // seeding (a failed search undecodes only its own path's regions, and
    // in the first step those are the two ends, reached by the seed edge,
    // which is not outward from either), and an edge's error for a symbol
    // is always the same float, so those symbols stay dead and are not tested
    // again: the path found is the same, for 19 % fewer symbol tests. Held
    // in the record's reference (left) and tokens (right), which mean
    // nothing before the region is decoded (both set then) and share the
    // cache line of its degree, which the search reads anyway; run() zeroes
    // them.
    static std::int32_t& deadSymbols(Region& r, bool left) { return left ? r.reference : r.tokens; }

    // Step 1. Returns true when the path was unique and its regions are assigned.
    bool findUniquePath(int seedEdge)
    {
        const StripePattern& pattern = ws_.pattern;
        const GraphEdge& seed = ws_.edges[seedEdge];
        const bool forward = features_[seedEdge].direction() == EdgeDirection::Forward;
        std::int32_t* path = ws_.pathVertices.get();
        const int maxPath = pattern.window() + 1;
        // The path is path[begin, end), left to right; room to grow either way.
        int begin = maxPath, end = maxPath;
        path[end++] = forward ? seed.a : seed.b;
        path[end++] = forward ? seed.b : seed.a;
        // The path's regions hold kOnPath in stripes_ while it grows, so one
        // test (stripe >= 0) skips decoded regions and the path's own; they
        // are undecoded again if no unique path is found.
        stripes_[path[begin]] = stripes_[path[begin + 1]] = kOnPath;
        auto fail = [&] {
            for (int i = begin; i < end; ++i) stripes_[path[i]] = -1;
            return false;
        };
        const SymbolCode symbol = bestSymbolFrom(features_[seedEdge], path[end - 2], path[end - 1]);
        // candidates: pattern edge index of the path's first edge.
        int count = 0;
        for (int p : pattern.edgesWithSymbol(symbol)) ws_.candidates[count++] = p;

        while (count > 1 && end - begin <= pattern.window()) {
            float bestError = A_;
            int bestRegion = -1;
            bool bestLeft = false;
            SymbolCode bestSymbol = kNullSymbol;
            // (Unrolled: each turn with `left` a constant, its tests and selects
            // folded; -0.15 M instructions per 780x580 decode.)
#pragma GCC unroll 2
            for (bool left : {true, false}) {
                // The symbols the candidates need at this end, each once, in
                // the candidates' order (a repeated symbol gives the same
                // error, which cannot be lower than the first time): the same
                // for every edge at this end.
                // Dead symbols (see deadSymbols) are left out, but count as
                // seen.
                const int endRegion = left ? path[begin] : path[end - 1];
                std::int32_t& dead = deadSymbols(ws_.regions[endRegion], left);
                std::array<SymbolCode, kSymbolCount> needed;
                int neededCount = 0;
                std::uint32_t seen = 0;
                if (end - begin == 2) {
                    // The first step: the candidates are all of the seed
                    // symbol's, whose symbols at this end are listed at
                    // start-up (ws.firstStep); less the dead ones.
                    const DecoderWorkspace::FirstStepSymbols& first = ws_.firstStep[symbol][left];
                    for (int k = 0; k < first.count; ++k) {
                        needed[neededCount] = first.symbols[k];
                        neededCount += !(static_cast<std::uint32_t>(dead) >> first.symbols[k] & 1);
                    }
                    seen = first.seen;
                } else {
                    for (int c = 0; c < count; ++c) {
                        SymbolCode beyond;
                        if (!symbolBeyond(pattern, ws_.candidates[c] + (left ? 0 : end - begin - 1), left, beyond))
                            continue;
                        needed[neededCount] = beyond;
                        neededCount += !((seen | static_cast<std::uint32_t>(dead)) >> beyond & 1);
                        seen |= 1u << beyond;
                    }
                }
                if (neededCount == 0) continue;
                // The edges that can extend the path: the right direction, the
                // neighbour undecoded and not on the path (kOnPath).
                const EdgeDirection outward = left ? EdgeDirection::Backward : EdgeDirection::Forward;
                auto extends = [&](const EdgeFeature& edge, int next) {
                    return (directionFrom(edge, endRegion, next) == outward) & (stripes_[next] < 0);
                };
                forEachEdgeWhere(endRegion, extends, [&](int e, int next) {
                    const EdgeFeature& edge = features_[e];
                    // The best kept by selects, not a branch, so that the
                    // symbols' chains of divisions overlap (and one loop, not
                    // two, ends per edge).
                    for (int k = 0; k < neededCount; ++k) {
                        const float error = symbolMatch(edge, endRegion, next, needed[k]) + alpha_ * edge.gradientError;
                        const bool better = error < bestError;
                        bestError = better ? error : bestError;
                        bestRegion = better ? next : bestRegion;
                        bestLeft = better ? left : bestLeft;
                        bestSymbol = better ? needed[k] : bestSymbol;
                    }
                    return true;
                });
                // Nothing below A at this end (nor at the left one before
                // it): the needed symbols are dead here (see deadSymbols).
                if (end - begin == 2 && bestError == A_) dead |= static_cast<std::int32_t>(seen);
            }
            if (bestRegion < 0) return fail();
            int kept = 0;
            for (int c = 0; c < count; ++c) {
                SymbolCode beyond;
                if (symbolBeyond(pattern, ws_.candidates[c] + (bestLeft ? 0 : end - begin - 1), bestLeft, beyond) &&
                    beyond == bestSymbol)
                    ws_.candidates[kept++] = ws_.candidates[c] - (bestLeft ? 1 : 0);
            }
            count = kept;
            if (bestLeft) path[--begin] = bestRegion;
            else path[end++] = bestRegion;
            stripes_[bestRegion] = kOnPath;
        }
        if (count != 1) return fail();

        const int first = ws_.candidates[0];
        const int pass = ws_.passCount;
        const int length = end - begin;
        for (int i = 0; i < length; ++i) {
            Region& r = ws_.regions[path[begin + i]];
            r.stripe = stripes_[path[begin + i]] = first + i;
            r.reference = path[begin + (i > 0 ? i - 1 : 1)];
            r.component = components_[path[begin + i]] = pass;
            r.tokens = std::min(length - 1, ws_.params.tokenBucketSize);
            r.positionError = 1e30f;
        }
        // Q of each path region: its best path edge.
        for (int i = 0; i + 1 < length; ++i) {
            const int l = path[begin + i], r = path[begin + i + 1];
            for (int k = 0; k < ws_.regions[l].degree; ++k) {
                const EdgeFeature& edge = features_[ws_.adjacency[ws_.regions[l].adjacencyBegin + k]];
                if (edge.otherEnd(l) != r) continue;
                float q = 0;
                edgeError(l, r, edge, stripeSymbol(ws_.pattern, first + i, first + i + 1), &q);
                ws_.regions[l].positionError = std::min(ws_.regions[l].positionError, q);
                ws_.regions[r].positionError = std::min(ws_.regions[r].positionError, q);
            }
        }
        ws_.openCount = 0;
        for (int i = 0; i < length; ++i) pushNeighbours(path[begin + i]);
        return true;
    }

    // The way to reach `to` from decoded region `from` over edge `e` (in
    // direction `dir` from `from`) that pushNeighbours' filter let through,
    // if any (else stripe -1); referenceWeight is the weight of the edge
    // from `from`'s reference region (0 without one). The filter took the
    // tests on the direction, the edge's weakness, the stripes' range and
    // the reference's stripe, and left each edge one case.
    Hypothesis bestHypothesis(int from, int to, int e, EdgeDirection dir, float referenceWeight) const
    {
        const EdgeFeature& edge = features_[e];
        const StripePattern& pattern = ws_.pattern;
        const Region& f = ws_.regions[from];
        // Across the stripes, an edge that is not weak: the next stripe. An
        // edge as weak as a null edge (fig. 6) is no stripe step: its
        // colour change is noise, and the normalised noise fits some symbol
        // now and then (sphere: regions one stripe off along its rim).
        if (dir != EdgeDirection::Parallel) {
            const int stripe = f.stripe + static_cast<int>(dir);
            // edgeError(from, to, edge, stripeSymbol(pattern, f.stripe,
            // stripe), &q) with the symbol seen from a taken directly: the
            // pattern's symbol up from the lower stripe, reversed where the
            // edge goes down from a (whichever end `from` is, walking from
            // a goes up exactly when the edge's direction from a is
            // forward); one selection, where stripeSymbol and symbolMatch
            // each reversed by which end `from` is.
            const SymbolCode up = pattern.edgeSymbol(std::min(f.stripe, stripe));
            const SymbolCode symbolFromA = edge.directionPlusOne() == 2 ? up : reversedSymbol(up);
            const float match = edge.bestSymbol() == symbolFromA
                                    ? edge.bestMatch
                                    : symbolError(ws_.edgeChanges[e], symbolFromA, scales_);
            const float q = beta_ * match / std::max(edge.weight, 1.0f) + edge.gradientError;
            return {match + alpha_ * edge.gradientError, q, stripe, from};
        }
        // Null edge (fig. 6): weak relative to the reference edge, the
        // reference one stripe off, and the (possibly virtual) edge
        // reference -> `to` has the reference edge's symbol.
        // Only along the stripes: across them the pattern changes at every
        // edge, and at low contrast a weak stripe edge taken for a null edge
        // slips the decoding by a stripe (photo texture, contrast 0.3:
        // patches 1-5 stripes off; inliers 77% -> 86%, outliers 0.20% ->
        // 0.10%, fan outliers 0.85% -> 0.72%).
        Hypothesis none;
        const Region& ref = ws_.regions[f.reference];
        const SymbolCode expected = stripeSymbol(pattern, ref.stripe, f.stripe);
        const ExpectedSymbolMatch match = expectedSymbolMatch(ws_, f.reference, to, expected, t_, scales_);
        if (!match.fits) return none;
        const GraphEdge& border = ws_.edges[e];
        const float meanGradient = (border.primaryGradient + border.secondaryGradient) / std::max(border.borderCount, 1);
        const float error = match.error + kNullBorderWeight * meanGradient / std::max(referenceWeight, 1.0f);
        if (!(error < 1e30f)) return none;  // as a first candidate's error it had to beat 1e30
        return {error, beta_ * error / std::max(match.weight, 1.0f), f.stripe, f.reference};
    }

    void pushNeighbours(int from)
    {
        const Region& f = ws_.regions[from];
        float referenceWeight = 0;
        if (f.reference >= 0)
            for (int c = 0; c < 3; ++c)
                referenceWeight = std::max(referenceWeight, std::abs(f.color[c] - ws_.regions[f.reference].color[c]));
        // Which edges can give a hypothesis (see bestHypothesis) is decided
        // first (forEachEdgeWhere), without a branch: whether a neighbour
        // already holds the stripe is data (a branch on it mispredicted
        // ~20 k times per 780x580 decode). Across the stripes the
        // only hypothesis is the next stripe, by an edge that is not weak:
        // a neighbour that holds it already needs no error evaluated (most
        // neighbours of a decoded region, in the interior of a pass). Along
        // them, a weak edge is a null edge if the reference is one stripe off.
        // (weakBelow: the product's least float not below, so an edge's
        // weight compares without a conversion; nullEdgeRatio >= 0.)
        const float weakBelow = leastFloatNotBelowNonNegative(ws_.params.nullEdgeRatio * referenceWeight);
        const int refStripe = f.reference >= 0 ? stripes_[f.reference] : -1;
        const bool nullEdges = refStripe >= 0 && std::abs(refStripe - f.stripe) == 1;
        const int stripe = f.stripe, stripeCount = ws_.pattern.stripeCount();
        // Bit dir + 1 (direction from `from`: -1, 0, +1): whether an edge
        // that way can give a hypothesis at all: across, the next stripe
        // exists; along, null edges are possible.
        const unsigned possible = (stripe - 1 >= 0) | (nullEdges << 1) | ((stripe + 1 < stripeCount) << 2);
        // With an edge weak exactly along the stripes: bit dir + 1 + 3 * weak
        // (across: bits 0 and 2, not weak; along: bit 4, weak).
        const unsigned possibleWeak = (possible & 5u) | (possible & 2u) << 3;
        // That, and a neighbour holding neither the stripe nor the next one
        // (along, next is the stripe): the conditions of bestHypothesis's two
        // cases as one expression. dir is directionFrom's product in int (no
        // sign extension of its int8 EdgeDirection), and the weak edge's test
        // is the mask's (no separate test of dir == 0); the plain form:
        //   dir = directionFrom(edge, from, to);
        //   (toStripe != stripe) & (toStripe != stripe + dir) &
        //   (weak == (dir == 0)) & (possible >> (dir + 1) & 1)
        auto canGiveHypothesis = [&](const EdgeFeature& edge, int to) {
            const int toStripe = stripes_[to];
            const int dir = (edge.directionPlusOne() - 1) * (2 * (from < to) - 1);
            const unsigned weak = edge.weight < weakBelow;
            return (toStripe != stripe) & (toStripe != stripe + dir) & (possibleWeak >> (dir + 1 + 3 * weak) & 1);
        };
        forEachEdgeWhere(from, canGiveHypothesis, [&](int e, int to) {
            const EdgeDirection dir = directionFrom(features_[e], from, to);
            const Hypothesis h = bestHypothesis(from, to, e, dir, referenceWeight);
            if (h.stripe < 0) return true;  // (the filter ruled out to's own stripe)
            // Below A an edge earns a token (up to the bucket), else up to
            // tokenErrorLimit it spends one, if there is one: as one branch
            // (which case is data) and one update. The scalar form:
            //   if (error < A) tokens = min(tokens + 1, bucket);
            //   else if (tokens > 0 && error < tokenErrorLimit) --tokens;
            //   else reject.
            // tokens <= bucket (every entry's tokens came from here or from
            // min(length - 1, bucket)), so min() leaves tokens - 1 as it is.
            const bool good = h.error < A_;
            if (!(good | ((f.tokens > 0) & (h.error < tokenErrorLimit_)))) return true;
            const int tokens = std::min(f.tokens + 2 * static_cast<int>(good) - 1, ws_.params.tokenBucketSize);
            if (ws_.openCount == ws_.maxOpen) {
                ws_.truncated = true;
                return false;
            }
            // The heap key orders by error, then region: the pushed errors
            // are below A or tokenErrorLimit, so never NaN.
            pushOpen({orderKey(h.error, to), h.positionError, h.reference, static_cast<std::int16_t>(h.stripe),
                      static_cast<std::int16_t>(tokens)});
            return true;
        });
    }

    // The open heap, the lowest key on top: std::push_heap and std::pop_heap
    // step for step with the order "later = larger key" (the same entries
    // in the same places, ties included), but the child on the way down is
    // chosen without a branch (its comparison is noise to the predictor).
    // Its entries are open[1, openCount]: node i's children are 2i and
    // 2i + 1, its parent i / 2, and open[0] holds the key 0 (no key is
    // below it), set in run(): the way up stops there without a test of the
    // index (the open storage holds maxOpen + 1 entries; callgrind: -0.15 M
    // instructions and -0.9 k mispredictions per 780x580 decode).
    void pushOpen(const OpenEntry& entry)
    {
        OpenEntry* heap = ws_.open.get();
        siftUp(heap, ++ws_.openCount, entry);
    }

    // (Indices as std::ptrdiff_t, no sign extension per level, and the
    // hole's address carried down: 19 -> 15 instructions per level.)
    OpenEntry popOpen()
    {
        OpenEntry* heap = ws_.open.get();
        const OpenEntry top = heap[1];
        const std::ptrdiff_t count = --ws_.openCount;
        if (count == 0) return top;
        const OpenEntry last = heap[count + 1];
        // A key above every other in the place the last entry leaves: a node
        // whose only child is the last entry has two then, and the way down
        // takes that child like any other, the larger one being never taken:
        // one store per pop instead of that case's test, on the count's
        // parity (its ~1.4 k mispredictions per 780x580 decode reappear in
        // callgrind at the sift-up, though). No key is all ones: errors are
        // not NaN.
        heap[count + 1].order = ~std::uint64_t{0};
        std::ptrdiff_t child = 1;  // the hole
        const std::ptrdiff_t withChildren = count / 2;  // the nodes up to it have a child (and the sentinel)
        OpenEntry* holeAt = heap + 1;  // heap + hole, carried (not recomputed from hole)
        while (child <= withChildren) {
            child = 2 * child + 1;
            child -= heap[child].order > heap[child - 1].order;
            OpenEntry* childAt = heap + child;
            *holeAt = *childAt;
            holeAt = childAt;
        }
        siftUp(heap, child, last);
        return top;
    }

    static void siftUp(OpenEntry* heap, std::ptrdiff_t hole, const OpenEntry& entry)
    {
        for (;;) {
            const std::ptrdiff_t parent = hole >> 1;
            if (!(heap[parent].order > entry.order)) break;  // (heap[0] ends it)
            heap[hole] = heap[parent];
            hole = parent;
        }
        heap[hole] = entry;
    }

    // Step 2.
    void propagate()
    {
        while (ws_.openCount > 0) {
            const OpenEntry entry = popOpen();
            const int region = static_cast<std::int32_t>(entry.order & 0xffffffffu);
            Region& r = ws_.regions[region];
            // The stripe from the compact copy (equal to the record's): the
            // branches wait on it, not on the record, which misses the cache
            // for about half the pops (780x580: 3.9 k of 7 k per decode).
            const int stripe = stripes_[region];
            if (stripe == entry.stripe) {
                r.positionError = std::min(r.positionError, entry.positionError);
                continue;
            }
            if (stripe >= 0 && r.positionError <= entry.positionError) continue;
            r.stripe = stripes_[region] = entry.stripe;
            r.positionError = entry.positionError;
            r.reference = entry.reference;
            r.tokens = entry.tokens;
            r.component = components_[region] = ws_.passCount;
            pushNeighbours(region);
        }
    }

    // The evidence of the checks below, in one pass over the edges (read in
    // order, each error evaluated once; walking the regions' incidence lists
    // read every edge twice, at random): per decoded region, in componentSize,
    // its contradicting border minus kContradictionRatio times its confirming
    // border (integers: the sum does not depend on the order), and in the
    // scratch (free after the seed sort; 2 entries per edge), for
    // rejectShortRuns, the links between decoded regions across the stripes
    // in edge order: pairs (left region, 2 * right region + confirmed), for
    // the same stripe (not confirmed) or consecutive stripes in the edge's
    // direction whose symbol fits (error < tokenErrorLimit, confirmed).
    //
    // A region decoded across a depth discontinuity by one edge that matched
    // by chance has the pattern contradicted by its other edges across the
    // stripes: weighed by border length, those that do not fit its stripe
    // (error >= tokenErrorLimit for the expected symbol, not a weak null
    // edge, neighbour not decoded consistently), and weak edges along the
    // stripes to a region of another stripe (kAlongStripeWeight times),
    // against those that fit. Such regions are undecoded when the
    // contradicting border outweighs the confirming one kContradictionRatio
    // times (rejectContradictedRegions); a region on a true boundary keeps one
    // confirming side, a wrongly offset one has almost none.
    int weighEvidence()
    {
        const StripePattern& pattern = ws_.pattern;
        const float limit = static_cast<float>(ws_.params.tokenErrorLimit);
        const float nullEdgeRatio = static_cast<float>(ws_.params.nullEdgeRatio);
        // The edge is weak for region v (as weak as a null edge): read only
        // where it decides, the region records being 64 bytes each.
        auto weakEdge = [&](int v) { return nullEdgeRatio * maxChannelRange(ws_.regions[v]); };
        std::int32_t* score = ws_.componentSize.get();
        std::fill(score, score + ws_.regionCount, 0);
        std::int32_t* pairs = ws_.scratch.get();
        int linkCount = 0;
        // The edges that can weigh are listed first, without a branch (which
        // regions are decoded is data), in the seed order's buffer (free
        // after the seeds): across the stripes those with both ends decoded,
        // in edge order (the links' order), from the front; from the back
        // the rest, whose scores are sums (the order does not matter):
        // across the stripes those with one end decoded, along them those
        // between regions of different stripes (few: the branch between
        // the two is predictable). The two lists hold at most edgeCount
        // entries; where they meet, both write e. (One list, with a branch
        // per edge on which ends are decoded, and the link by selects GCC
        // made a branch: 6.6 k more mispredictions per 780x580 decode.)
        std::int32_t* both = ws_.edgeOrder.get();
        std::int32_t* rest = both + ws_.maxEdges - 1;  // rest[-i]
        std::ptrdiff_t bothCount = 0, restCount = 0;  // (no sign extension per store)
        const int edgeCount = ws_.edgeCount;  // (not reloaded after each store to the lists)
        // 4 edges per step: the ends' stripes and the directions in lanes,
        // the two tests in lanes, then the lists written as by the scalar
        // loop after it (the reference, and the last edgeCount % 4): 29 ->
        // ~24 instructions per edge (the stripes are 8 loads either way).
        {
            int e = 0;
            const GraphEdge* edges = ws_.edges.get();
            using Mask = std::int32_t __attribute__((vector_size(16)));
#if defined(__aarch64__)
            // The packed words by one ld4, the lists by appendLanes: 8
            // entries past the loop's edges keep the lists' garbage lanes (up
            // to 3 past each count) off the other list's entries. (The
            // stripes by ld1 lane loads took more: ld1 has no register
            // offset, an add per lane.) The members in locals: GCC reloaded
            // them after each store to the lists.
            const std::int32_t* stripes = stripes_;
            const EdgeFeature* features = features_;
            int32x4_t indices = {0, 1, 2, 3};
            for (; e + 8 <= edgeCount; e += 4, indices = vaddq_s32(indices, vdupq_n_s32(4))) {
                const GraphEdge* g = edges + e;
                const Mask sa = {stripes[g[0].a], stripes[g[1].a], stripes[g[2].a], stripes[g[3].a]};
                const Mask sb = {stripes[g[0].b], stripes[g[1].b], stripes[g[2].b], stripes[g[3].b]};
                const Mask packed = vld4q_s32(reinterpret_cast<const std::int32_t*>(features + e)).val[0];
                const Mask parallel = (packed >> EdgeFeature::kEndBits & 3) == 1;
                const Mask noneDecoded = sa & sb, notAllDecoded = sa | sb;
                const Mask bothMask = ~(parallel | notAllDecoded);
                // The rest's test as one select by parallel (bsl; its lanes
                // are -1 or 0) of the two halves' inverses (orr, orn): the
                // same sign bits; the two masks and their sign bits' tests
                // 10 instructions where the reference's expression took 12.
                const Mask restMask = ~(parallel ? notAllDecoded | (sa == sb) : noneDecoded | ~notAllDecoded);
                bothCount += appendLanes(both + bothCount, indices, laneSignBits(bothMask));
                restCount += appendLanesBackward(rest - restCount, indices, laneSignBits(restMask));
            }
#endif
            for (; e + 4 <= edgeCount; e += 4) {
                const GraphEdge* g = edges + e;
                const Mask sa = {stripes_[g[0].a], stripes_[g[1].a], stripes_[g[2].a], stripes_[g[3].a]};
                const Mask sb = {stripes_[g[0].b], stripes_[g[1].b], stripes_[g[2].b], stripes_[g[3].b]};
                const Mask packed = {static_cast<std::int32_t>(features_[e].packed),
                                     static_cast<std::int32_t>(features_[e + 1].packed),
                                     static_cast<std::int32_t>(features_[e + 2].packed),
                                     static_cast<std::int32_t>(features_[e + 3].packed)};
                // The tests' results in the lanes' sign bits, which the
                // movemask takes: sa & sb is negative where no end is
                // decoded (!anyDecoded), sa | sb where one is not
                // (!allDecoded); parallel and sa == sb are -1 where true.
                const Mask parallel = (packed >> EdgeFeature::kEndBits & 3) == 1;
                const Mask noneDecoded = sa & sb, notAllDecoded = sa | sb;
                const Mask bothMask = ~(parallel | notAllDecoded);
                const Mask restMask =
                    (~(parallel | noneDecoded) & notAllDecoded) | (parallel & ~(notAllDecoded | (sa == sb)));
#if defined(__SSE2__)
                const unsigned bothBits = static_cast<unsigned>(_mm_movemask_ps((__m128)bothMask));
                const unsigned restBits = static_cast<unsigned>(_mm_movemask_ps((__m128)restMask));
#else
                unsigned bothBits = 0, restBits = 0;
                for (int k = 0; k < 4; ++k) {
                    bothBits |= (static_cast<unsigned>(bothMask[k]) >> 31) << k;
                    restBits |= (static_cast<unsigned>(restMask[k]) >> 31) << k;
                }
#endif
                for (int k = 0; k < 4; ++k) {
                    both[bothCount] = e + k;
                    bothCount += bothBits >> k & 1;
                    rest[-restCount] = e + k;
                    restCount += restBits >> k & 1;
                }
            }
            for (; e < edgeCount; ++e) {
                const GraphEdge& edge = ws_.edges[e];
                const int sa = stripes_[edge.a], sb = stripes_[edge.b];
                const bool parallel = features_[e].direction() == EdgeDirection::Parallel;
                const bool anyDecoded = (sa & sb) >= 0, allDecoded = (sa | sb) >= 0;
                both[bothCount] = e;
                bothCount += !parallel & allDecoded;
                rest[-restCount] = e;
                restCount += (!parallel & anyDecoded & !allDecoded) | (parallel & allDecoded & (sa != sb));
            }
        }
        for (std::ptrdiff_t i = 0; i < restCount; ++i) {
            const int e = rest[-i];
            const GraphEdge& edge = ws_.edges[e];
            const EdgeFeature& feature = features_[e];
            const EdgeDirection direction = feature.direction();
            const int border = edge.borderCount;
            if (direction == EdgeDirection::Parallel) {
                // Along the stripes the stripe stays: a weak edge to a region
                // decoded as another stripe contradicts one of them.
                if (feature.weight < weakEdge(edge.a)) score[edge.a] += kAlongStripeWeight * border;
                if (feature.weight < weakEdge(edge.b)) score[edge.b] += kAlongStripeWeight * border;
                continue;
            }
            // One end decoded: does the edge show the symbol to the next stripe?
            const int sa = stripes_[edge.a], sb = stripes_[edge.b];
            const int step = static_cast<int>(direction);  // b = a + step if consecutive
            // (v, w) = (a, b) if a is the decoded end, else (b, a), by masks:
            // GCC made the selects a branch (~1.2 k mispredictions per
            // 780x580 decode).
            const int fromB = sa >> 31;  // -1 where a is not decoded (then b is)
            const int flip = (edge.a ^ edge.b) & fromB;
            const int v = edge.a ^ flip, w = edge.b ^ flip;
            const int stripe = sa ^ ((sa ^ sb) & fromB), expected = stripe + ((step ^ fromB) - fromB);
            if (expected >= 0 && expected < pattern.stripeCount() &&
                edgeError(v, w, feature, stripeSymbol(pattern, stripe, expected), nullptr) < limit)
                score[v] -= kContradictionRatio * border;
            else if (feature.weight >= weakEdge(v))
                score[v] += border;
        }
        // Both ends decoded: a link if the stripe is the same (a null edge
        // within the stripe, not confirmed) or the next one in the edge's
        // direction with a fitting symbol (confirmed, a confirming border);
        // else a contradicting border. The link is written for every edge,
        // counted where it is one; the score's change is selected.
        for (std::ptrdiff_t i = 0; i < bothCount; ++i) {
            const int e = both[i];
            const GraphEdge& edge = ws_.edges[e];
            const int sa = stripes_[edge.a], sb = stripes_[edge.b];
            const EdgeFeature& feature = features_[e];
            const int border = edge.borderCount;
            const int step = static_cast<int>(feature.direction());  // b = a + step if consecutive
            const bool same = sa == sb;
            const bool fits = sb == sa + step &&
                              edgeError(edge.a, edge.b, feature, stripeSymbol(pattern, sa, sb), nullptr) < limit;
            // (left, right) = (a, b) forward, (b, a) backward, by masks: GCC
            // made the selects a branch (~3.8 k mispredictions per decode).
            const int flip = (edge.a ^ edge.b) & -static_cast<int>(step < 0);
            const int left = edge.a ^ flip, right = edge.b ^ flip;
            pairs[2 * linkCount] = left;
            pairs[2 * linkCount + 1] = 2 * right + fits;
            linkCount += same | fits;
            const int change = fits ? -kContradictionRatio * border : same ? 0 : border;
            score[edge.a] += change;
            score[edge.b] += change;
        }
        return linkCount;
    }

    // The checks below undecode regions in stripes_ only, without a branch
    // (which regions are decoded, and which fail, is data: a branch per
    // region mispredicted ~11 k times per 780x580 decode in the three);
    // rejectSmallComponents writes the records' stripes. An undecoded region
    // has no score (weighEvidence scores decoded ends only).
    void rejectContradictedRegions()
    {
        const std::int32_t* score = ws_.componentSize.get();
        const int regionCount = ws_.regionCount;  // not reloaded after each store: the loop vectorises
        for (int v = 0; v < regionCount; ++v) stripes_[v] |= -static_cast<std::int32_t>(score[v] > 0);
    }

    // The window property, region by region: a region keeps its stripe only
    // if, following confirmed stripe edges (consecutive stripes in the right
    // direction whose symbol fits, error < tokenErrorLimit; same-stripe
    // neighbours pass through), window() edges of pattern evidence surround
    // it: run to the left + run to the right >= window(). Narrow patches
    // reached across a depth step by one chance match (the wall between the
    // slats of a fan) cannot show that much evidence.
    // A black stripe (all channels off) looks like a shadow: it is only
    // evidenced by light on both sides, so it also needs a confirmed stripe
    // edge on each side (a slat's shadow on the wall next to a lit stripe
    // otherwise decodes as the pattern's next black stripe and spreads
    // through the shadow over null edges).
    void rejectShortRuns(int listed)
    {
        const StripePattern& pattern = ws_.pattern;
        const int window = pattern.window();
        // The runs to the left and to the right, one byte each (window() <=
        // 13), in two arrays in the component sizes' storage (4 bytes per
        // region): the sweeps update them without a branch (max), where
        // the packed words' two tests mispredicted (which link extends a
        // run is data), and note a change by an OR.
        const int regionCount = ws_.regionCount;
        std::uint8_t* left = reinterpret_cast<std::uint8_t*>(ws_.componentSize.get());
        std::uint8_t* right = left + regionCount;
        std::fill(left, left + 2 * static_cast<std::ptrdiff_t>(regionCount), std::uint8_t{0});
        // The links weighEvidence() listed, less those of regions undecoded
        // since (in place, in edge order, without a branch: which remain is
        // data): the sweeps visit only them, without reading the edges again.
        std::int32_t* pairs = ws_.scratch.get();
        int linkCount = 0;
        for (int i = 0; i < listed; ++i) {
            const int lo = pairs[2 * i], hi = pairs[2 * i + 1];
            pairs[2 * linkCount] = lo;
            pairs[2 * linkCount + 1] = hi;
            linkCount += (stripes_[lo] >= 0) & (stripes_[hi >> 1] >= 0);
        }
        // The same updates in the same order as the scalar form
        //   if (newRight > right(lo)) { right(lo) = newRight; changed = true; }
        //   if (newLeft > left(hi)) { left(hi) = newLeft; changed = true; }
        // (a run only grows, so max() stores what the test stored).
        for (int sweep = 0; sweep < 2 * window + 2; ++sweep) {
            int changed = 0;  // nonzero when a run grew: the OR of new ^ old
            for (int i = 0; i < linkCount; ++i) {
                // (unsigned: the indices need no sign extension)
                const std::uint32_t lo = pairs[2 * i], hi = static_cast<std::uint32_t>(pairs[2 * i + 1]) >> 1;
                const int add = pairs[2 * i + 1] & 1;
                const int oldRight = right[lo], grownRight = std::max(oldRight, std::min(window, right[hi] + add));
                right[lo] = static_cast<std::uint8_t>(grownRight);
                const int oldLeft = left[hi], grownLeft = std::max(oldLeft, std::min(window, left[lo] + add));
                left[hi] = static_cast<std::uint8_t>(grownLeft);
                changed |= (grownRight ^ oldRight) | (grownLeft ^ oldLeft);
            }
            if (changed == 0) break;
        }
        for (int v = 0; v < regionCount; ++v) {
            const int stripe = stripes_[v];
            const bool unbounded = (pattern.color(std::max(stripe, 0)) == 0) & ((left[v] == 0) | (right[v] == 0));
            stripes_[v] = stripe | -static_cast<std::int32_t>((left[v] + right[v] < window) | unbounded);
        }
    }

    static float maxChannelRange(const Region& r) { return std::max({r.range[0], r.range[1], r.range[2]}); }

    void rejectSmallComponents()
    {
        // size[component + 1]: size[0] counts nothing, for the regions
        // never decoded (component -1). passCount + 1 <= regionCount: a pass
        // decodes at least two regions.
        std::int32_t* size = ws_.componentSize.get();
        std::fill(size, size + ws_.passCount + 1, 0);
        Region* regions = ws_.regions.get();
        const int regionCount = ws_.regionCount;
        for (int r = 0; r < regionCount; ++r) size[components_[r] + 1] += stripes_[r] >= 0;
        // The records hold the stripes the propagation gave, equal to
        // stripes_ then (a region has a component exactly when it was
        // decoded); the checks only undecode. So only the regions decoded
        // then and undecoded now are written (~1 700 of 7 000 at 780x580),
        // not every record (a store to each 64-byte record was a cache line
        // per region): listed first without a branch (which is data), in
        // place of the components read (the list's end never passes r).
        int decoded = 0, undecoded = 0;
        for (int r = 0; r < regionCount; ++r) {
            const int component = components_[r];
            const bool keep = (stripes_[r] >= 0) & (size[component + 1] >= ws_.params.minComponentRegions);
            stripes_[r] |= -static_cast<std::int32_t>(!keep);
            decoded += keep;
            components_[undecoded] = r;
            undecoded += !keep & (component >= 0);
        }
        for (int i = 0; i < undecoded; ++i) regions[components_[i]].stripe = -1;
        ws_.decodedRegions = decoded;
    }

    DecoderWorkspace& ws_;
    const EdgeFeature* features_;
    const float t_;
    const MatchScales scales_;
    const float alpha_, A_, beta_;
    // params.tokenErrorLimit for pushNeighbours' token test (the same
    // comparisons: leastFloatNotBelow; weighEvidence's limit is the
    // nearest float, as it always was).
    const float tokenErrorLimit_;
    std::int32_t* stripes_ = nullptr;  // the regions' stripes (run)
    std::int32_t* components_ = nullptr;  // and components, as the records' (run)
};

}  // namespace

void setFirstStepSymbols(DecoderWorkspace& ws)
{
    const StripePattern& pattern = ws.pattern;
    for (int seedSymbol = 0; seedSymbol < kSymbolCount; ++seedSymbol)
        for (bool left : {false, true}) {
            DecoderWorkspace::FirstStepSymbols& first = ws.firstStep[seedSymbol][left];
            first = {};
            // A candidate p is the path on stripes p, p + 1.
            for (int p : pattern.edgesWithSymbol(static_cast<SymbolCode>(seedSymbol))) {
                SymbolCode beyond;
                if (!symbolBeyond(pattern, left ? p : p + 1, left, beyond) || (first.seen >> beyond & 1)) continue;
                first.symbols[first.count++] = beyond;
                first.seen |= 1u << beyond;
            }
        }
}

void decodeStripes(DecoderWorkspace& ws) { Traversal(ws).run(); }

}  // namespace stria::pipeline
