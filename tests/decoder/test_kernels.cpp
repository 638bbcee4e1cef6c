// The decoder's fast kernels against their scalar references, exactly: the
// gradient row (NEON on ARM, int16 lanes elsewhere) on random rows and
// simulator frames, the steepest-descent watershed (its row kernel NEON on
// ARM) against a plain scalar writing of the same algorithm, label for label,
// on simulator frames, noise, terraces and images 1-2 pixels wide or high,
// the region colours (pixels sorted by label, medians by a bitwise search)
// against the nth_element medians they replaced, with the median kernel
// (NEON on ARM) against a histogram, and the region graph against a
// map-based construction, with its border mask and pair gradient kernels
// against scalar references and pairGradient.
#include "hal/sim/scene/scene.hpp"
#include "pipeline/decoder/simd.hpp"
#include "pipeline/decoder/symbol_error.hpp"
#include "pipeline/decoder/workspace.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <deque>
#include <limits>
#include <map>
#include <numeric>
#include <random>
#include <vector>

namespace stria::pipeline {
namespace {

cv::Mat renderFrame(hal::sim::SceneKind kind, hal::sim::Albedo albedo, double noise)
{
    const hal::sim::SimRig rig = hal::sim::desktopRig();
    hal::sim::RenderSettings settings;
    settings.noiseSigma = noise;
    hal::sim::Rendering out;
    if (!hal::sim::SceneRenderer(rig).render(hal::sim::makeScene(kind, rig, albedo, 3), settings, out)) return {};
    return out.image;
}

cv::Mat randomFrame(int width, int height, unsigned seed)
{
    cv::Mat frame(height, width, CV_8UC3);
    std::mt19937 rng(seed);
    for (int y = 0; y < height; ++y)
        for (int i = 0; i < 3 * width; ++i) frame.ptr(y)[i] = static_cast<std::uint8_t>(rng());
    return frame;
}

// Rows of the fast kernel that differ from the reference, over both along directions.
int gradientRowsDiffering(const cv::Mat& frame)
{
    const int w = frame.cols, h = frame.rows;
    std::vector<std::uint8_t> magnitude(w), refMagnitude(w);
    std::vector<std::int16_t> lanes(12 * static_cast<std::size_t>(w));
    int differing = 0;
    for (bool alongY : {false, true})
        for (int y = 0; y < h; ++y) {
            const std::uint8_t* up = frame.ptr(std::max(y - 1, 0));
            const std::uint8_t* down = frame.ptr(std::min(y + 1, h - 1));
            // Each row's histogram alone, so that a difference counts once.
            AlongCounts along{}, refAlong{};
            gradientRow(up, frame.ptr(y), down, w, alongY, magnitude.data(), along, lanes.data());
            gradientRowReference(up, frame.ptr(y), down, w, alongY, refMagnitude.data(), refAlong);
            differing += magnitude != refMagnitude || along != refAlong;
        }
    return differing;
}

TEST(DecoderKernels, GradientRowMatchesReferenceOnRandomRowsOfEveryWidth)
{
    // Widths around the 16-pixel NEON block and the 3-pixel minimum, full
    // byte range (differences up to +-1020 before the /4).
    for (int width : {1, 2, 3, 4, 16, 17, 18, 19, 33, 47, 64, 781})
        EXPECT_EQ(gradientRowsDiffering(randomFrame(width, 5, static_cast<unsigned>(width))), 0) << "width " << width;
    cv::Mat extremes(3, 40, CV_8UC3);
    for (int y = 0; y < 3; ++y)
        for (int i = 0; i < 120; ++i) extremes.ptr(y)[i] = ((i / 3 + y) % 2) ? 255 : 0;
    EXPECT_EQ(gradientRowsDiffering(extremes), 0);
}

TEST(DecoderKernels, GradientRowMatchesReferenceOnSimulatorFrames)
{
    // One frame per test: rendering dominates the run time under qemu.
    const cv::Mat frame = renderFrame(hal::sim::SceneKind::TexturedRelief, hal::sim::Albedo::Photo, 4);
    ASSERT_FALSE(frame.empty());
    EXPECT_EQ(gradientRowsDiffering(frame), 0);
}

// Window samples of projectedGradientWindows unequal to the reference's
// (-infinity outside the row): batches of 1-40 windows at random positions,
// some cut by either end of the row, in both channel orders the decoder
// uses and one it does not (the generic path).
int projectedGradientsDiffering(const cv::Mat& frame, const cv::Matx33f& m, std::mt19937& rng)
{
    std::uniform_real_distribution<float> unit(-1, 1);
    constexpr float kOutside = -std::numeric_limits<float>::infinity();
    int differing = 0;
    for (const std::array<int, 3> rgbOffset :
         {std::array<int, 3>{2, 1, 0}, std::array<int, 3>{0, 1, 2}, std::array<int, 3>{1, 2, 0}})
        for (int y = 0; y < frame.rows; ++y) {
            const int count = 1 + static_cast<int>(rng() % 40);
            std::vector<std::int32_t> firsts(count);
            std::vector<cv::Vec3f> weights(count);
            for (int j = 0; j < count; ++j) {
                firsts[j] = static_cast<int>(rng() % static_cast<unsigned>(frame.cols + 12)) - 10;
                weights[j] = cv::Vec3f(unit(rng), unit(rng), unit(rng));
            }
            std::vector<std::array<float, kWindowSamples + 1>> fast(count);
            projectedGradientWindows(frame.ptr(y), frame.cols, firsts.data(), weights.data(), count, rgbOffset, m,
                                     fast.data());
            for (int j = 0; j < count; ++j)
                for (int k = 0; k < kWindowSamples; ++k) {
                    const int i = firsts[j] + k;
                    float reference = kOutside;
                    if (i >= 0 && i <= frame.cols - 2)
                        projectedGradientsReference(frame.ptr(y), i, 1, rgbOffset, m, weights[j], &reference);
                    differing += fast[j][k] != reference;
                }
        }
    return differing;
}

TEST(DecoderKernels, EdgeLocationGradientsEqualReferenceOnRandomRows)
{
    std::mt19937 rng(5);
    // The simulator's crosstalk inverted, and the identity.
    const cv::Matx33f crosstalk(0.9f, 0.08f, 0.02f, 0.1f, 0.8f, 0.1f, 0.03f, 0.12f, 0.85f);
    const cv::Mat noise = randomFrame(200, 40, 9);
    EXPECT_EQ(projectedGradientsDiffering(noise, crosstalk.inv(), rng), 0);
    EXPECT_EQ(projectedGradientsDiffering(noise, cv::Matx33f::eye(), rng), 0);
}

TEST(DecoderKernels, EdgeLocationGradientsEqualReferenceOnSimulatorFrame)
{
    std::mt19937 rng(6);
    const cv::Matx33f crosstalk(0.9f, 0.08f, 0.02f, 0.1f, 0.8f, 0.1f, 0.03f, 0.12f, 0.85f);
    const cv::Mat relief = renderFrame(hal::sim::SceneKind::TexturedRelief, hal::sim::Albedo::Photo, 4);
    ASSERT_FALSE(relief.empty());
    EXPECT_EQ(projectedGradientsDiffering(relief, crosstalk.inv(), rng), 0);
}

// Region medians whose fast selection differs from the reference: every
// count up to 70 (around the 4-pixel blocks, and the tail alone) and a few
// up to 40000 (past the 255 pixels the byte-lane search takes, the 1020 of
// the 16-bit lanes' search, the 64-block steps of the chunks' loop and the
// 254 blocks of one chunk), of random bytes, of
// few distinct values (ties at the median) and of the extremes 0 and 255.
// Each region's pixels are followed by kRegionPad entries of the value 0
// (kRegionByteBias stored), as the kernels require.
int regionMediansDiffering(unsigned seed)
{
    std::mt19937 rng(seed);
    std::vector<std::uint32_t> pixels(40000 + kRegionPad);
    int differing = 0;
    constexpr int stride = 255 + kRegionPad;
    std::vector<std::uint32_t> other(3 * stride);
    auto pad = [](std::uint32_t* end) { std::fill(end, end + kRegionPad, kRegionByteBias * 0x01010101u); };
    auto compare = [&](int count) {
        pad(pixels.data() + count);
        differing += channelMedians(pixels.data(), count) != channelMediansReference(pixels.data(), count);
        // The kernel for four regions: this one, then three of 1-255 random
        // pixels in the second buffer.
        const std::array<int, 4> counts{count, 1 + (count * 37) % 255, 1 + count % 16, 255 - count % 255};
        const std::array<const std::uint32_t*, 4> regions{pixels.data(), other.data(), other.data() + stride,
                                                          other.data() + 2 * stride};
        for (std::uint32_t& p : other) p = rng();
        for (int j = 1; j < 4; ++j) pad(other.data() + stride * (j - 1) + counts[j]);
        const auto medians = channelMediansOfFour(regions, counts);
        for (int j = 0; j < 4; ++j) {
            const std::array<std::uint8_t, 3> v = channelMediansReference(regions[j], counts[j]);
            differing += medians[j] != static_cast<std::uint32_t>(v[0] | v[1] << 8 | v[2] << 16);
        }
        if (count > 255) return;
        // The kernel for four regions of as many blocks: this one, then three
        // of random counts with the same (count + 3) / 4.
        const int first = count - (count - 1) % 4;  // 1, 5, 9, ..: the block count's smallest
        const std::array<int, 4> alike{count, first + static_cast<int>(rng() % 4), first + static_cast<int>(rng() % 4),
                                       first + static_cast<int>(rng() % 4)};
        std::array<int, 4> clamped = alike;
        for (int j = 1; j < 4; ++j) {
            clamped[j] = std::min(alike[j], 255);
            pad(other.data() + stride * (j - 1) + clamped[j]);
        }
        const auto alikeMedians = channelMediansOfFourAlike(regions, clamped);
        for (int j = 0; j < 4; ++j) {
            const std::array<std::uint8_t, 3> v = channelMediansReference(regions[j], clamped[j]);
            differing += alikeMedians[j] != static_cast<std::uint32_t>(v[0] | v[1] << 8 | v[2] << 16);
        }
    };
    for (int count : {1, 2, 3, 4, 5, 63, 64, 65, 252, 255, 256, 257, 511, 512, 516, 771, 1016, 1019, 1020, 1021,
                      1024, 2040, 2041, 3000, 32767, 32768, 40000})
        for (int kind = 0; kind < 3; ++kind) {
            for (int i = 0; i < count; ++i) {
                const std::uint32_t v = rng();
                pixels[i] = kind == 0 ? v : kind == 1 ? 0x64646464u + (v & 0x01010101u) : (v & 0x01010101u) * 255;
            }
            compare(count);
        }
    for (int count = 1; count <= 70; ++count)
        for (int trial = 0; trial < 20; ++trial) {
            for (int i = 0; i < count; ++i) pixels[i] = rng();
            compare(count);
        }
    return differing;
}

TEST(DecoderKernels, RegionMediansMatchReference)
{
    EXPECT_EQ(regionMediansDiffering(7u), 0);
    // The reference itself: byte k's value at index count / 2 of the sorted
    // (the bytes stored as value ^ kRegionByteBias).
    std::array<std::uint32_t, 6> pixels{0x000109u, 0x010203u, 0x0203c8u, 0x030403u, 0x040507u, 0x0506ffu};
    for (std::uint32_t& p : pixels) p ^= kRegionByteBias * 0x010101u;
    EXPECT_EQ(channelMediansReference(pixels.data(), 6), (std::array<std::uint8_t, 3>{9, 4, 3}));
    EXPECT_EQ(channelMediansReference(pixels.data(), 5), (std::array<std::uint8_t, 3>{7, 3, 2}));
    EXPECT_EQ(channelMediansReference(pixels.data(), 1), (std::array<std::uint8_t, 3>{9, 1, 0}));
}

// Border masks and border pair gradients that differ (bitwise) from the
// references: every count of a mask block on random label rows with few
// labels, every pair the pair kernels reach on the frame, both directions.
int graphKernelsDiffering(const cv::Mat& frame, unsigned seed)
{
    const int w = frame.cols, h = frame.rows;
    std::mt19937 rng(seed);
    std::vector<std::int32_t> labels(130);
    int differing = 0;
    for (int count = 0; count <= 64; ++count) {
        for (std::int32_t& l : labels) l = static_cast<std::int32_t>(rng() % 3);
        differing += borderMask(labels.data(), labels.data() + 1, count) !=
                     borderMaskReference(labels.data(), labels.data() + 1, count);
        differing += borderMask(labels.data(), labels.data() + 65, count) !=
                     borderMaskReference(labels.data(), labels.data() + 65, count);
    }
    const FrameView view{frame.data, w, h, static_cast<std::ptrdiff_t>(frame.step), PixelFormat::Bgr8};
    const cv::Vec2f primary(0.8f, -0.6f);
    auto equal = [](const PairGradient& a, const PairGradient& b) {
        return a.primary == b.primary && a.secondary == b.secondary;
    };
    for (int y = 0; y < h; ++y)
        for (int x = 0; x + 2 < w; ++x) {
            differing += !equal(horizontalPairGradient(frame.ptr(std::max(y - 1, 0)), frame.ptr(y),
                                                       frame.ptr(std::min(y + 1, h - 1)), x, primary),
                                pairGradient(view, x, y, true, primary));
            if (x > 0 && y + 1 < h)
                differing += !equal(verticalPairGradient(frame.ptr(y), frame.ptr(y + 1), x, primary),
                                    pairGradient(view, x, y, false, primary));
        }
    return differing;
}

TEST(DecoderKernels, GraphKernelsMatchReferenceOnRandomAndSimulatorFrames)
{
    // Full byte range (differences up to +-1020 before the quarter), and the
    // texture and noise of a simulator frame.
    EXPECT_EQ(graphKernelsDiffering(randomFrame(37, 9, 21), 3u), 0);
    const cv::Mat frame = renderFrame(hal::sim::SceneKind::TexturedRelief, hal::sim::Albedo::Photo, 4);
    ASSERT_FALSE(frame.empty());
    EXPECT_EQ(graphKernelsDiffering(frame, 4u), 0);
}

// The watershed by steepest descent written plainly: an arrow to the lowest
// strictly lower 4-neighbour (ties up, left, right, down); pixels of a plateau
// without one take an arrow breadth-first from the plateau's lower border
// (first the pixels next to it, in raster order, then FIFO); the remaining
// flat pixels are regional minima, found by flood fill and numbered in raster
// order of their first pixel, the first maxRegions in (level, raster) order
// kept when over capacity and the rest numbered from maxRegions on; each pixel
// takes the minimum at the end of its arrows; over capacity, one raster sweep
// over 4-neighbour pairs joins each set of basins without a kept one to its
// neighbour (the larger root to the smaller).
int referenceWatershed(const std::uint8_t* g, int w, int h, int maxRegions, std::vector<std::int32_t>& label)
{
    const int n = w * h;
    auto neighbours = [&](int p) {  // up, left, right, down; -1 outside the image
        const int x = p % w, y = p / w;
        return std::array<int, 4>{y > 0 ? p - w : -1, x > 0 ? p - 1 : -1, x + 1 < w ? p + 1 : -1,
                                  y + 1 < h ? p + w : -1};
    };
    std::vector<int> next(n, -1);
    for (int p = 0; p < n; ++p) {
        int lowest = g[p];
        for (int q : neighbours(p))
            if (q >= 0 && g[q] < lowest) {
                lowest = g[q];
                next[p] = q;
            }
    }
    const std::vector<int> descent = next;
    std::deque<int> queue;
    for (int p = 0; p < n; ++p)
        if (next[p] < 0)
            for (int q : neighbours(p))
                if (q >= 0 && g[q] == g[p] && descent[q] >= 0) {
                    next[p] = q;
                    queue.push_back(p);
                    break;
                }
    for (; !queue.empty(); queue.pop_front())
        for (int q : neighbours(queue.front()))
            if (q >= 0 && g[q] == g[queue.front()] && next[q] < 0) {
                next[q] = queue.front();
                queue.push_back(q);
            }
    std::vector<int> minimumOf(n, -1), firstPixel;
    for (int p = 0; p < n; ++p) {
        if (next[p] >= 0 || minimumOf[p] >= 0) continue;
        std::vector<int> stack{p};
        minimumOf[p] = static_cast<int>(firstPixel.size());
        while (!stack.empty()) {
            const int q = stack.back();
            stack.pop_back();
            for (int r : neighbours(q))
                if (r >= 0 && next[r] < 0 && minimumOf[r] < 0) {
                    EXPECT_EQ(g[r], g[q]);  // adjacent flat pixels are on one level
                    minimumOf[r] = minimumOf[p];
                    stack.push_back(r);
                }
        }
        firstPixel.push_back(p);
    }
    const int minima = static_cast<int>(firstPixel.size());
    std::vector<int> byLevel(minima);
    std::iota(byLevel.begin(), byLevel.end(), 0);
    std::stable_sort(byLevel.begin(), byLevel.end(), [&](int a, int b) { return g[firstPixel[a]] < g[firstPixel[b]]; });
    std::vector<bool> kept(minima, false);
    for (int k = 0; k < std::min(minima, maxRegions); ++k) kept[byLevel[k]] = true;
    std::vector<int> number(minima);
    int keptCount = 0, excessCount = 0;
    for (int m = 0; m < minima; ++m) number[m] = kept[m] ? keptCount++ : maxRegions + excessCount++;
    label.assign(n, -1);
    for (int p = 0; p < n; ++p) {
        int q = p;
        while (next[q] >= 0) q = next[q];
        label[p] = number[minimumOf[q]];
    }
    if (minima <= maxRegions) return minima;
    std::vector<int> parent(minima);
    std::iota(parent.begin(), parent.end(), 0);
    auto root = [&](int b) {
        while (parent[b] != b) b = parent[b];
        return b;
    };
    auto join = [&](int p, int q) {
        const int a = root(label[p]), b = root(label[q]);
        if (a != b && std::max(a, b) >= maxRegions) parent[std::max(a, b)] = std::min(a, b);
    };
    for (int p = 0; p < n; ++p) {
        if (p % w + 1 < w) join(p, p + 1);
        if (p / w + 1 < h) join(p, p + w);
    }
    for (int p = 0; p < n; ++p) label[p] = root(label[p]);
    return maxRegions;
}

// Rows of descentRow that differ from the reference; the first and last rows
// against a wall of 255, as the watershed passes them.
int descentRowsDiffering(const std::vector<std::uint8_t>& g, int w, int h)
{
    const std::vector<std::uint8_t> wall(w, 255);
    std::vector<std::uint8_t> fast(w), reference(w);
    int differing = 0;
    for (int y = 0; y < h; ++y) {
        const std::uint8_t* up = y > 0 ? &g[(y - 1) * w] : wall.data();
        const std::uint8_t* down = y + 1 < h ? &g[(y + 1) * w] : wall.data();
        descentRow(up, &g[y * w], down, w, fast.data());
        descentRowReference(up, &g[y * w], down, w, reference.data());
        differing += fast != reference;
    }
    return differing;
}

std::vector<std::uint8_t> randomLevels(int w, int h, int lowest, int count, std::mt19937& rng)
{
    std::vector<std::uint8_t> g(static_cast<std::size_t>(w) * h);
    for (std::uint8_t& v : g) v = static_cast<std::uint8_t>(lowest + static_cast<int>(rng() % count));
    return g;
}

TEST(DecoderKernels, DescentRowMatchesReferenceOnRandomRowsOfEveryWidth)
{
    // Widths around the 16-pixel NEON block; the full byte range, three low
    // levels (ties in every direction) and the top three (ties with the wall).
    std::mt19937 rng(21);
    for (int width : {1, 2, 3, 4, 15, 16, 17, 18, 19, 33, 47, 64, 781})
        for (const auto& [lowest, count] : {std::pair{0, 256}, std::pair{0, 3}, std::pair{253, 3}})
            EXPECT_EQ(descentRowsDiffering(randomLevels(width, 6, lowest, count, rng), width, 6), 0)
                << "width " << width << ", levels from " << lowest;
}

TEST(DecoderKernels, SweepRowsMatchReferencesOnRandomRowsOfEveryWidth)
{
    // Every code (arrows 0-3, plateau arrows 4-7, flat 8; a quarter with
    // kMinimumArrow, which the sweeps ignore as kPlateauArrow), mostly arrows left
    // and right (long runs across the 4-label blocks), some labels unresolved.
    std::mt19937 rng(23);
    int differing = 0, rows = 0;
    for (int width : {1, 2, 3, 4, 5, 7, 8, 9, 15, 16, 17, 33, 64, 781})
        for (int trial = 0; trial < 20; ++trial) {
            std::vector<std::uint8_t> code(width);
            std::vector<std::int32_t> above(width), fast(width), reference(width);
            for (int x = 0; x < width; ++x) {
                const unsigned r = rng() % 16;
                code[x] = static_cast<std::uint8_t>(r < 5 ? kDescentLeft : r < 10 ? kDescentRight : r - 10 + (r == 15) * 2);
                code[x] |= static_cast<std::uint8_t>(code[x] < kDescentFlat && rng() % 4 == 0 ? kPlateauArrow : 0);
                code[x] |= static_cast<std::uint8_t>(rng() % 4 == 0 ? kMinimumArrow : 0);
                above[x] = rng() % 8 == 0 ? kUnresolved : static_cast<std::int32_t>(rng() % 1000);
                fast[x] = reference[x] = rng() % 8 == 0 ? kUnresolved : static_cast<std::int32_t>(rng() % 1000);
            }
            std::vector<std::int32_t> fastUpLeft = fast, referenceUpLeft = reference;
            // The unresolved masks start as garbage: the sweeps write every word.
            std::vector<std::uint64_t> fastUnresolved((width + 63) / 64, ~0ull), referenceUnresolved((width + 63) / 64, 0x5555);
            sweepRow(code.data(), above.data(), fast.data(), width, fastUnresolved.data());
            sweepRowReference(code.data(), above.data(), reference.data(), width, referenceUnresolved.data());
            sweepRowUpLeft(code.data(), above.data(), fastUpLeft.data(), width);
            sweepRowUpLeftReference(code.data(), above.data(), referenceUpLeft.data(), width);
            differing += fast != reference || fastUpLeft != referenceUpLeft || fastUnresolved != referenceUnresolved;
            ++rows;
        }
    EXPECT_EQ(differing, 0) << "of " << rows << " rows";
}

// computeWatershed on a given gradient image, in a workspace sized as
// Decoder::create() sizes it.
struct Basins {
    std::vector<std::int32_t> labels;
    int regions = 0;
    bool truncated = false;
};
Basins watershedOf(const std::vector<std::uint8_t>& g, int w, int h, int maxRegions)
{
    DecoderWorkspace ws(StripePattern::generate(40, 4, 8, 7).value(), DecoderParams{});
    const std::size_t n = g.size();
    ws.width = w;
    ws.height = h;
    ws.maxRegions = maxRegions;
    ws.maxEdges = 3 * maxRegions;
    allocateFrameBuffers(ws);
    std::copy(g.begin(), g.end(), ws.gradient.get());
    computeWatershed(ws);
    return {std::vector<std::int32_t>(ws.labels.get(), ws.labels.get() + n), ws.regionCount, ws.truncated};
}

TEST(DecoderKernels, WatershedSplitsAPlateauHalfwayBetweenItsWaysDown)
{
    // A ridge plateau between two minima, along a row and along a column: the
    // pixels drain to the nearer end; the middle of an odd one to the basin
    // reached first in raster order.
    const std::vector<std::uint8_t> even{0, 5, 5, 5, 5, 5, 5, 0}, odd{0, 5, 5, 5, 5, 5, 0};
    EXPECT_EQ(watershedOf(even, 8, 1, 8).labels, (std::vector<std::int32_t>{0, 0, 0, 0, 1, 1, 1, 1}));
    EXPECT_EQ(watershedOf(even, 1, 8, 8).labels, (std::vector<std::int32_t>{0, 0, 0, 0, 1, 1, 1, 1}));
    EXPECT_EQ(watershedOf(odd, 7, 1, 7).labels, (std::vector<std::int32_t>{0, 0, 0, 0, 1, 1, 1}));
    // Capacity 1: the higher minimum (level 2, first in raster order) is merged.
    const Basins one = watershedOf({2, 5, 5, 0}, 4, 1, 1);
    EXPECT_EQ(one.labels, (std::vector<std::int32_t>{0, 0, 0, 0}));
    EXPECT_EQ(one.regions, 1);
    EXPECT_TRUE(one.truncated);
}

TEST(DecoderKernels, WatershedMatchesReferenceOnTinyAndTerracedImages)
{
    // Terraces of 4 levels (plateaus everywhere) and the full byte range, with
    // room for every minimum and with capacity 3.
    std::mt19937 rng(22);
    int truncatedCases = 0;
    for (const auto& [w, h] : {std::pair{1, 1}, std::pair{1, 2}, std::pair{2, 1}, std::pair{2, 2}, std::pair{1, 37},
                              std::pair{37, 1}, std::pair{2, 33}, std::pair{33, 2}, std::pair{40, 30},
                              std::pair{200, 9}})  // runs across the 64-pixel words of the minima's bit masks
        for (const int count : {4, 256})
            for (const int maxRegions : {w * h, 3}) {
                const std::vector<std::uint8_t> g = randomLevels(w, h, 0, count, rng);
                std::vector<std::int32_t> reference;
                const int minima = referenceWatershed(g.data(), w, h, w * h, reference);
                const int regions = referenceWatershed(g.data(), w, h, maxRegions, reference);
                const Basins fast = watershedOf(g, w, h, maxRegions);
                EXPECT_EQ(fast.labels, reference) << w << "x" << h << ", " << count << " levels, capacity " << maxRegions;
                EXPECT_EQ(fast.regions, regions);
                EXPECT_EQ(fast.truncated, minima > maxRegions);
                truncatedCases += fast.truncated;
            }
    EXPECT_GE(truncatedCases, 6);  // the capacity is exceeded in most of the larger images
}

// The region statistics as first written: each region's pixels gathered in
// raster order, each channel's median (index size / 2) by nth_element, the
// centroid from integer coordinate sums.
std::vector<Region> referenceRegionColours(const DecoderWorkspace& ws)
{
    std::vector<std::vector<std::int32_t>> pixels(ws.regionCount);
    for (int p = 0; p < ws.width * ws.height; ++p) pixels[ws.labels[p]].push_back(p);
    std::vector<Region> regions(ws.regionCount);
    for (int r = 0; r < ws.regionCount; ++r) {
        const int size = static_cast<int>(pixels[r].size());
        long long sx = 0, sy = 0;
        std::array<std::vector<std::uint8_t>, 3> channel;
        for (const std::int32_t p : pixels[r]) {
            const int y = p / ws.width, x = p % ws.width;
            sx += x;
            sy += y;
            for (int c = 0; c < 3; ++c) channel[c].push_back(ws.frame.row(y)[3 * x + ws.rgbOffset[c]]);
        }
        cv::Vec3f median;
        for (int c = 0; c < 3; ++c) {
            std::nth_element(channel[c].begin(), channel[c].begin() + size / 2, channel[c].end());
            median[c] = channel[c][size / 2];
        }
        const cv::Vec3f corrected = ws.colorCorrection * median;
        regions[r].color = {corrected[0], corrected[1], corrected[2]};
        regions[r].pixelCount = size;
        regions[r].centroidX = static_cast<float>(static_cast<double>(sx) / size);
        regions[r].centroidY = static_cast<float>(static_cast<double>(sy) / size);
    }
    return regions;
}

// The region adjacency graph by a map from label pairs to edges, pairs in
// the same raster order (so edge indices and float sums agree); the
// per-pair gradient is the stage's own pairGradient.
std::vector<GraphEdge> referenceGraph(const DecoderWorkspace& ws)
{
    const int w = ws.width, h = ws.height;
    std::map<std::pair<std::int32_t, std::int32_t>, std::size_t> index;
    std::vector<GraphEdge> edges;
    auto addPair = [&](int x, int y, bool horizontal) {
        const std::int32_t p = y * w + x, q = horizontal ? p + 1 : p + w;
        const std::int32_t a = std::min(ws.labels[p], ws.labels[q]), b = std::max(ws.labels[p], ws.labels[q]);
        const int sign = ws.labels[p] < ws.labels[q] ? 1 : -1;
        auto [it, added] = index.emplace(std::make_pair(a, b), edges.size());
        if (added) {
            edges.emplace_back();
            edges.back().a = a;
            edges.back().b = b;
        }
        GraphEdge& edge = edges[it->second];
        ++edge.borderCount;
        std::int16_t& normal = horizontal ? edge.normalX : edge.normalY;
        if (normal > -32767 && normal < 32767) normal = static_cast<std::int16_t>(normal + sign);  // saturating
        const PairGradient gradient = pairGradient(ws.frame, x, y, horizontal, ws.primary);
        edge.primaryGradient += gradient.primary;
        edge.secondaryGradient += gradient.secondary;
    };
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x + 1 < w; ++x)
            if (ws.labels[y * w + x] != ws.labels[y * w + x + 1]) addPair(x, y, true);
        if (y + 1 < h)
            for (int x = 0; x < w; ++x)
                if (ws.labels[y * w + x] != ws.labels[(y + 1) * w + x]) addPair(x, y, false);
    }
    return edges;
}

