// stria pattern: generate, validate and draw stripe patterns.
#include "firmware/cli.hpp"
#include "firmware/formats/atomic_file.hpp"
#include "firmware/formats/pattern_file.hpp"

#include "firmware/formats/image_file.hpp"

#include <cstdio>

namespace stria::firmware {
namespace {

constexpr const char* kUsage = R"(usage:
  stria pattern generate --stripes N --window W [--stripe-width PX] [--seed S]
                         [--alphabet LETTERS] --out PATTERN.yaml
  stria pattern validate PATTERN.yaml
  stria pattern validate --colors LETTERS [--stripe-width PX] [--window W]
  stria pattern slide PATTERN.yaml --width PX --height PX [--contrast C] --out SLIDE.png

Colours are letters K B G C R M Y W (0..7: bit 2 red, bit 1 green, bit 0 blue).
A valid pattern has different neighbouring stripes, changes every channel at
least once in any two consecutive edges, and every window of W consecutive edge
symbols occurs once. The slide is drawn from projector column 0; a channel that
is off has (1 - C) times the on level (C = contrast, 1 by default).)";

int run(std::span<const std::string> argv);
const Command kPattern{"pattern", "generate, validate and draw stripe patterns", kUsage, run};

int generate(Args& args)
{
    if (!args.require({"stripes", "window", "out"})) return usageError(kPattern, args.error());
    const long stripes = args.integer("stripes", 0);
    const long window = args.integer("window", 0);
    const long width = args.integer("stripe-width", 8);
    const long seed = args.integer("seed", 1);
    if (!args.ok()) return usageError(kPattern, args.error());
    auto pattern = pipeline::StripePattern::generate(static_cast<int>(stripes), static_cast<int>(window),
                                                     static_cast<int>(width), static_cast<std::uint64_t>(seed),
                                                     args.valueOr("alphabet", std::string(pipeline::kColorLetters)));
    if (!pattern) return failure("pattern", pattern.message());
    const std::string out = *args.value("out");
    if (Status s = savePatternFile(*pattern, out); !s) return failure("pattern", s.message());
    std::printf("wrote %s: %d stripes of %d px, window %d, %d projector columns\n  %s\n", out.c_str(),
                pattern->stripeCount(), pattern->stripeWidth(), pattern->window(), pattern->projectorColumnsUsed(),
                pattern->colorLetters().c_str());
    return kExitOk;
}

int validate(Args& args)
{
    if (args.has("colors")) {
        const long width = args.integer("stripe-width", 8);
        const long window = args.integer("window", 0);
        if (!args.ok()) return usageError(kPattern, args.error());
        auto pattern = pipeline::StripePattern::create(static_cast<int>(width), *args.value("colors"),
                                                       static_cast<int>(window));
        if (!pattern) return failure("pattern", "invalid pattern: " + pattern.message());
        std::printf("valid: %d stripes, %d edges, every window of %d edge symbols is unique\n",
                    pattern->stripeCount(), pattern->edgeCount(), pattern->window());
        return kExitOk;
    }
    if (args.positional().size() != 2) return usageError(kPattern, "validate needs a pattern file or --colors");
    auto pattern = loadPatternFile(args.positional()[1]);
    if (!pattern) return failure("pattern", "invalid " + pattern.message());
    std::printf("valid: %s: %d stripes of %d px, %d edges, every window of %d edge symbols is unique\n",
                args.positional()[1].c_str(), pattern->stripeCount(), pattern->stripeWidth(), pattern->edgeCount(),
                pattern->window());
    return kExitOk;
}

int slide(Args& args)
{
    if (args.positional().size() != 2) return usageError(kPattern, "slide needs a pattern file");
    if (!args.require({"width", "height", "out"})) return usageError(kPattern, args.error());
    const long width = args.integer("width", 0);
    const long height = args.integer("height", 0);
    const double contrast = args.number("contrast", 1.0);
    if (!args.ok()) return usageError(kPattern, args.error());
    if (width <= 0 || height <= 0 || width > 16384 || height > 16384)
        return usageError(kPattern, "--width and --height must be between 1 and 16384");
    if (!(contrast > 0.0 && contrast <= 1.0)) return usageError(kPattern, "--contrast must be in (0, 1]");
    auto pattern = loadPatternFile(args.positional()[1]);
    if (!pattern) return failure("pattern", pattern.message());
    if (pattern->projectorColumnsUsed() > width)
        return failure("pattern", "the pattern needs " + std::to_string(pattern->projectorColumnsUsed()) +
                                      " projector columns but the slide is only " + std::to_string(width) + " wide");
    const cv::Mat image = pattern->renderSlide(static_cast<int>(width), static_cast<int>(height), contrast);
    const std::string out = *args.value("out");
    if (Status s = writePng(out, image); !s) return failure("pattern", s.message());
    std::printf("wrote %s (%ldx%ld, contrast %.2f)\n", out.c_str(), width, height, contrast);
    return kExitOk;
}

int run(std::span<const std::string> argv)
{
    Args args(argv, {"stripes", "window", "stripe-width", "seed", "alphabet", "out", "colors", "width", "height",
                     "contrast"},
              {});
    if (!args.ok()) return usageError(kPattern, args.error());
    if (args.positional().empty()) return usageError(kPattern, "missing action: generate, validate or slide");
    const std::string& action = args.positional()[0];
    if (action == "generate") return generate(args);
    if (action == "validate") return validate(args);
    if (action == "slide") return slide(args);
    return usageError(kPattern, "unknown action '" + action + "'");
}

}  // namespace

STRIA_COMMAND(pattern, kPattern);

}  // namespace stria::firmware
