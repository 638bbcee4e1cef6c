// Stage 2: superpixels by a watershed of the gradient magnitude.
//
// The watershed by steepest descent (tobogganing; Meijster & Roerdink,
// Bieniek & Moga 2000), in raster passes that stay near the pixel at hand:
// 1. each pixel points to its lowest 4-neighbour if that is strictly lower
//    (descentRow: NEON on ARM, vectorised by GCC elsewhere);
// 2. on a plateau that has a way down, the pixels without one point
//    breadth-first towards its lower border, so each drains to the nearest
//    (deterministic and geodesically fair, as a flooding FIFO splits it);
// 3. the plateaus without a way down are the regional minima: one basin
//    each, connected components by union-find, numbered in raster order of
//    their first pixel;
// 4. every other pixel takes the basin at the end of its arrows.
// Every pixel gets a label; there are no watershed lines (a border is any
// pair of 4-neighbours with different labels). With more than maxRegions
// minima, the lowest keep their basins, each other basin joins a neighbouring
// one and the frame is marked truncated.
//
// Speed: Meyer's flooding with a hierarchical queue, which this replaced,
// sorted the pixels by level and then wandered over the whole image at every
// level (cache misses, IPC about 0.5); here every pass reads rows in order
// and every arrow leads to a neighbour. Branches on data mispredict (flat
// pixels and runs of arrows come in runs of every length), so the passes
// avoid them: the minima are found on runs of flat pixels as bit masks,
// their pixels keep arrows to their runs' first pixels (so only those take
// a label one by one), the arrows along a row take their labels by a prefix
// scan of 4 labels per step (sweepRow), and only paths leading down are
// walked.
#include "pipeline/decoder/workspace.hpp"

#include "pipeline/decoder/simd.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cstring>
#include <limits>

#if defined(__SSE2__)
#include <emmintrin.h>
#elif defined(__ARM_NEON)
#include <arm_neon.h>
#endif