// A workspace with the buffers of the stages up to the graph, sized by
// Decoder::create()'s own function (allocateFrameBuffers).
struct FloodCase {
    explicit FloodCase(const cv::Mat& image, int maxRegions)
        : frame(image), ws(StripePattern::generate(40, 4, 8, 7).value(), DecoderParams{})
    {
        ws.width = image.cols;
        ws.height = image.rows;
        ws.maxRegions = maxRegions;
        ws.maxEdges = 3 * maxRegions;
        allocateFrameBuffers(ws);
        ws.primary = cv::Vec2f(0.8f, -0.6f);
        ws.colorCorrection = cv::Matx33f(0.9f, 0.08f, 0.02f, 0.1f, 0.8f, 0.1f, 0.03f, 0.12f, 0.85f).inv();
        ws.frame = {image.data, image.cols, image.rows, static_cast<std::ptrdiff_t>(image.step), PixelFormat::Bgr8};
    }
    // Labels that differ from the reference's; also the region counts.
    int differingLabels()
    {
        computeGradient(ws);
        computeWatershed(ws);
        std::vector<std::int32_t> reference;
        referenceRegions = referenceWatershed(ws.gradient.get(), ws.width, ws.height, ws.maxRegions, reference);
        int differing = 0;
        for (std::size_t p = 0; p < reference.size(); ++p) differing += ws.labels[p] != reference[p];
        return differing;
    }
    // Regions whose pixel count, centroid or colour differ (bitwise) from the
    // reference's, after the watershed ran.
    int differingRegions()
    {
        computeRegions(ws);
        const std::vector<Region> reference = referenceRegionColours(ws);
        int differing = 0;
        for (int r = 0; r < ws.regionCount; ++r) {
            const Region& a = ws.regions[r];
            const Region& b = reference[r];
            differing += a.pixelCount != b.pixelCount || a.centroidX != b.centroidX || a.centroidY != b.centroidY ||
                         a.color != b.color;
        }
        return differing;
    }
    // Graph edges that differ from the reference's (any field, floats
    // bitwise), plus incidence lists that do not list each region's edges
    // in increasing order; after the regions stage ran.
    int differingGraphEdges()
    {
        buildGraph(ws);
        const std::vector<GraphEdge> reference = referenceGraph(ws);
        int differing = std::abs(ws.edgeCount - static_cast<int>(reference.size()));
        for (int e = 0; e < std::min<int>(ws.edgeCount, static_cast<int>(reference.size())); ++e) {
            const GraphEdge& a = ws.edges[e];
            const GraphEdge& b = reference[e];
            differing += a.a != b.a || a.b != b.b || a.borderCount != b.borderCount || a.normalX != b.normalX ||
                         a.normalY != b.normalY || a.primaryGradient != b.primaryGradient ||
                         a.secondaryGradient != b.secondaryGradient;
        }
        std::vector<std::vector<std::int32_t>> incident(ws.regionCount);
        for (int e = 0; e < static_cast<int>(reference.size()); ++e) {
            incident[reference[e].a].push_back(e);
            incident[reference[e].b].push_back(e);
        }
        for (int r = 0; r < ws.regionCount; ++r) {
            const Region& region = ws.regions[r];
            differing += std::vector<std::int32_t>(ws.adjacency.get() + region.adjacencyBegin,
                                                   ws.adjacency.get() + region.adjacencyBegin + region.degree) !=
                         incident[r];
        }
        return differing;
    }
    cv::Mat frame;
    DecoderWorkspace ws;
    int referenceRegions = -1;
};

