#pragma once
// The colour-stripe pattern on the slide: colours, edge symbols, the window
// uniqueness property and the window lookup tables built once at start-up.
//
// Colours are 3-bit: bit 2 red, bit 1 green, bit 0 blue; letters K B G C R M Y W
// stand for 0..7. Stripe i covers projector columns [i*w - 0.5, (i+1)*w - 0.5)
// (OpenCV pixel coordinates, pixel centres on integers). Edge k lies between
// stripes k and k+1, at projector column x = (k+1)*w - 0.5.

#include "pipeline/status.hpp"

#include <opencv2/core.hpp>

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace stria::pipeline {

using Color = std::uint8_t;  // 0..7
inline constexpr std::string_view kColorLetters = "KBGCRMYW";
inline constexpr int kRed = 0, kGreen = 1, kBlue = 2;  // channel indices used by symbols

// Per channel: +1 rising, 0 constant, -1 falling. Packed as a code 0..26:
// (r+1)*9 + (g+1)*3 + (b+1). Code 13 is the null symbol (no change at all).
using SymbolCode = std::uint8_t;
inline constexpr int kSymbolCount = 27;
inline constexpr SymbolCode kNullSymbol = 13;

constexpr int colorChannel(Color c, int channel) { return (c >> (2 - channel)) & 1; }
constexpr SymbolCode makeSymbol(int r, int g, int b)
{
    return static_cast<SymbolCode>((r + 1) * 9 + (g + 1) * 3 + (b + 1));
}
constexpr int symbolChannel(SymbolCode s, int channel)
{
    constexpr int kDiv[3] = {9, 3, 1};
    return (s / kDiv[channel]) % 3 - 1;
}
constexpr SymbolCode symbolBetween(Color left, Color right)
{
    return makeSymbol(colorChannel(right, kRed) - colorChannel(left, kRed),
                      colorChannel(right, kGreen) - colorChannel(left, kGreen),
                      colorChannel(right, kBlue) - colorChannel(left, kBlue));
}
// The symbol seen when the edge is crossed right-to-left.
constexpr SymbolCode reversedSymbol(SymbolCode s) { return static_cast<SymbolCode>(26 - s); }
// "R+G-" style name; "0" for the null symbol.
std::string symbolName(SymbolCode s);

class StripePattern {
public:
    // Checks every constraint and builds the lookup tables. window = 0 picks the
    // smallest window length for which every window is unique.
    static Result<StripePattern> create(int stripeWidth, std::string_view colors, int window = 0);

    // Precise description of the first constraint that `colors` violates, or ok.
    static Status validate(int stripeWidth, std::string_view colors, int window);

    // A random valid pattern (deterministic for a seed) over the given alphabet.
    static Result<StripePattern> generate(int stripes, int window, int stripeWidth, std::uint64_t seed,
                                          std::string_view alphabet = kColorLetters);

    int stripeWidth() const { return stripeWidth_; }
    int stripeCount() const { return static_cast<int>(colors_.size()); }
    int edgeCount() const { return static_cast<int>(symbols_.size()); }
    int window() const { return window_; }
    Color color(int stripe) const { return colors_[stripe]; }
    SymbolCode edgeSymbol(int edge) const { return symbols_[edge]; }
    std::span<const SymbolCode> edgeSymbols() const { return symbols_; }
    std::string colorLetters() const;
    // Projector columns spanned by the pattern: [0, stripeCount * stripeWidth).
    int projectorColumnsUsed() const { return stripeCount() * stripeWidth_; }
    double edgeColumn(int edge) const { return (edge + 1) * stripeWidth_ - 0.5; }

    // Edges carrying `symbol`, in increasing order (the paper's lookup table).
    std::span<const int> edgesWithSymbol(SymbolCode symbol) const;
    // Start edge of the window of window() symbols equal to `symbols`, or -1.
    int findWindow(std::span<const SymbolCode> symbols) const;

    // The slide as the projector shows it: BGR, width x height, stripes from
    // column 0, columns beyond the pattern black. A channel that is "off" has
    // (1 - contrast) times the "on" level (255).
    cv::Mat renderSlide(int width, int height, double contrast = 1.0) const;

private:
    StripePattern() = default;
    void buildTables();

    int stripeWidth_ = 0;
    int window_ = 0;
    std::vector<Color> colors_;
    std::vector<SymbolCode> symbols_;
    std::vector<int> symbolEdges_;                                // edges grouped by symbol
    std::array<std::pair<int, int>, kSymbolCount> symbolRange_{};  // [begin, end) in symbolEdges_
    std::vector<std::pair<std::uint64_t, int>> windowIndex_;     // sorted (window key, start edge)
};

}  // namespace stria::pipeline
