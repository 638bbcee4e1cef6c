// Stage 4: the region adjacency graph.
//
// One vertex per superpixel, one edge per pair of superpixels that touch
// (4-neighbourhood, so the graph is planar and has at most 3V - 6 edges). Each
// border pixel pair adds to its edge: the count, the unit normal pointing from
// the smaller label to the larger one (their sum is the border's chord, used
// for the direction in fig. 5) and the image gradient split into the primary
// direction (across the stripes) and the secondary one (along them) for eq. 8.
// Edges are found through a hash table of label pairs, then laid out as
// compressed incidence lists for the traversal.
#include "pipeline/decoder/simd_graph.hpp"
#include "pipeline/decoder/workspace.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <type_traits>

namespace stria::pipeline {

// The definition of a border pair's gradient terms (the graph test's
// reference calls it); buildGraph gets the same floats from the kernels
// horizontalPairGradient and verticalPairGradient (simd.hpp), except in the
// first and last columns, which they do not reach.
PairGradient pairGradient(const FrameView& frame, int x, int y, bool horizontal, const cv::Vec2f& primary)
{
    const int w = frame.width, h = frame.height;
    const float px = primary[0], py = primary[1];
    const std::uint8_t* r0 = frame.row(y);
    PairGradient out;
    for (int c = 0; c < 3; ++c) {
        float gx, gy;
        if (horizontal) {
            const std::uint8_t* up = frame.row(std::max(y - 1, 0));
            const std::uint8_t* down = frame.row(std::min(y + 1, h - 1));
            gx = static_cast<float>(r0[3 * (x + 1) + c] - r0[3 * x + c]);
            gy = 0.25f * static_cast<float>(down[3 * x + c] - up[3 * x + c] + down[3 * (x + 1) + c] -
                                            up[3 * (x + 1) + c]);
        } else {
            const std::uint8_t* r1 = frame.row(y + 1);
            const int xl = 3 * std::max(x - 1, 0) + c, xr = 3 * std::min(x + 1, w - 1) + c;
            gy = static_cast<float>(r1[3 * x + c] - r0[3 * x + c]);
            gx = 0.25f * static_cast<float>(r0[xr] - r0[xl] + r1[xr] - r1[xl]);
        }
        out.primary += std::abs(gx * px + gy * py);
        out.secondary += std::abs(-gx * py + gy * px);
    }
    return out;
}

namespace {

// (hide, simd.hpp: constants and pointers made opaque keep a register in
// buildGraph's pair loops rather than being built again for each pair: a
// 64-bit constant is 2-4 instructions on AArch64, a movabs on x86-64;
// 780x580, x86-64: graph stage 11.10 -> 10.97 M instructions.)


// A border pair's labels as one word, q's high and p's low (addPair).
std::uint64_t labelPair(std::int32_t p, std::int32_t q)
{
    return std::uint64_t{static_cast<std::uint32_t>(q)} << 32 | static_cast<std::uint32_t>(p);
}
// The same for p and the label after it (a little-endian 8-byte load).
std::uint64_t labelPair(const std::int32_t* p)
{
    if constexpr (std::endian::native == std::endian::little) {
        std::uint64_t word;
        std::memcpy(&word, p, sizeof word);
        return word;
    } else {
        return labelPair(p[0], p[1]);
    }
}

// buildGraph's borderCount, normalX and normalY (bytes 8-15 of a GraphEdge)
// as one little-endian word while the pairs add to it: normalY is less by
// one where normalX < 0 (a borrow), which buildGraph gives back at the end.
static_assert(offsetof(GraphEdge, normalX) == offsetof(GraphEdge, borderCount) + 4 &&
              offsetof(GraphEdge, normalY) == offsetof(GraphEdge, borderCount) + 6);
void addCountAndNormal(GraphEdge& edge, std::uint64_t delta)
{
    static_assert(std::endian::native == std::endian::little);  // a big-endian target would swap the halves
    std::uint64_t word;
    std::memcpy(&word, &edge.borderCount, sizeof word);
    word += delta;
    std::memcpy(&edge.borderCount, &word, sizeof word);
}
// Below this count an edge's normal sums cannot have reached the +-32767
// where they saturate (|normal| <= count).
constexpr std::int32_t kSaturatingCount = 32767;

// An edge's key: its labels a and b (bytes 0-7 of a GraphEdge) as one
// little-endian word, b (the larger) high.
static_assert(offsetof(GraphEdge, a) == 0 && offsetof(GraphEdge, b) == 4);
std::uint64_t keyOf(const GraphEdge& edge)
{
    std::uint64_t key;
    std::memcpy(&key, &edge.a, sizeof key);
    return key;
}
void setKey(GraphEdge& edge, std::uint64_t key) { std::memcpy(&edge.a, &key, sizeof key); }

// buildGraph's hash table holds an edge's record as its offset in words
// (3 e: a GraphEdge is 3 words), which addresses the record without a
// multiply by 24 (x86-64: an index scaled by 8; AArch64: a shifted register).
// The offsets as std::size_t in buildGraph's loop (64 bits on 64-bit
// targets): no extension to 64 bits before each address (a 32-bit load from
// the table zero-extends for free).
static_assert(sizeof(GraphEdge) == 3 * sizeof(std::uint64_t));
constexpr std::size_t kEdgeWords = 3;
GraphEdge* recordAt(GraphEdge* edges, std::size_t words)
{
    return reinterpret_cast<GraphEdge*>(reinterpret_cast<char*>(edges) + sizeof(std::uint64_t) * words);
}
const GraphEdge* recordAt(const GraphEdge* edges, std::size_t words)
{
    return recordAt(const_cast<GraphEdge*>(edges), words);
}

// buildGraph's hash table of edge offsets by key; find gives the edge
// (its index) of a key, or -1 for a pair past the capacity.
constexpr std::uint64_t kHashMultiplier = 0x9e3779b97f4a7c15u;
struct EdgeTable {
    const std::int32_t* table;
    std::size_t size;
    int shift;
    const GraphEdge* edges;
    std::uint64_t multiplier = kHashMultiplier;
    std::uint64_t slot(std::uint64_t key) const { return key * multiplier >> shift; }
    std::int32_t find(std::uint64_t key) const
    {
        std::uint64_t at = slot(key);
        while (table[at] >= 0 && keyOf(*recordAt(edges, static_cast<std::uint32_t>(table[at]))) != key)
            at = (at + 1) & (size - 1);
        return table[at] < 0 ? -1 : table[at] / static_cast<std::int32_t>(kEdgeWords);
    }
};

// The normal sums of the edges of kSaturatingCount pairs or more, again:
// buildGraph's adds wrap there instead of saturating, so these take the
// reference's update (saturating, and staying there), pair by pair in
// buildGraph's order. Only a border wound through a large part of the frame
// has so many pairs: never in the benchmark's frames.
[[gnu::noinline]] void recountSaturatingNormals(DecoderWorkspace& ws, const EdgeTable& lookup)
{
    GraphEdge* edges = ws.edges.get();
    for (int e = 0; e < ws.edgeCount; ++e)
        if (edges[e].borderCount >= kSaturatingCount) edges[e].normalX = edges[e].normalY = 0;
    auto add = [&](std::int32_t p, std::int32_t q, bool horizontal) {
        if (p == q) return;
        const std::int32_t e = lookup.find(labelPair(std::min(p, q), std::max(p, q)));  // the larger high
        if (e < 0 || edges[e].borderCount < kSaturatingCount) return;
        std::int16_t& normal = horizontal ? edges[e].normalX : edges[e].normalY;
        if (normal > -32767 && normal < 32767) normal = static_cast<std::int16_t>(normal + (p < q ? 1 : -1));
    };
    const int w = ws.width, h = ws.height;
    for (int y = 0; y < h; ++y) {
        const std::int32_t* row = ws.labels.get() + static_cast<std::ptrdiff_t>(y) * w;
        for (int x = 0; x + 1 < w; ++x) add(row[x], row[x + 1], true);
        if (y + 1 < h)
            for (int x = 0; x < w; ++x) add(row[x], row[x + w], false);
    }
}

}  // namespace

std::size_t graphScratchEntries(std::size_t regions, std::size_t edges)
{
    // 2 entries per edge and 2 more (the traversal's share; the graph's
    // label pairs are in its edge records), then the graph's counter per
    // region; the traversal's stripes and components per region there.
    return 2 * regions + 2 * edges + 2;
}

std::size_t graphTableEntries(std::size_t regions, std::size_t edges)
{
    // At most half full: a power of two >= twice the edges there can be (a
    // planar graph has fewer than 3 per vertex).
    return std::bit_ceil(std::max<std::size_t>(2, 2 * std::min(edges, 3 * regions)));
}

// Cloned for x86-64-v3 and -v4 (STRIA_X86_CLONES, simd.hpp): the pair
// kernels' SSE2 intrinsics in VEX encoding (three-operand forms, no register
// copies; vpmovzxbw widens a load), shrx for the hash's shift (no reload of
// %cl per pair), blsr for the bit loops. The same floats: the project builds
// with -ffp-contract=off, so no multiply and add fuse. 780x580: graph stage
// 10.59 -> 9.25 M instructions per decode (the v3 clone, which callgrind runs).
STRIA_X86_CLONES void buildGraph(DecoderWorkspace& ws)
{
    const int w = ws.width, h = ws.height;
    const std::int32_t* label = ws.labels.get();

    // Edges by label pair: a hash table of edge indices (open addressing,
    // linear probing; in the order buffer, free from the regions stage to the
    // depth stage) and each edge's pair (its a and b, keyOf). At most half full
    // (graphTableEntries), a quarter where the buffer has room (it has for
    // the default capacities): a pair finds its edge, or the empty slot of a
    // new one, nearly always at the first probe, and whether the edge is new
    // (a fifth of the look-ups, in no pattern a branch predictor learns) is
    // selected, not branched on: the empty slot takes the next edge index,
    // whose record is cleared ahead. (A per-region list walk here cost one
    // mispredicted branch per look-up.)
    const std::size_t tableSize =
        std::min(std::bit_floor(ws.orderEntries), 2 * graphTableEntries(ws.regionCount, ws.maxEdges));
    const int shift = 64 - std::countr_zero(tableSize);
    std::int32_t* table = ws.pixelOrder;
    std::fill(table, table + tableSize, -1);
    // Below maxEdges only for non-planar label graphs (never half full).
    const std::int32_t capacity = static_cast<std::int32_t>(std::min<std::size_t>(ws.maxEdges, tableSize / 2));
    // Locals, not workspace fields, across the kernel calls: kept in
    // registers (the edge count is in every look-up's dependency chain).
    GraphEdge* edges = ws.edges.get();
    // The hash's multiplier hidden from GCC (hide), which otherwise built it
    // again for each pair (AArch64: mov and three movk).
    std::uint64_t multiplier = kHashMultiplier;
    hide(multiplier);
    const EdgeTable lookup{table, tableSize, shift, edges, multiplier};
    // The edges so far as words of records (kEdgeWords per edge, the
    // table's unit): edgeCount().
    std::size_t edgeWords = 0;
    auto edgeCount = [&] { return static_cast<std::int32_t>(edgeWords / kEdgeWords); };
    // Edge records are cleared ahead of the count, 64 at a time.
    constexpr std::int32_t kClearBlock = 64;
    std::int32_t cleared = 0;
    auto clearAhead = [&] {
        const std::int32_t end = std::min(cleared + kClearBlock, capacity);
        // GraphEdge{} is all zero bytes: a memset's wide stores, where
        // std::fill stored field by field.
        static_assert(std::is_trivially_copyable_v<GraphEdge>);
        std::memset(static_cast<void*>(edges + cleared), 0, sizeof(GraphEdge) * static_cast<std::size_t>(end - cleared));
        cleared = end;
    };
    clearAhead();
    // A pair's edge record. Unchecked (std::false_type), for a row that
    // cannot reach the capacity or the records not yet cleared (the
    // caller's test, once per row): no test. Checked, once full, the edge
    // of a key already there or, for a new one (ws.truncated), a record
    // nobody reads.
    GraphEdge overflow;
    auto edgeOf = [&](std::uint64_t key, auto checked) -> GraphEdge* {
        if constexpr (checked) {
            if (edgeCount() == capacity) [[unlikely]] {
                const std::int32_t e = lookup.find(key);
                ws.truncated |= e < 0;
                return e < 0 ? &overflow : edges + e;
            }
        }
        std::uint64_t slot = lookup.slot(key);
        // The key goes in ahead into the next free record (cleared, below
        // the capacity), and an empty slot (-1) reads as that record's
        // offset (the unsigned minimum: stored ones are below it), so the probe stops
        // at the edge or at the empty slot by one compare, and whether the
        // edge is new (a fifth of the look-ups, in no pattern a branch
        // predictor learns) is selected, not branched on (GCC 12 makes the
        // minimum a cmov with the signed count, a branch with an unsigned
        // one: check the mispredictions when changing it). The record's
        // other fields are only written once it is the pair's edge.
        const std::size_t next = edgeWords;
        setKey(*recordAt(edges, next), key);
        auto probe = [&] { return std::min<std::size_t>(static_cast<std::uint32_t>(table[slot]), next); };
        std::size_t e = probe();
        // A collision (the collision loop out of the way of the first
        // probe's: a jump less per pair). The edge found (or the new one)
        // then takes its home slot, and the home slot's edge moves to the
        // slot where the probe stopped: a border's pairs come row after row,
        // while the edge in its home slot is most often one whose border the
        // rows have left, so the edge's next look-ups find it at the first
        // probe. (Linear probing allows the swap: the slots from the moved
        // edge's own home to the probe's stop are all taken.) 780x580:
        // collisions 8.4 k -> 1.4 k per decode (of 118 k look-ups), each
        // nearly always a mispredicted branch; 1388x1038: 14.2 k -> 1.9 k.
        if (keyOf(*recordAt(edges, e)) != key) [[unlikely]] {
            do {
                slot = (slot + 1) & (tableSize - 1);
                e = probe();
            } while (keyOf(*recordAt(edges, e)) != key);
            // The home slot computed and read again (hide: GCC otherwise
            // kept the home slot or its first load in a register through
            // the pair loops for this rare store, which spilled one of the
            // loops' pointers: an instruction more per pair).
            std::uint64_t hidden = key;
            hide(hidden);
            const std::uint64_t home = lookup.slot(hidden);
            table[slot] = table[home];
            slot = home;
        }
        table[slot] = static_cast<std::int32_t>(e);
        // e <= next, new where equal: the next record is past e's then, and
        // else the same (a stored e is at most next - kEdgeWords).
        edgeWords = std::max(e + kEdgeWords, next);
        if constexpr (checked) {
            if (edgeCount() >= cleared) [[unlikely]] clearAhead();  // every 64 new edges (none once full)
        }
        return recordAt(edges, e);
    };

    // Adds border pair p-q (q right of p or below it) to its edge, given
    // its labels as one word, q's high and p's low (a horizontal pair's two
    // labels as they lie in memory). The edge's key, the larger label high
    // and the smaller low, is the larger of that word and its halves
    // swapped (the labels differ), and the word is the key where p has
    // the smaller label: a rotation, a compare and a select, without a
    // branch (which side has the smaller label is unpredictable).
    //
    // The count and the normal sums take one 64-bit add (addCountAndNormal):
    // 1 + sign << 32 (horizontal) or 1 + sign << 48 (vertical). A -1 added
    // to normalX borrows from normalY where normalX is 0 or less (the
    // fields' word is normalX + 65536 normalY, both signed), which the loop
    // after the pairs gives back. The normals saturate at +-32767 (and stay
    // there), which only an edge of 32767 pairs or more can reach: those
    // edges' normals are counted again after the loop
    // (recountSaturatingNormals), so that the adds here need no test.
    // The two words to add, by direction (PairDeltas): set once per row
    // and hidden from GCC (hide), which otherwise built them again for each
    // pair (the vertical pairs' 1 + 1 << 48: mov and movk on AArch64).
    struct PairDeltas {
        std::uint64_t positive, negative;
    };
    auto pairDeltas = [](int at) {
        PairDeltas deltas{std::uint64_t{1} + (std::uint64_t{1} << at), std::uint64_t{1} - (std::uint64_t{1} << at)};
        hide(deltas.positive);
        hide(deltas.negative);
        return deltas;
    };
    auto addPair = [&](std::uint64_t labels, const PairDeltas& deltas, const PairGradient& gradient, auto checked) {
        // The key and the delta selected by one compare, ahead of the
        // look-up (selected after it, GCC compared again: the flags do not
        // live across the look-up; 780x580: -0.15 M instructions).
        const std::uint64_t swapped = std::rotl(labels, 32);
        const bool positive = labels >= swapped;  // the normal from a to b points to +x / +y
        const std::uint64_t key = positive ? labels : swapped;
        const std::uint64_t delta = positive ? deltas.positive : deltas.negative;
        GraphEdge& edge = *edgeOf(key, checked);
        addCountAndNormal(edge, delta);
        edge.primaryGradient += gradient.primary;
        edge.secondaryGradient += gradient.secondary;
    };

    // The border pairs of each row in raster order, horizontal then
    // vertical. The pair kernels read 8 bytes from 3 x (vertical pairs also
    // from 3 x - 3): pairGradient takes the pairs they do not reach, at their
    // place in that order (a row's last horizontal pair; its first vertical
    // pair and last two), and the mask walks leave them out, so that they
    // test no column per pair. A local copy of the primary direction: the
    // kernels' broadcasts of it are hoisted (the edge sums' float stores
    // might alias the workspace's).
    const cv::Vec2f primary = ws.primary;
    // The kernels' weights: the folded ones (a multiply less per pair) in
    // the unchecked rows, which take them only where they give the same
    // floats (quarterFolds); else the rows take the checked look-ups (the
    // same edges, only slower) and the plain weights.
    const graph_kernels::PairWeights plain = graph_kernels::plainWeights(primary);
    const graph_kernels::PairWeights horizontalWeights = graph_kernels::horizontalFoldedWeights(primary);
    const graph_kernels::PairWeights verticalWeights = graph_kernels::verticalFoldedWeights(primary);
    const bool folds = graph_kernels::quarterFolds(primary);
    const std::uint16_t* const positions = ws.borderPositions;
    const std::int32_t* const starts = ws.borderStarts.get();
    const int lastH = w - 2;  // the last horizontal pair
    // Inlined (both variants) by force: called, its captures were read from
    // memory in the pair loops, and GCC's choice flipped with small changes
    // of the loop.
    auto addRow = [&](int y, auto checked) __attribute__((always_inline)) {
        constexpr bool kFolded = !decltype(checked)::value;
        const std::int32_t* row = label + static_cast<std::ptrdiff_t>(y) * w;
        const std::uint8_t* up = ws.frame.row(std::max(y - 1, 0));
        const std::uint8_t* pixels = ws.frame.row(y);
        const std::uint8_t* down = ws.frame.row(std::min(y + 1, h - 1));
        const PairDeltas horizontal = pairDeltas(32), vertical = pairDeltas(48);
        // The horizontal pairs from the regions stage's list of the row's
        // borders (ws.borderPositions, in increasing order), in one loop per
        // row; the reference is a walk of its masks (borderMask) by a
        // loop per 64-bit word, whose exit was mispredicted on most words
        // (with pointers to the word's column, hidden from GCC; here the
        // same count of instructions without them).
        if (lastH >= 0) {
            const std::uint16_t* border = positions + starts[y];
            const std::uint16_t* bordersEnd = positions + starts[y + 1];
            // The last pair (column lastH) by pairGradient, after the others.
            const bool last = border != bordersEnd && bordersEnd[-1] == lastH;
            bordersEnd -= last;
            for (; border != bordersEnd; ++border) {
                const std::size_t x = *border;
                addPair(labelPair(row + x), horizontal,
                        graph_kernels::horizontalPair<kFolded>(up, pixels, down, x,
                                                               kFolded ? horizontalWeights : plain),
                        checked);
            }
            if (last)
                addPair(labelPair(row + lastH), horizontal, pairGradient(ws.frame, lastH, y, true, primary), checked);
        }
        if (y + 1 < h) {
            auto verticalPair = [&](int x) {
                addPair(labelPair(row[x], row[x + w]), vertical, pairGradient(ws.frame, x, y, false, primary), checked);
            };
            if (row[0] != row[w]) verticalPair(0);
            // Columns 1 to w - 3.
            std::uint64_t first = ~std::uint64_t{1};
            for (int i0 = 0; i0 < w - 2; i0 += 64) {
                const std::int32_t* rowAt = row + i0;
                const std::int32_t* belowAt = rowAt + w;
                const std::uint8_t* pixelsAt = pixels + 3 * static_cast<std::ptrdiff_t>(i0);
                const std::uint8_t* downAt = down + 3 * static_cast<std::ptrdiff_t>(i0);
                // A whole word (all but a row's last) by the inline kernel,
                // its whole-word case only; the last one by the call.
                const int count = w - 2 - i0;
                const std::uint64_t mask = (count >= 64 ? graph_kernels::borderMask(rowAt, belowAt, 64)
                                                        : borderMask(rowAt, belowAt, count)) &
                                           first;
                for (std::uint64_t bits = mask; bits; bits &= bits - 1) {
                    const std::size_t x = lowestBit(bits);
                    addPair(labelPair(rowAt[x], belowAt[x]), vertical,
                            graph_kernels::verticalPair<kFolded>(pixelsAt, downAt, x, kFolded ? verticalWeights : plain),
                            checked);
                }
                first = ~std::uint64_t{0};
            }
            for (int x = std::max(w - 2, 1); x < w; ++x)
                if (row[x] != row[x + w]) verticalPair(x);
        }
    };
    // A row has fewer than 2 w pairs, so fewer new edges: where the capacity
    // leaves room for them, the records for them are cleared and the row
    // takes the unchecked look-ups (and the folded weights); else (only near
    // the capacity, or for a direction that does not fold) the checked ones.
    const std::int32_t rowEdges = 2 * w;
    for (int y = 0; y < h; ++y) {
        if (rowEdges <= capacity - edgeCount() && folds) {
            while (cleared < edgeCount() + rowEdges) clearAhead();
            addRow(y, std::false_type{});
        } else {
            addRow(y, std::true_type{});
        }
    }

    ws.edgeCount = edgeCount();

    // The incidence lists (CSR), each region's degree and then its next
    // list position counted in a compact array in the scratch
    // (graphScratchEntries), not in the 64-byte region records: those are
    // written once, in order, instead of being incremented at random 4
    // times per edge. (The counts and the lists in locals: the workspace's
    // fields were loaded again after each store.)
    Region* regions = ws.regions.get();
    const int regionCount = ws.regionCount;
    std::int32_t* adjacency = ws.adjacency.get();
    const std::int32_t edgeTotal = ws.edgeCount;
    std::int32_t* next = ws.scratch.get() + 2 * static_cast<std::ptrdiff_t>(ws.maxEdges) + 2;
    std::fill(next, next + regionCount, 0);
    bool saturating = false;
    for (int e = 0; e < edgeTotal; ++e) {
        const std::int32_t a = edges[e].a, b = edges[e].b;
        edges[e].normalY = static_cast<std::int16_t>(edges[e].normalY + (edges[e].normalX < 0));  // addPair's borrow
        saturating |= edges[e].borderCount >= kSaturatingCount;
        ++next[a];
        ++next[b];
    }
    if (saturating) [[unlikely]] recountSaturatingNormals(ws, lookup);
    std::int32_t offset = 0;
    for (int r = 0; r < regionCount; ++r) {
        const std::int32_t degree = next[r];
        regions[r].adjacencyBegin = offset;
        regions[r].degree = degree;
        next[r] = offset;
        offset += degree;
    }
    for (int e = 0; e < edgeTotal; ++e) {
        adjacency[next[edges[e].a]++] = e;
        adjacency[next[edges[e].b]++] = e;
    }
}

}  // namespace stria::pipeline