TEST(DecoderKernels, WatershedRegionsAndGraphMatchReferencesOnSimulatorFrame)
{
    const cv::Mat frame = renderFrame(hal::sim::SceneKind::TexturedRelief, hal::sim::Albedo::Photo, 4);
    ASSERT_FALSE(frame.empty());
    FloodCase c(frame, frame.cols * frame.rows / 16);
    EXPECT_EQ(c.differingLabels(), 0);
    EXPECT_EQ(c.ws.regionCount, c.referenceRegions);
    EXPECT_GT(c.ws.regionCount, 1000);  // thousands of basins flooded at once
    EXPECT_FALSE(c.ws.truncated);
    EXPECT_EQ(c.differingRegions(), 0);
    EXPECT_EQ(c.differingGraphEdges(), 0);
    EXPECT_GT(c.ws.edgeCount, 2 * c.ws.regionCount);  // a planar graph of mostly hexagon-like cells
}

TEST(DecoderKernels, WatershedRegionsAndGraphMatchReferencesOnNoiseAndWhenTruncated)
{
    // Random bytes: the most irregular basins and queue traffic.
    const cv::Mat noise = randomFrame(97, 61, 11);
    FloodCase full(noise, 97 * 61);
    EXPECT_EQ(full.differingLabels(), 0);
    EXPECT_EQ(full.ws.regionCount, full.referenceRegions);
    EXPECT_GT(full.ws.regionCount, 20);
    FloodCase truncated(noise, full.ws.regionCount / 2);
    EXPECT_EQ(truncated.differingLabels(), 0);
    EXPECT_EQ(truncated.ws.regionCount, full.ws.regionCount / 2);
    EXPECT_TRUE(truncated.ws.truncated);
    // Regions of one pixel up to large flooded ones, both byte orders.
    EXPECT_EQ(full.differingRegions(), 0);
    EXPECT_EQ(full.differingGraphEdges(), 0);
    EXPECT_EQ(truncated.differingRegions(), 0);
    EXPECT_EQ(truncated.differingGraphEdges(), 0);
    truncated.ws.rgbOffset = {0, 1, 2};
    EXPECT_EQ(truncated.differingRegions(), 0);
}

