#include "firmware/formats/pattern_file.hpp"

#include <gtest/gtest.h>

#include <filesystem>

using namespace stria::firmware;

TEST(PatternFile, AcceptsTheTwoMinimalKeys)
{
    auto p = parsePattern("stripe_width: 8\ncolors: \"CGMRGWBG\"\n", "slide.yaml");
    ASSERT_TRUE(p) << p.message();
    EXPECT_EQ(p->stripeWidth(), 8);
    EXPECT_EQ(p->colorLetters(), "CGMRGWBG");
}

TEST(PatternFile, RoundTripsThroughSave)
{
    auto p = stria::pipeline::StripePattern::generate(128, 4, 8, 9);
    ASSERT_TRUE(p);
    const auto path = (std::filesystem::temp_directory_path() / "stria-pattern-roundtrip.yaml").string();
    ASSERT_TRUE(savePatternFile(*p, path));
    auto back = loadPatternFile(path);
    ASSERT_TRUE(back) << back.message();
    EXPECT_EQ(back->colorLetters(), p->colorLetters());
    EXPECT_EQ(back->window(), 4);
    std::filesystem::remove(path);
}

TEST(PatternFile, ErrorsNameFileKeyAndConstraint)
{
    auto missing = parsePattern("colors: RGB\n", "p.yaml");
    ASSERT_FALSE(missing);
    EXPECT_EQ(missing.message(), "pattern 'p.yaml': missing key 'stripe_width'");

    auto type = parsePattern("stripe_width: wide\ncolors: RGB\n", "p.yaml");
    ASSERT_FALSE(type);
    EXPECT_EQ(type.message(), "pattern 'p.yaml': key 'stripe_width' must be a whole number");

    auto invalid = parsePattern("stripe_width: 8\ncolors: RGGB\n", "p.yaml");
    ASSERT_FALSE(invalid);
    EXPECT_EQ(invalid.message(), "pattern 'p.yaml': stripes 1 and 2 are both 'G': neighbouring stripes must differ");

    auto window = parsePattern("stripe_width: 8\ncolors: RGBRGB\nwindow: 2\n", "p.yaml");
    ASSERT_FALSE(window);
    EXPECT_NE(window.message().find("repeats at edge 3"), std::string::npos) << window.message();
}

// OpenCV's YAML reader keeps "# ..." in an unquoted string; stria drops it as YAML would.
TEST(PatternFile, TrailingCommentIsNotPartOfTheColours)
{
    auto p = parsePattern("stripe_width: 8  # projector px\ncolors: CGMRGWBG   # the manufactured slide\n", "slide.yaml");
    ASSERT_TRUE(p) << p.message();
    EXPECT_EQ(p->colorLetters(), "CGMRGWBG");
}