namespace stria::pipeline {

namespace {

// Scratch entries of the per-pixel codes and the wall row (bytes).
std::size_t codeEntries(std::size_t pixels, std::size_t width)
{
    return (pixels + width + 3) / 4;
}


// Bit 7 of byte k is set if pixel k of the 8 is flat (code bit 3: arrows
// are 0-7) and above level 0 (adding 0x7f to the level's low 7 bits, or its
// own bit 7, sets bit 7).
[[gnu::always_inline]] inline std::uint64_t raisedFlat(const std::uint8_t* codes, const std::uint8_t* levels)
{
    static_assert(std::endian::native == std::endian::little, "byte k of the word is pixel k");
    constexpr std::uint64_t kLow7 = 0x7f7f7f7f7f7f7f7full, kHigh = 0x8080808080808080ull;
    std::uint64_t c, l;
    std::memcpy(&c, codes, 8);
    std::memcpy(&l, levels, 8);
    return (c << 4) & (((l & kLow7) + kLow7) | l) & kHigh;
}

// Bit i set if code i of the span (at most 64) has bit 3 (kDescentFlat: in
// step 3 the flat pixels): 16 per movemask (bit 3 shifted to each byte's bit
// 7) on SSE2, 64 per byteMask64 on AArch64, else 8 per multiplication gathering
// the bits into a byte. (Inlined, as raisedFlat and runStart: the call took
// 6 instructions of the 25 per word.)
[[gnu::always_inline]] inline std::uint64_t bit3Word(const std::uint8_t* code, int span)
{
    static_assert(std::endian::native == std::endian::little, "byte k of the word is pixel k");
    std::uint64_t bits = 0;
    int x = 0;
#if defined(__SSE2__)
    if (span == 64) {  // all words but a row's last: 4 steps without bounds
        for (int i = 0; i < 4; ++i) {
            const __m128i c = _mm_loadu_si128(reinterpret_cast<const __m128i*>(code + 16 * i));
            bits |= std::uint64_t{static_cast<std::uint32_t>(_mm_movemask_epi8(_mm_slli_epi16(c, 4)))} << 16 * i;
        }
        return bits;
    }
    for (; x + 16 <= span; x += 16) {
        const __m128i c = _mm_loadu_si128(reinterpret_cast<const __m128i*>(code + x));
        bits |= std::uint64_t{static_cast<std::uint32_t>(_mm_movemask_epi8(_mm_slli_epi16(c, 4)))} << x;
    }
#elif defined(__aarch64__)
    if (span == 64) {  // all words but a row's last
        const uint8x16_t bit3 = vdupq_n_u8(8);
        return byteMask64(vtstq_u8(vld1q_u8(code), bit3), vtstq_u8(vld1q_u8(code + 16), bit3),
                          vtstq_u8(vld1q_u8(code + 32), bit3), vtstq_u8(vld1q_u8(code + 48), bit3));
    }
#endif
    for (; x + 8 <= span; x += 8) {
        std::uint64_t c;
        std::memcpy(&c, code + x, 8);
        bits |= (((c >> 3) & 0x0101010101010101ull) * 0x0102040810204080ull) >> 56 << x;
    }
    for (; x < span; ++x) bits |= std::uint64_t{code[x] >> 3 & 1u} << x;
    return bits;
}

// Root of a provisional label: roots are their own parents, the others have
// a smaller label. The first step is a load alone, without a branch (a root
// stays): a join's labels are roots or one step from one (780x580: 57 % and
// 42 %; 1388x1038: 35 % and 64 %), and the branch on which mispredicted in 1
// of 3 calls; the loop, for the rare longer paths, halves them.
[[gnu::always_inline]] inline std::int32_t findRoot(std::int32_t* parent, std::int32_t l)
{
    l = parent[l];
    while (parent[l] != l) l = parent[l] = parent[parent[l]];
    return l;
}

// A row's flat pixels as bits, 64 pixels per word (bit x % 64 of word x / 64).
struct RunWord {
    std::uint64_t flat = 0;
    std::uint64_t starts = 0;  // the first pixel of each run of flat pixels
    std::int32_t lastStart = 0;  // the last start in the words before (0 if none)
};

int runWords(int width) { return (width + 63) / 64; }

// The run words of two rows, in the scratch after the watershed's other
// entries (watershedScratchEntries), aligned.
RunWord* runWordsIn(std::int32_t* scratch, int width, int height)
{
    static_assert(alignof(RunWord) == 2 * alignof(std::int32_t));
    const std::size_t offset = codeEntries(static_cast<std::size_t>(width) * height, width) + width + 8;
    return reinterpret_cast<RunWord*>(scratch + offset + offset % 2);
}

// The first pixel of the run holding flat pixel x of the word at column x0
// (the last start at or before x; rarely one in the words before).
// through: bits 0 to x - x0 set, as bits ^ (bits - 1) when x is the lowest
// set bit of the bits a loop walks (cheaper than from x).
// (64-bit on x86-64: no sign extension of the index.)
[[gnu::always_inline]] inline std::ptrdiff_t runStart(const RunWord& word, std::ptrdiff_t x0, std::uint64_t through)
{
    const std::uint64_t before = word.starts & through;
    const std::ptrdiff_t inWord = x0 + 63 - std::countl_zero(before | 1);
    return before != 0 ? inWord : word.lastStart;  // a cmov (and-or masks took 3 more)
}

// A row of kUnresolved: 64 labels (8 stores of 32 bytes, 2 per 16 on SSE2) per
// step, the last step ending at the row's end over labels filled already, where
// std::fill took 8 per step (4 instructions per 8 labels on AVX2, 0.23 M per
// 780x580 decode). Inlined into each clone of computeWatershed.
[[gnu::always_inline]] inline void fillUnresolved(std::int32_t* row, int width)
{
    using Labels8 = std::int32_t __attribute__((vector_size(32)));
    constexpr Labels8 unresolved = Labels8{} + kUnresolved;
    constexpr int kStep = 64;
    if (width < kStep) {
        std::fill(row, row + width, kUnresolved);
        return;
    }
    auto block = [&](int x) {
        for (int i = 0; i < kStep; i += 8) std::memcpy(row + x + i, &unresolved, sizeof unresolved);
    };
    int x = 0;
    for (; x + kStep <= width; x += kStep) block(x);
    if (x < width) block(width - kStep);
}

// Step 3's minima codes in blocks of this many pixels.
constexpr int kMinimumBlock = 32;

// Steps of a walk down (computeWatershed, step 4) taken without a branch:
// 3 of 1-5 steps (the 780x580 frame's 18.3 k walks: 14 % take 1 step, 28 %
// 2, 27 % 3, 15 % 4, 8 % 5, 8 % more); 4 took 0.16 M instructions more per
// 780x580 decode for 3.7 k fewer mispredictions, no gain.
constexpr int kWalkSteps = 3;

// Root of a basin in the union-find of excess basins (path halving).
std::int32_t findBasin(std::int32_t* parent, std::int32_t b)
{
    while (parent[b] != b) b = parent[b] = parent[parent[b]];
    return b;
}

}  // namespace

namespace {

// Provisional labels (step 3) at most: a minimum's run starts at a flat
// pixel whose left neighbour is not flat, so a row has at most (width + 1) /
// 2 new minima, and one below a new minimum's first pixel (flat) is none: two
// rows hold at most width.
std::size_t maxProvisional(int width, int height)
{
    return static_cast<std::size_t>(height / 2) * width + (height % 2) * ((width + 1) / 2);
}

// A pixel index's sign bit (63; on 32-bit targets 31): a shift of a
// sign-extended label by it gives -1 for a negative one.
constexpr int kIndexSignShift = std::numeric_limits<std::ptrdiff_t>::digits;

// Step 3's numbering: each provisional label's number, a root's (in raster
// order, or over capacity the ~number set before, in place of the root's own
// label), another's that of its parent (a smaller label, numbered before),
// written at its first pixel too.
// Without a branch on roots (it mispredicted). A function of its own per
// case (within capacity, the usual one, no masks for it; and registers of its
// own: inside computeWatershed the loop reloaded 2 pointers from the stack),
// the parent loaded sign-extended (no extension of a 32-bit index): 16
// instructions per label instead of 19 (x86-64-v3; clones for BMI's andn).
template <bool kOverCapacity>
STRIA_X86_CLONES [[gnu::noinline]] void numberLabels(std::int32_t* parent, const std::int32_t* firstPixel,
                                                     std::int32_t* label, int provisional)
{
    for (std::ptrdiff_t l = 0, next = 0; l < provisional; ++l) {
        const std::ptrdiff_t up = parent[l];
        const std::ptrdiff_t root = kOverCapacity ? up >> kIndexSignShift : -std::ptrdiff_t{up == l};  // -1 for a root
        const std::ptrdiff_t number = kOverCapacity ? ~up : next;
        parent[l] = static_cast<std::int32_t>((number & root) | (parent[up & ~root] & ~root));
        label[firstPixel[l]] = parent[l];
        next -= root;
    }
}

// Step 4 of computeWatershed (below), the sweeps and walks of every row: a
// function of its own, with registers of its own (inside computeWatershed a
// change of the walk loop moved spills into step 3's loops: 0.12 M
// instructions more per 780x580 decode).
STRIA_X86_CLONES [[gnu::noinline]] void labelBasins(const std::uint8_t* code, std::int32_t* label,
                                                    std::uint64_t* unresolved, std::int32_t* positions, int w, int h)
{
    // The walks' step by a whole code (its arrow in bits 0-1): no masking
    // per step; and a label's sign as a 64-bit mask from its load sign
    // extended (no extension of a 32-bit one): 2 instructions less per step.
    // (Pixel indices in the walks as std::ptrdiff_t: no sign extension per step.)
    const std::array<std::ptrdiff_t, 4> step{-w, -1, 1, w};
    std::array<std::ptrdiff_t, 256> stepOf;
    for (int c = 0; c < 256; ++c) stepOf[c] = step[c & 3];
    const int words = runWords(w);
    for (int y = 0; y < h; ++y) {
        const std::uint8_t* rowCode = code + y * w;
        std::int32_t* row = label + y * w;
        sweepRow(rowCode, y > 0 ? row - w : row, row, w, unresolved);  // no arrow up in row 0
        // Only the words with unresolved pixels, by a mask of them per 64
        // words made without a branch (6 instructions a word): a test of
        // each word mispredicted on the empty ones (37 % of the words at
        // 780x580, 46 % at 1388x1038; 2.5 k mispredictions per 780x580
        // decode for 49 k instructions, 9.2 k for 91 k at 1388x1038).
        for (int k0 = 0; k0 < words; k0 += 64) {
            std::uint64_t nonEmpty = 0;
            for (std::ptrdiff_t k = std::min(64, words - k0) - 1; k >= 0; --k)
                nonEmpty = 2 * nonEmpty + (unresolved[k0 + k] != 0);
            // The unresolved pixels of those words as a list (appendBitPositions,
            // simd.hpp: 8 per word without a branch, where 92 % of the
            // non-empty words have at most 8, 3.8 on average; with 4, 70 %,
            // the branch beyond them mispredicted 1.6 k times more per 780x580
            // decode), walked in one loop, where a loop per word mispredicted
            // its exit on most words.
            std::int32_t* listEnd = positions;
            for (; nonEmpty != 0; nonEmpty &= nonEmpty - 1) {
                const int word = k0 + std::countr_zero(nonEmpty);
                listEnd = appendBitPositions<8>(unresolved[word], 64 * word, listEnd);
            }
            const std::ptrdiff_t rowStart = std::ptrdiff_t{y} * w;
            for (const std::int32_t* at = positions; at != listEnd; ++at) {
                // The first kWalkSteps steps without a branch (walks take
                // 1 to 5 steps, 3 on average; the branches on their ends
                // mispredicted, about 2 per walk): a walk that has ended
                // stays at its end, and the path's pixels are the steps'
                // own positions, labelled without walking the path again
                // (the basin written at the end too, where it is
                // already). Where a path crosses a run's first pixel with
                // a provisional label the basin replaces it, as that
                // row's sweep will along the pixel's arrow up. Without
                // branches the core overlaps the next walks with this
                // one's loads (often L1 misses: a step down is a row
                // away), as the two walks at a time this replaced did by
                // hand.
                std::array<std::ptrdiff_t, kWalkSteps + 1> path;
                path[0] = rowStart + *at;
                for (int k = 0; k < kWalkSteps; ++k) {
                    // (As a mask: GCC made a ternary a branch.)
                    // on: -1 while not final
                    const std::ptrdiff_t q = path[k], on = std::ptrdiff_t{label[q]} >> kIndexSignShift;
                    path[k + 1] = q + (stepOf[code[q]] & on);
                }
                std::ptrdiff_t end = path[kWalkSteps];
                while (label[end] < 0) end += stepOf[code[end]];  // the longer walks go on
                const std::int32_t basin = label[end];
                for (int k = 0; k < kWalkSteps; ++k) label[path[k]] = basin;
                for (std::ptrdiff_t r = path[kWalkSteps]; r != end; r += stepOf[code[r]]) label[r] = basin;
            }
        }
    }
}

}  // namespace

std::size_t watershedOrderEntries(int width, int height)
{
    return 2 * maxProvisional(width, height);
}

std::size_t watershedScratchEntries(int width, int height)
{
    // The codes and the wall, then a row's minima codes (room for a row of
    // int32 and 8 more), then the run words of two rows (after at most one entry to align
    // them; in step 4 the unresolved pixels' bits).
    return codeEntries(static_cast<std::size_t>(width) * height, width) + width + 8 + 1 +
           2 * runWords(width) * sizeof(RunWord) / sizeof(std::int32_t);
}

// x86-64: clones for AVX2 and AVX-512 too (STRIA_X86_CLONES): the loops GCC
// vectorises take 32 bytes per step, the bit loops BMI's tzcnt/blsr/shlx.
STRIA_X86_CLONES void computeWatershed(DecoderWorkspace& ws)
{
    const int w = ws.width, h = ws.height, n = w * h;
    const std::uint8_t* g = ws.gradient.get();
    std::int32_t* label = ws.labels.get();
    // Scratch: the codes, a row of 255 (the wall beyond the image border),
    // a row's minima codes (bytes), and the run words (runWordsIn), later a row's unresolved pixels as bits.
    auto* code = reinterpret_cast<std::uint8_t*>(ws.scratch.get());
    std::uint8_t* wall = code + n;
    std::fill(wall, wall + w, 255);

    // 1. Arrows down the steepest 4-neighbour step.
    for (int y = 0; y < h; ++y)
        descentRow(y > 0 ? g + (y - 1) * w : wall, g + y * w, y + 1 < h ? g + (y + 1) * w : wall, w, code + y * w);

    // 2. Plateaus with a lower border: arrows breadth-first from the border
    // inward, so every plateau pixel drains towards its nearest way down.
    // First the pixels next to a border pixel (raster order), then FIFO.
    std::int32_t* queue = ws.pixelOrder;
    [[maybe_unused]] std::int32_t* positions = ws.bitPositions.get();
    int tail = 0;
    auto seed = [&](int x, int y) {
        const int p = y * w + x;
        auto descends = [&](int q) { return g[q] == g[p] && code[q] < kPlateauArrow; };
        int direction = -1;
        if (y > 0 && descends(p - w)) direction = kDescentUp;
        else if (x > 0 && descends(p - 1)) direction = kDescentLeft;
        else if (x + 1 < w && descends(p + 1)) direction = kDescentRight;
        else if (y + 1 < h && descends(p + w)) direction = kDescentDown;
        if (direction < 0) return;
        code[p] = static_cast<std::uint8_t>(kPlateauArrow | direction);
        queue[tail++] = p;
    };
    // Flat pixels above level 0 (level 0 has no way down) are about 1 %:
    // they are found 64 or 16 (SSE2) or 8 at a time.
    for (int y = 0; y < h; ++y) {
        int x = 0;
#if defined(__SSE2__)
        const __m128i flat = _mm_set1_epi8(kDescentFlat), zero = _mm_setzero_si128();
        // 64 at a time, into a list of the row's positions
        // (appendBitPositions, simd.hpp: 2 without a branch, where 97 % of
        // the words have at most 2; a loop per word mispredicted its exit on
        // most words), then 16. Seed changes only the pixel it seeds, so the
        // masks taken before seeding stay valid.
        std::int32_t* listEnd = positions;
        for (; x + 64 <= w; x += 64) {
            std::uint64_t bits = 0;
            for (int i = 0; i < 4; ++i) {
                const __m128i c = _mm_loadu_si128(reinterpret_cast<const __m128i*>(code + y * w + x + 16 * i));
                const __m128i l = _mm_loadu_si128(reinterpret_cast<const __m128i*>(g + y * w + x + 16 * i));
                const auto raised = _mm_movemask_epi8(_mm_andnot_si128(_mm_cmpeq_epi8(l, zero), _mm_cmpeq_epi8(c, flat)));
                bits |= std::uint64_t{static_cast<std::uint32_t>(raised)} << 16 * i;
            }
            listEnd = appendBitPositions<2>(bits, x, listEnd);
        }
        for (const std::int32_t* at = positions; at != listEnd; ++at) seed(*at, y);
        for (; x + 16 <= w; x += 16) {
            const __m128i c = _mm_loadu_si128(reinterpret_cast<const __m128i*>(code + y * w + x));
            const __m128i l = _mm_loadu_si128(reinterpret_cast<const __m128i*>(g + y * w + x));
            for (unsigned bits = _mm_movemask_epi8(_mm_andnot_si128(_mm_cmpeq_epi8(l, zero), _mm_cmpeq_epi8(c, flat)));
                 bits != 0; bits &= bits - 1)
                seed(x + std::countr_zero(bits), y);
        }
#elif defined(__aarch64__)
        // 64 at a time: one test (the lanes' maximum) per 64 pixels, the
        // bits only where there are flat pixels. The bits are those of
        // raisedFlat (code bit 3, level above 0); seed changes only the
        // pixel it seeds, so the mask taken before seeding stays valid.
        const uint8x16_t bit3 = vdupq_n_u8(kDescentFlat);
        for (; x + 64 <= w; x += 64) {
            // 0xff where pixel x + i.. (16) is flat and above level 0.
            auto raised = [&, at = y * w + x](int i) {
                const uint8x16_t level = vld1q_u8(g + at + i);
                return vandq_u8(vtstq_u8(vld1q_u8(code + at + i), bit3), vtstq_u8(level, level));
            };
            const uint8x16_t m0 = raised(0), m1 = raised(16), m2 = raised(32), m3 = raised(48);
            if (vmaxvq_u8(vorrq_u8(vorrq_u8(m0, m1), vorrq_u8(m2, m3))) == 0) continue;
            for (std::uint64_t bits = byteMask64(m0, m1, m2, m3); bits != 0; bits &= bits - 1)
                seed(x + std::countr_zero(bits), y);
        }
#endif
        for (; x + 8 <= w; x += 8)
            for (std::uint64_t bits = raisedFlat(code + y * w + x, g + y * w + x); bits != 0; bits &= bits - 1)
                seed(x + std::countr_zero(bits) / 8, y);
        for (; x < w; ++x)
            if (code[y * w + x] == kDescentFlat && g[y * w + x] != 0) seed(x, y);
    }
    // (The queue holds a few thousand pixels: a division each is cheap.)
    for (int head = 0; head < tail; ++head) {
        const int p = queue[head], y = p / w, x = p - y * w;
        auto visit = [&](int q, std::uint8_t towardP) {
            if (code[q] != kDescentFlat || g[q] != g[p]) return;
            code[q] = kPlateauArrow | towardP;
            queue[tail++] = q;
        };
        if (y > 0) visit(p - w, kDescentDown);
        if (x > 0) visit(p - 1, kDescentRight);
        if (x + 1 < w) visit(p + 1, kDescentLeft);
        if (y + 1 < h) visit(p + w, kDescentUp);
    }

    // 3. The flat pixels left are regional minima: connected components by
    // union-find over provisional labels in raster order (adjacent flat
    // pixels are on one level), row by row on runs of flat pixels as bits, 64
    // pixels per word (branches on the runs' ends mispredicted): a run that
    // starts below a flat pixel takes the label of the run there, any other
    // starts a minimum (a provisional label, in raster order); where a run meets
    // another run above past its own start, their minima join. The labels
    // are written at the runs' first pixels only; every other pixel is
    // unresolved. Each flat pixel's code becomes kMinimumArrow | an arrow
    // left if its left neighbour is flat, else up if the upper one is, else
    // kDescentFlat (the only code with bit 3): step 4's sweeps follow those
    // arrows from the first pixels, so only the new minima's first pixels
    // take their basin by the union-find: the numbering below writes it
    // there, at the first pixel kept for each provisional label (a list in
    // raster order, where a loop over code bits per row mispredicted and
    // took 0.4 M instructions more per 780x580 decode).
    // (The order buffer: watershedOrderEntries.)
    std::int32_t* parent = ws.pixelOrder;
    std::int32_t* firstPixel = parent + maxProvisional(w, h);  // of each provisional label
    auto* minimumCode = reinterpret_cast<std::uint8_t*>(ws.scratch.get() + codeEntries(n, w));
    const int words = runWords(w);
    RunWord* runs = runWordsIn(ws.scratch.get(), w, h);
    RunWord* runsAbove = runs + words;
    std::fill(runsAbove, runsAbove + words, RunWord{});  // above row 0: none
    int provisional = 0, joined = 0;
    // The lists of a row's positions, each of at most half a row's words' bits
    // (no two adjacent pixels start runs, nor join them) and a group's junk
    // entries after (bitPositionEntries).
    const std::ptrdiff_t listEntries = 32 * words + 8;
    std::int32_t* freshPositions = ws.bitPositions.get();
    std::int32_t* startPositions = freshPositions + listEntries;
    std::int32_t* joinPositions = startPositions + listEntries;
    // The codes by byte masks, which the compiler vectorises (ternaries
    // became branches).
    auto mask = [](bool condition) { return static_cast<std::uint8_t>(-static_cast<int>(condition)); };
    for (int y = 0; y < h; ++y) {
        std::uint8_t* rowCode = code + y * w;
        std::int32_t* row = label + y * w;
        // The row's pixels start unresolved: filled row by row, so the first
        // pixels' labels go to lines still in the L1 cache (a fill of the
        // whole image first left them to miss: 76 -> 49 k D1 write misses
        // per 780x580 decode in callgrind).
        fillUnresolved(row, w);
        // Row 0: nothing above; the label read there for a new minimum unused.
        const std::int32_t* labelAbove = y > 0 ? row - w : row;
        std::uint64_t carry = 0, carryAbove = 0;  // bit 63 of the previous word
        std::int32_t last = 0;
        std::int32_t *freshEnd = freshPositions, *startsEnd = startPositions, *joinsEnd = joinPositions;
        for (int k = 0; k < words; ++k) {
            const int x0 = 64 * k;
            // Code kDescentFlat, the only one with bit 3.
            const std::uint64_t flat = bit3Word(rowCode + x0, std::min(64, w - x0));
            const std::uint64_t left = flat << 1 | carry, above = runsAbove[k].flat,
                                aboveLeft = above << 1 | carryAbove;
            carry = flat >> 63;
            carryAbove = above >> 63;
            RunWord& word = runs[k];
            word.flat = flat;
            word.starts = flat & ~left;
            word.lastStart = last;
            if (word.starts != 0) last = x0 + 63 - std::countl_zero(word.starts);
            // The three kinds of pixels' positions (the lists below).
            const std::uint64_t fresh = word.starts & ~above;
            freshEnd = appendBitPositions<4>(fresh, x0, freshEnd);
            startsEnd = appendBitPositions<8>(word.starts & ~fresh, x0, startsEnd);
            joinsEnd = appendBitPositions<4>(flat & left & above & ~aboveLeft, x0, joinsEnd);
        }
        // The new minima take the next provisional labels (in raster order),
        // the other runs the label of the run above their first pixel, then
        // the joins: three loops on the three kinds of pixels (no branch
        // between them), each over the row's list of their positions
        // (appendBitPositions, simd.hpp; a loop per word mispredicted its exit
        // on most words, 3 per word). The groups fit the bits per word
        // (780x580 and 1388x1038): new minima 1.8 and 1.7 on average, 95 %
        // at most 4; other starts 5.9 and 5.1, 89 % and 98 % at most 8; joins
        // 1.0 and 2.0, 99 % at most 4. Callgrind per decode: 780x580 -20 k
        // mispredictions for +0.69 M instructions, 1388x1038 -70 k for +2.1 M.
        for (const std::int32_t* at = freshPositions; at != freshEnd; ++at) {
            const int x = *at;
            parent[provisional] = provisional;
            firstPixel[provisional] = y * w + x;
            row[x] = ~provisional++;
        }
        for (const std::int32_t* at = startPositions; at != startsEnd; ++at) {
            const std::ptrdiff_t x = *at;
            const RunWord& word = runsAbove[x >> 6];
            // The starts above at or before x in its word.
            const std::uint64_t before = word.starts & (~std::uint64_t{0} >> (63 - (x & 63)));
            const std::int32_t* start = before != 0
                ? labelAbove + (x | 63) - static_cast<unsigned>(std::countl_zero(before))
                : labelAbove + word.lastStart;
            row[x] = *start;
        }
        for (const std::int32_t* at = joinPositions; at != joinsEnd; ++at) {
            const std::ptrdiff_t x = *at, x0 = x & ~std::ptrdiff_t{63};
            const std::uint64_t through = ~std::uint64_t{0} >> (63 - (x & 63));  // bits 0 to x - x0
            const std::int32_t a = findRoot(parent, ~row[runStart(runs[x >> 6], x0, through)]),
                               b = findRoot(parent, ~labelAbove[runStart(runsAbove[x >> 6], x0, through)]);
            // The larger root joins the smaller, without a branch on a !=
            // b (where a == b, parent[a] = a as it was: with findRoot's
            // branches gone, which had foretold it, that branch
            // mispredicted 19 k times per 1388x1038 decode) nor on a < b
            // (the smaller hidden by hide, simd.hpp, and the larger from
            // it: GCC otherwise branched, 1 in 2 mispredicted).
            std::int32_t smaller = std::min(a, b);
            hide(smaller);
            parent[a ^ b ^ smaller] = smaller;
            joined += a != b;
        }
        // Row 0: the wall above (never a minimum).
        const std::uint8_t* codeAbove = y > 0 ? rowCode - w : wall;
        auto minimumAbove = [&](int x) { return (codeAbove[x] & 0xf0) == kMinimumArrow; };
        minimumCode[0] = rowCode[0] != kDescentFlat ? rowCode[0]
                         : minimumAbove(0)          ? kMinimumArrow | kDescentUp
                                                    : kMinimumArrow | kDescentFlat;
        auto minimumCodes = [&](int x) {
            const std::uint8_t flat = mask(rowCode[x] == kDescentFlat), up = mask(minimumAbove(x)),
                               left = mask(rowCode[x - 1] == kDescentFlat);
            const std::uint8_t arrow = (left & kDescentLeft) | (~left & ~up & kDescentFlat);
            minimumCode[x] = (flat & (kMinimumArrow | arrow)) | (~flat & rowCode[x]);
        };
        // In blocks of a fixed length, the last one ending at the row's end
        // over codes done already (the same again), where a loop to w had a
        // scalar tail that mispredicted; ivdep: the buffers do not overlap.
        auto block = [&](int x0) {
#pragma GCC ivdep
            for (int i = 0; i < kMinimumBlock; ++i) minimumCodes(x0 + i);
        };
        int x = 1;
        if (w > kMinimumBlock) {
            for (; x + kMinimumBlock <= w; x += kMinimumBlock) block(x);
            if (x < w) block(w - kMinimumBlock);
            x = w;
        }
        for (; x < w; ++x) minimumCodes(x);
        std::memcpy(rowCode, minimumCode, w);
        std::swap(runs, runsAbove);
    }
    const int minima = provisional - joined;

    // Basin numbers in raster order of each minimum's first pixel. Over
    // capacity, the lowest minima keep theirs (raster order within the
    // threshold level) and the rest are numbered from maxRegions on: then
    // the roots' numbers are set first, as ~number.
    const bool overCapacity = minima > ws.maxRegions;
    if (overCapacity) {
        std::array<int, 256> count{};
        for (int l = 0; l < provisional; ++l)
            if (parent[l] == l) ++count[g[firstPixel[l]]];
        int threshold = 0, kept = 0;
        for (; kept + count[threshold] <= ws.maxRegions; ++threshold) kept += count[threshold];
        int atThreshold = ws.maxRegions - kept, keptCount = 0, excessCount = 0;
        for (int l = 0; l < provisional; ++l) {
            if (parent[l] != l) continue;
            const int level = g[firstPixel[l]];
            const bool keep = level < threshold || (level == threshold && atThreshold-- > 0);
            parent[l] = ~(keep ? keptCount++ : ws.maxRegions + excessCount++);
        }
    }
    // Each label's number: a root's (in raster order, or the one set above),
    // another's that of its parent, a smaller label numbered before. Without
    // a branch on roots (it mispredicted): numberLabels.
    if (overCapacity) numberLabels<true>(parent, firstPixel, label, provisional);
    else numberLabels<false>(parent, firstPixel, label, provisional);

    // 4. Every pixel takes the basin at the end of its arrows, row by row
    // from the top (the row above is labelled; the new minima's first pixels
    // hold their basins already): a sweep to the right copies the
    // labels along arrows up and left, one to the left those along arrows
    // right (a run of arrows ends at a pixel with an arrow up, a minimum's
    // first pixel or an arrow down, never at one against it), without a
    // branch (sweepRow). What remains leads down: those pixels, marked in bit
    // masks by the last sweep, walk to a labelled pixel and label the path on
    // the way back (the first kWalkSteps steps without a branch). A walk
    // ends at a path labelled before or, in a row below, at a new minimum's
    // first pixel: in a minimum it follows the runs' arrows up and left,
    // through the first pixels of the runs below another run, whose
    // provisional labels (~label) are negative like kUnresolved, so a walk
    // tells a final label by its sign alone and reads no union-find
    // (labelBasins, above).
    // The row's unresolved pixels as bits (sweepRow), in the run words' place.
    auto* unresolved = reinterpret_cast<std::uint64_t*>(runs);
    labelBasins(code, label, unresolved, ws.bitPositions.get(), w, h);

    // 5. Over capacity: each excess basin joins a neighbouring one, chains of
    // excess basins too, in one raster sweep over 4-neighbour pairs (a set
    // still without a kept basin after the sweep would have no neighbour
    // outside it, so it would be the whole image, which holds basin 0).
    ws.regionCount = std::min(minima, ws.maxRegions);
    if (minima <= ws.maxRegions) return;
    ws.truncated = true;
    std::int32_t* basin = ws.pixelOrder;
    for (int b = 0; b < minima; ++b) basin[b] = b;
    auto join = [&](int p, int q) {
        if (label[p] == label[q]) return;
        const std::int32_t a = findBasin(basin, label[p]), b = findBasin(basin, label[q]);
        if (std::max(a, b) >= ws.maxRegions) basin[std::max(a, b)] = std::min(a, b);
    };
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            if (x + 1 < w) join(y * w + x, y * w + x + 1);
            if (y + 1 < h) join(y * w + x, y * w + x + w);
        }
    for (int p = 0; p < n; ++p) label[p] = findBasin(basin, label[p]);
}

}  // namespace stria::pipeline