TEST(DecoderKernels, RegionsAndGraphMatchReferencesOnTinyImages)
{
    // Rows and columns shorter than the kernels' blocks; the frame's last
    // pixel has no byte after it; regions within 4 pixels of the sorted
    // buffer's end take the reference medians.
    for (const auto& [width, height] : {std::pair{1, 1}, {1, 7}, {7, 1}, {2, 2}, {3, 5}, {17, 3}, {66, 2}}) {
        FloodCase c(randomFrame(width, height, 40u + width * height), width * height);
        c.differingLabels();
        EXPECT_EQ(c.differingRegions(), 0) << width << "x" << height;
        EXPECT_EQ(c.differingGraphEdges(), 0) << width << "x" << height;
    }
}

TEST(DecoderKernels, GraphMatchesReferenceForTinyAndZeroPrimaryComponents)
{
    // buildGraph's pair kernels take the 0.25 of a pair's quartered
    // difference into the primary direction's components (one multiply less
    // per pair), which gives pairGradient's floats unless a component is
    // below 2^-124 (0.25 p or the product subnormal): those directions take
    // the unfolded kernels.
    const cv::Mat noise = randomFrame(97, 61, 12);
    for (const cv::Vec2f& primary : {cv::Vec2f(1.0f, 0.0f), cv::Vec2f(0.0f, -1.0f), cv::Vec2f(1.1e-38f, -3.3e-38f),
                                    cv::Vec2f(-1.3e-39f, 2.9e-39f), cv::Vec2f(0x1p-124f, 0x1.8p-123f),
                                    cv::Vec2f(3e38f, 0.5f)}) {
        FloodCase c(noise, 97 * 61);
        c.ws.primary = primary;
        c.differingLabels();
        EXPECT_EQ(c.differingRegions(), 0);
        EXPECT_EQ(c.differingGraphEdges(), 0) << primary;
    }
}

