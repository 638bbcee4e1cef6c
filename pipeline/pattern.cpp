#include "pipeline/pattern.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <random>
#include <sstream>

namespace stria::pipeline {
namespace {

constexpr const char* kChannelNames[3] = {"red", "green", "blue"};
constexpr int kMaxWindow = 13;  // 27^13 < 2^64: a window packs into one 64-bit key

int colorFromLetter(char letter)
{
    const auto pos = kColorLetters.find(static_cast<char>(std::toupper(static_cast<unsigned char>(letter))));
    return pos == std::string_view::npos ? -1 : static_cast<int>(pos);
}

std::uint64_t windowKey(std::span<const SymbolCode> symbols)
{
    std::uint64_t key = 0;
    for (SymbolCode s : symbols) key = key * kSymbolCount + s;
    return key;
}

std::string windowNames(std::span<const SymbolCode> symbols)
{
    std::string out;
    for (SymbolCode s : symbols) {
        if (!out.empty()) out += ' ';
        out += symbolName(s);
    }
    return out;
}

// Index of the first window length-`window` repeat, as (first, second) start edges.
std::pair<int, int> firstRepeatedWindow(std::span<const SymbolCode> symbols, int window)
{
    std::vector<std::pair<std::uint64_t, int>> keys;
    for (int k = 0; k + window <= static_cast<int>(symbols.size()); ++k)
        keys.emplace_back(windowKey(symbols.subspan(k, window)), k);
    std::sort(keys.begin(), keys.end());
    std::pair<int, int> best{-1, -1};
    for (std::size_t i = 1; i < keys.size(); ++i) {
        if (keys[i].first != keys[i - 1].first) continue;
        // keys with equal value are sorted by position: report the earliest pair
        if (best.first < 0 || keys[i - 1].second < best.first ||
            (keys[i - 1].second == best.first && keys[i].second < best.second))
            best = {keys[i - 1].second, keys[i].second};
    }
    return best;
}

}  // namespace

std::string symbolName(SymbolCode s)
{
    if (s == kNullSymbol) return "0";
    std::string out;
    for (int ch = 0; ch < 3; ++ch) {
        const int v = symbolChannel(s, ch);
        if (v == 0) continue;
        out += "RGB"[ch];
        out += v > 0 ? '+' : '-';
    }
    return out;
}

// Checks everything but window uniqueness; fills the edge symbols on success.
static Status validateColors(int stripeWidth, std::string_view colors, std::vector<SymbolCode>& symbols)
{
    if (stripeWidth < 1)
        return Status::error("stripe_width is " + std::to_string(stripeWidth) + ": it must be at least 1 projector pixel");
    if (colors.size() < 2)
        return Status::error("colors has " + std::to_string(colors.size()) + " stripes: a pattern needs at least 2");
    std::vector<Color> c(colors.size());
    for (std::size_t i = 0; i < colors.size(); ++i) {
        const int v = colorFromLetter(colors[i]);
        if (v < 0)
            return Status::error("colors[" + std::to_string(i) + "] is '" + std::string(1, colors[i]) +
                                 "': each stripe must be one of the letters K B G C R M Y W");
        c[i] = static_cast<Color>(v);
    }
    symbols.assign(c.size() - 1, kNullSymbol);
    for (std::size_t k = 0; k + 1 < c.size(); ++k) {
        if (c[k] == c[k + 1])
            return Status::error("stripes " + std::to_string(k) + " and " + std::to_string(k + 1) + " are both '" +
                                 std::string(1, kColorLetters[c[k]]) + "': neighbouring stripes must differ");
        symbols[k] = symbolBetween(c[k], c[k + 1]);
    }
    for (std::size_t k = 0; k + 1 < symbols.size(); ++k) {
        for (int ch = 0; ch < 3; ++ch) {
            if (symbolChannel(symbols[k], ch) == 0 && symbolChannel(symbols[k + 1], ch) == 0)
                return Status::error("edges " + std::to_string(k) + " and " + std::to_string(k + 1) + " (stripes " +
                                     std::string(colors.substr(k, 3)) + " at " + std::to_string(k) + ".." +
                                     std::to_string(k + 2) + ") both leave " + kChannelNames[ch] +
                                     " unchanged: every channel must change at least once in any two "
                                     "consecutive edges");
        }
    }
    return Status::ok();
}

Status StripePattern::validate(int stripeWidth, std::string_view colors, int window)
{
    std::vector<SymbolCode> symbols;
    if (Status s = validateColors(stripeWidth, colors, symbols); !s) return s;
    const int edges = static_cast<int>(symbols.size());
    if (window < 1 || window > kMaxWindow)
        return Status::error("window is " + std::to_string(window) + ": it must be between 1 and " +
                             std::to_string(kMaxWindow));
    if (window > edges)
        return Status::error("window is " + std::to_string(window) + " but the pattern has only " +
                             std::to_string(edges) + " edges");
    const auto [first, second] = firstRepeatedWindow(symbols, window);
    if (first >= 0)
        return Status::error("the window of " + std::to_string(window) + " edge symbols at edge " +
                             std::to_string(first) + " (" + windowNames(std::span(symbols).subspan(first, window)) +
                             ") repeats at edge " + std::to_string(second) + ": windows must be unique");
    return Status::ok();
}

Result<StripePattern> StripePattern::create(int stripeWidth, std::string_view colors, int window)
{
    if (window == 0) {
        // The smallest window length for which every window is unique.
        std::vector<SymbolCode> symbols;
        if (Status s = validateColors(stripeWidth, colors, symbols); !s) return s;
        window = 1;
        while (window < kMaxWindow && window < static_cast<int>(symbols.size()) &&
               firstRepeatedWindow(symbols, window).first >= 0)
            ++window;
    }
    if (Status s = validate(stripeWidth, colors, window); !s) return s;
    StripePattern p;
    p.stripeWidth_ = stripeWidth;
    p.window_ = window;
    for (char letter : colors) p.colors_.push_back(static_cast<Color>(colorFromLetter(letter)));
    p.buildTables();
    return p;
}

void StripePattern::buildTables()
{
    symbols_.resize(colors_.size() - 1);
    for (std::size_t k = 0; k + 1 < colors_.size(); ++k) symbols_[k] = symbolBetween(colors_[k], colors_[k + 1]);

    symbolEdges_.clear();
    for (int s = 0; s < kSymbolCount; ++s) {
        const int begin = static_cast<int>(symbolEdges_.size());
        for (int k = 0; k < edgeCount(); ++k)
            if (symbols_[k] == s) symbolEdges_.push_back(k);
        symbolRange_[s] = {begin, static_cast<int>(symbolEdges_.size())};
    }
    windowIndex_.clear();
    for (int k = 0; k + window_ <= edgeCount(); ++k)
        windowIndex_.emplace_back(windowKey(std::span(symbols_).subspan(k, window_)), k);
    std::sort(windowIndex_.begin(), windowIndex_.end());
}

std::span<const int> StripePattern::edgesWithSymbol(SymbolCode symbol) const
{
    if (symbol >= kSymbolCount) return {};
    const auto [begin, end] = symbolRange_[symbol];
    return std::span(symbolEdges_).subspan(begin, end - begin);
}

int StripePattern::findWindow(std::span<const SymbolCode> symbols) const
{
    if (static_cast<int>(symbols.size()) != window_) return -1;
    const std::uint64_t key = windowKey(symbols);
    const auto it = std::lower_bound(windowIndex_.begin(), windowIndex_.end(), std::pair<std::uint64_t, int>{key, -1});
    return (it != windowIndex_.end() && it->first == key) ? it->second : -1;
}

std::string StripePattern::colorLetters() const
{
    std::string out;
    for (Color c : colors_) out += kColorLetters[c];
    return out;
}

Result<StripePattern> StripePattern::generate(int stripes, int window, int stripeWidth, std::uint64_t seed,
                                              std::string_view alphabet)
{
    if (stripes < 2) return Status::error("a pattern needs at least 2 stripes, not " + std::to_string(stripes));
    if (window < 1 || window > kMaxWindow)
        return Status::error("window must be between 1 and " + std::to_string(kMaxWindow));
    std::vector<Color> letters;
    for (char a : alphabet) {
        const int v = colorFromLetter(a);
        if (v < 0) return Status::error(std::string("alphabet letter '") + a + "' is not one of K B G C R M Y W");
        if (std::find(letters.begin(), letters.end(), v) == letters.end()) letters.push_back(static_cast<Color>(v));
    }
    if (letters.size() < 2) return Status::error("the alphabet needs at least 2 distinct colours");

    // Randomised depth-first search with backtracking. Each level chooses the
    // next stripe colour; a choice is kept if it satisfies the neighbour and
    // channel constraints and completes a window not seen before.
    std::mt19937_64 rng(seed);
    std::vector<Color> seq;
    std::vector<SymbolCode> sym;
    std::vector<std::uint64_t> seen;  // sorted window keys in use
    std::vector<std::vector<Color>> options(static_cast<std::size_t>(stripes));
    std::vector<std::uint64_t> addedKey(static_cast<std::size_t>(stripes), ~0ull);
    long budget = 20'000'000;

    auto shuffled = [&] {
        std::vector<Color> o = letters;
        std::shuffle(o.begin(), o.end(), rng);
        return o;
    };
    options[0] = shuffled();
    int level = 0;
    while (level >= 0 && level < stripes) {
        if (--budget < 0) break;
        if (options[level].empty()) {
            // backtrack
            --level;
            if (level < 0) break;
            seq.pop_back();
            if (level > 0) sym.pop_back();  // the symbol that stripe `level` added
            if (addedKey[level] != ~0ull) {
                seen.erase(std::lower_bound(seen.begin(), seen.end(), addedKey[level]));
                addedKey[level] = ~0ull;
            }
            continue;
        }
        const Color c = options[level].back();
        options[level].pop_back();
        if (level > 0) {
            if (c == seq.back()) continue;
            const SymbolCode s = symbolBetween(seq.back(), c);
            if (!sym.empty()) {
                bool ok = true;
                for (int ch = 0; ch < 3; ++ch)
                    ok = ok && (symbolChannel(sym.back(), ch) != 0 || symbolChannel(s, ch) != 0);
                if (!ok) continue;
            }
            sym.push_back(s);
            if (static_cast<int>(sym.size()) >= window) {
                const std::uint64_t key = windowKey(std::span(sym).subspan(sym.size() - window, window));
                const auto it = std::lower_bound(seen.begin(), seen.end(), key);
                if (it != seen.end() && *it == key) {
                    sym.pop_back();
                    continue;
                }
                seen.insert(it, key);
                addedKey[level] = key;
            }
        }
        seq.push_back(c);
        ++level;
        if (level < stripes) options[level] = shuffled();
    }
    if (static_cast<int>(seq.size()) != stripes)
        return Status::error("no pattern of " + std::to_string(stripes) + " stripes with unique windows of " +
                             std::to_string(window) + " edges exists over the alphabet '" + std::string(alphabet) +
                             "' (or the search gave up): use a longer window or more colours");
    std::string colors;
    for (Color c : seq) colors += kColorLetters[c];
    return create(stripeWidth, colors, window);
}

cv::Mat StripePattern::renderSlide(int width, int height, double contrast) const
{
    cv::Mat slide(height, width, CV_8UC3, cv::Scalar::all(0));
    const double on = 255.0;
    const auto off = static_cast<std::uint8_t>(std::lround((1.0 - std::clamp(contrast, 0.0, 1.0)) * on));
    for (int x = 0; x < std::min(width, projectorColumnsUsed()); ++x) {
        const Color c = colors_[x / stripeWidth_];
        const cv::Vec3b bgr(colorChannel(c, kBlue) ? 255 : off, colorChannel(c, kGreen) ? 255 : off,
                            colorChannel(c, kRed) ? 255 : off);
        for (int y = 0; y < height; ++y) slide.at<cv::Vec3b>(y, x) = bgr;
    }
    return slide;
}

}  // namespace stria::pipeline