TEST(DecoderKernels, GraphNormalsSaturateLikeTheReference)
{
    // Three labels in diagonal stripes, (x + y) mod 3 and (x - y) mod 3:
    // edges of about 80000 border pairs whose normal sums run to +32767 or
    // -32767 in x and in y (all four sign combinations), where they stay.
    for (const int slope : {1, -1}) {
        FloodCase c(randomFrame(400, 300, 5u), 400 * 300 / 16);
        const int w = c.ws.width, h = c.ws.height;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) c.ws.labels[y * w + x] = ((x + slope * y) % 3 + 3) % 3;
        // The rows' border lists, as the regions stage writes them.
        std::int32_t borders = 0;
        for (int y = 0; y < h; ++y) {
            const std::int32_t* row = c.ws.labels.get() + y * w;
            c.ws.borderStarts[y] = borders;
            forEachBorder(row, row + 1, w - 1,
                          [&](int x) { c.ws.borderPositions[borders++] = static_cast<std::uint16_t>(x); });
        }
        c.ws.borderStarts[h] = borders;
        c.ws.regionCount = 3;
        EXPECT_EQ(c.differingGraphEdges(), 0) << slope;
        ASSERT_EQ(c.ws.edgeCount, 3);
        for (int e = 0; e < 3; ++e) {
            EXPECT_GT(c.ws.edges[e].borderCount, 70000);
            EXPECT_EQ(std::abs(c.ws.edges[e].normalX), 32767);
            EXPECT_EQ(std::abs(c.ws.edges[e].normalY), 32767);
        }
    }
}

// The per-channel loops edges.cpp's symbolError, matchError and
// equalizedChange replaced with vector lanes and selects (before issue #7,
// round 5); the lanes must give the same floats.
EqualizedChange referenceEqualizedChange(const Region& f, const Region& t)
{
    EqualizedChange out;
    float norm = 0;
    for (int c = 0; c < 3; ++c) {
        const float raw = t.color[c] - f.color[c];
        out.weight = std::max(out.weight, std::abs(raw));
        out.c[c] = raw / std::max(0.5f * (f.color[c] + t.color[c]), 20.0f);
        norm = std::max(norm, std::abs(out.c[c]));
    }
    out.relative = norm;
    if (norm > 0)
        for (float& c : out.c) c /= norm;
    return out;
}

float referenceMatchError(const std::array<float, 3>& c, SymbolCode symbol, float t)
{
    const float onScale = 1 / (1 - t), offScale = 1 / t;
    float sum = 0;
    for (int ch = 0; ch < 3; ++ch) {
        const int sign = symbolChannel(symbol, ch);
        const float e = sign == 0 ? std::abs(c[ch]) * offScale : (1 - sign * c[ch]) * onScale;
        sum += e * e;
    }
    return std::sqrt(sum);
}

float referenceSymbolError(const EqualizedChange& change, SymbolCode symbol, float t)
{
    const std::array<float, 3>& c = change.c;
    float sum[3] = {0, 0, 0};
    int count[3] = {0, 0, 0};
    for (int ch = 0; ch < 3; ++ch) {
        sum[symbolChannel(symbol, ch) + 1] += c[ch];
        ++count[symbolChannel(symbol, ch) + 1];
    }
    float common = 0;
    if (count[1] > 0) common = sum[1] / static_cast<float>(count[1]);
    else if (count[0] > 0 && count[2] > 0)
        common = 0.5f * (sum[0] / static_cast<float>(count[0]) + sum[2] / static_cast<float>(count[2]));
    const float bound = change.relative > 0 ? std::min(0.3f, 0.15f / change.relative) : 0.0f;
    common = std::clamp(common, -bound, bound);
    if (common == 0) return referenceMatchError(c, symbol, t);
    std::array<float, 3> corrected{c[0] - common, c[1] - common, c[2] - common};
    const float norm = std::max({std::abs(corrected[0]), std::abs(corrected[1]), std::abs(corrected[2])});
    if (norm > 0)
        for (float& v : corrected) v /= norm;
    return referenceMatchError(corrected, symbol, t);
}

TEST(DecoderKernels, EdgeSymbolErrorsMatchThePerChannelLoopsBitwise)
{
    // Region colours as the regions stage leaves them (medians after a
    // crosstalk correction: any float in and somewhat beyond [0, 255],
    // dark ones below the brightness floor), whole digits (equal channels,
    // zero changes) among them; every symbol on every change.
    DecoderWorkspace ws(StripePattern::generate(40, 4, 8, 7).value(), DecoderParams{});
    std::vector<Region> regions(2);
    ws.regions = ArenaArray<Region>(regions.data());
    std::mt19937 random(7);
    std::uniform_real_distribution<float> colour(-10.0f, 270.0f);
    std::uniform_int_distribution<int> digit(0, 3);
    const float t = static_cast<float>(ws.params.t);
    const MatchScales scales(t);
    int changes = 0, differing = 0, corrected = 0, fitting = 0;
    for (int i = 0; i < 20000; ++i) {
        for (int r = 0; r < 2; ++r)
            for (float& c : ws.regions[r].color) c = i % 3 == 0 ? static_cast<float>(64 * digit(random)) : colour(random);
        const EqualizedChange change = equalizedChange(ws, 0, 1);
        const EqualizedChange reference = referenceEqualizedChange(ws.regions[0], ws.regions[1]);
        differing += std::memcmp(&change, &reference, sizeof change) != 0;
        for (int s = 0; s < kSymbolCount; ++s) {
            const auto symbol = static_cast<SymbolCode>(s);
            const float error = symbolError(reference, symbol, t);
            differing += std::bit_cast<std::uint32_t>(error) !=
                         std::bit_cast<std::uint32_t>(referenceSymbolError(reference, symbol, t));
            differing += std::bit_cast<std::uint32_t>(matchError(reference.c, symbol, t)) !=
                         std::bit_cast<std::uint32_t>(referenceMatchError(reference.c, symbol, t));
            corrected += error != matchError(reference.c, symbol, t);
            // The traversal's null-edge test in one pass: optimalSymbol and matchError.
            const ExpectedSymbolMatch match = expectedSymbolMatch(ws, 0, 1, symbol, t, scales);
            const bool fits = optimalSymbol(reference.c, t) == symbol;
            differing += match.fits != fits ||
                         std::bit_cast<std::uint32_t>(match.weight) != std::bit_cast<std::uint32_t>(reference.weight) ||
                         (fits && std::bit_cast<std::uint32_t>(match.error) !=
                                      std::bit_cast<std::uint32_t>(referenceMatchError(reference.c, symbol, t)));
            fitting += fits;
        }
        ++changes;
    }
    EXPECT_EQ(differing, 0) << "of " << changes << " changes";
    // The common change's correction is exercised, not bypassed.
    EXPECT_GT(corrected, changes);
    // Every change fits one symbol, its optimal one.
    EXPECT_EQ(fitting, changes);
}

// The edge stage (edges.cpp: 4 edges per step in vector lanes) against the
// one-edge functions, and the direction test of fig. 5, edge by edge: every
// feature, range and stored change bitwise, and the traversal's symbol errors
// from the stored change equal to those from equalizedChange both ways.
TEST(DecoderKernels, EdgeStageMatchesTheOneEdgeFunctionsBitwise)
{
    DecoderWorkspace ws(StripePattern::generate(40, 4, 8, 7).value(), DecoderParams{});
    constexpr int kRegions = 300, kEdges = 20003;  // not a multiple of the 4 lanes
    std::vector<Region> regions(kRegions);
    std::vector<GraphEdge> edges(kEdges);
    std::vector<EdgeFeature> features(kEdges);
    ws.regions = ArenaArray<Region>(regions.data());
    ws.edges = ArenaArray<GraphEdge>(edges.data());
    ws.edgeFeatures = ArenaArray<EdgeFeature>(features.data());
    std::vector<EdgeChange> edgeChanges(kEdges);
    ws.edgeChanges = edgeChanges.data();
    ws.edgeCount = kEdges;
    ws.primary = cv::Vec2f(0.8f, -0.6f);
    std::mt19937 random(11);
    std::uniform_real_distribution<float> colour(-10.0f, 270.0f), position(0.0f, 780.0f), gradient(0.0f, 400.0f);
    std::uniform_int_distribution<int> digit(0, 3), region(0, kRegions - 1), normal(-40, 40), border(1, 60);
    for (int r = 0; r < kRegions; ++r) {
        for (float& c : ws.regions[r].color) c = r % 3 == 0 ? static_cast<float>(64 * digit(random)) : colour(random);
        ws.regions[r].centroidX = position(random);
        ws.regions[r].centroidY = position(random);
    }
    for (int e = 0; e < kEdges; ++e) {
        GraphEdge& edge = ws.edges[e];
        do {
            edge.a = region(random);
            edge.b = region(random);
        } while (edge.a == edge.b);
        if (edge.a > edge.b) std::swap(edge.a, edge.b);
        edge.borderCount = border(random);
        edge.normalX = static_cast<std::int16_t>(e % 7 == 0 ? 0 : normal(random));
        edge.normalY = static_cast<std::int16_t>(e % 5 == 0 ? 0 : normal(random));
        edge.primaryGradient = e % 11 == 0 ? 0.0f : gradient(random);
        edge.secondaryGradient = gradient(random);
    }
    computeEdgeFeatures(ws);

    const float t = static_cast<float>(ws.params.t);
    std::vector<std::array<float, 3>> ranges(kRegions);
    int differing = 0, across = 0, ragged = 0, symbolErrors = 0;
    for (int e = 0; e < kEdges; ++e) {
        const GraphEdge& edge = ws.edges[e];
        const Region &a = ws.regions[edge.a], &b = ws.regions[edge.b];
        float nx = edge.normalX, ny = edge.normalY;
        const float count = static_cast<float>(edge.borderCount);
        if (nx * nx + ny * ny < 0.0625f * count * count) {
            nx = b.centroidX - a.centroidX;
            ny = b.centroidY - a.centroidY;
            ++ragged;
        }
        const float length2 = nx * nx + ny * ny, along = nx * ws.primary[0] + ny * ws.primary[1];
        const bool parallel = length2 == 0 || 2 * along * along < length2;
        const auto direction = parallel ? EdgeDirection::Parallel : along > 0 ? EdgeDirection::Forward : EdgeDirection::Backward;
        for (int c = 0; c < 3; ++c) {
            const float change = std::abs(b.color[c] - a.color[c]);
            ranges[edge.a][c] = std::max(ranges[edge.a][c], change);
            ranges[edge.b][c] = std::max(ranges[edge.b][c], change);
        }
        const EqualizedChange change = equalizedChange(ws, edge.a, edge.b);
        EdgeFeature expected;
        expected.weight = change.weight;
        expected.packed = EdgeFeature::pack(edge.a, edge.b, direction, kNullSymbol);
        if (!parallel) {
            const SymbolCode symbol = optimalSymbol(change.c, t);
            expected.packed = EdgeFeature::pack(edge.a, edge.b, direction, symbol);
            expected.bestMatch = symbolError(change, symbol, t);
            expected.gradientError =
                edge.primaryGradient > 0 ? std::min(edge.secondaryGradient / edge.primaryGradient, 10.0f) : 10.0f;
            ++across;
        }
        differing += std::memcmp(&expected, &ws.edgeFeatures[e], sizeof expected) != 0;
        // The stored change, and the traversal's symbol errors from it, both ways along the edge.
        const EdgeChange& stored = ws.edgeChanges[e];
        differing += std::memcmp(&stored.c, &change.c, sizeof change.c) != 0 ||
                     std::bit_cast<std::uint32_t>(stored.commonBound) !=
                         std::bit_cast<std::uint32_t>(change.relative > 0 ? std::min(0.3f, 0.15f / change.relative) : 0.0f);
        const MatchScales scales(t);
        const EqualizedChange backward = equalizedChange(ws, edge.b, edge.a);
        for (int s = 0; s < kSymbolCount; ++s) {
            const auto symbol = static_cast<SymbolCode>(s);
            const auto bits = [](float v) { return std::bit_cast<std::uint32_t>(v); };
            symbolErrors += 2;
            differing += bits(symbolError(stored, symbol, scales)) != bits(symbolError(change, symbol, scales));
            differing += bits(symbolError(stored, reversedSymbol(symbol), scales)) != bits(symbolError(backward, symbol, scales));
        }
    }
    for (int r = 0; r < kRegions; ++r) differing += std::memcmp(&ranges[r], &ws.regions[r].range, sizeof ranges[r]) != 0;
    EXPECT_EQ(differing, 0) << "of " << kEdges << " edges, " << kRegions << " regions and " << symbolErrors
                            << " symbol errors";
    // Both directions and both ways to them are exercised.
    EXPECT_GT(across, kEdges / 4);
    EXPECT_LT(across, kEdges * 3 / 4);
    EXPECT_GT(ragged, kEdges / 10);
}

}  // namespace
}  // namespace stria::pipeline
