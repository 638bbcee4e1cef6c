#include "pipeline/pattern.hpp"

#include <gtest/gtest.h>

#include <set>

using namespace stria::pipeline;

namespace {

// Independent check of every constraint, written without the class's tables.
void expectValid(const StripePattern& p)
{
    for (int i = 0; i + 1 < p.stripeCount(); ++i) EXPECT_NE(p.color(i), p.color(i + 1)) << "stripe " << i;
    for (int k = 0; k + 1 < p.edgeCount(); ++k)
        for (int ch = 0; ch < 3; ++ch)
            EXPECT_TRUE(symbolChannel(p.edgeSymbol(k), ch) != 0 || symbolChannel(p.edgeSymbol(k + 1), ch) != 0)
                << "edges " << k << "," << k + 1 << " channel " << ch;
    std::set<std::vector<SymbolCode>> windows;
    for (int k = 0; k + p.window() <= p.edgeCount(); ++k) {
        const auto w = p.edgeSymbols().subspan(k, p.window());
        EXPECT_TRUE(windows.insert({w.begin(), w.end()}).second) << "window at " << k << " repeats";
    }
}

}  // namespace

TEST(Symbols, PackingAndNames)
{
    // R (100) -> G (010): red falls, green rises, blue stays.
    const SymbolCode s = symbolBetween(4, 2);
    EXPECT_EQ(symbolChannel(s, kRed), -1);
    EXPECT_EQ(symbolChannel(s, kGreen), 1);
    EXPECT_EQ(symbolChannel(s, kBlue), 0);
    EXPECT_EQ(symbolName(s), "R-G+");
    EXPECT_EQ(reversedSymbol(s), symbolBetween(2, 4));
    EXPECT_EQ(symbolBetween(5, 5), kNullSymbol);
    EXPECT_EQ(symbolName(kNullSymbol), "0");
}

TEST(StripePattern, GeneratesValidPatterns)
{
    for (std::uint64_t seed : {1u, 2u, 3u}) {
        auto p = StripePattern::generate(128, 4, 8, seed);
        ASSERT_TRUE(p) << p.message();
        EXPECT_EQ(p->stripeCount(), 128);
        EXPECT_EQ(p->edgeCount(), 127);
        EXPECT_EQ(p->window(), 4);
        EXPECT_EQ(p->projectorColumnsUsed(), 1024);
        expectValid(*p);
    }
}

TEST(StripePattern, GenerationIsDeterministicPerSeed)
{
    EXPECT_EQ(StripePattern::generate(64, 4, 8, 7)->colorLetters(), StripePattern::generate(64, 4, 8, 7)->colorLetters());
    EXPECT_NE(StripePattern::generate(64, 4, 8, 7)->colorLetters(), StripePattern::generate(64, 4, 8, 8)->colorLetters());
}

TEST(StripePattern, GenerationReportsImpossibleRequests)
{
    // Two colours give one symbol pair alternating: windows of 2 repeat at once.
    auto p = StripePattern::generate(40, 2, 8, 1, "RG");
    ASSERT_FALSE(p);
    EXPECT_NE(p.message().find("no pattern of 40 stripes"), std::string::npos) << p.message();
}

TEST(StripePattern, AcceptsAManufacturedSlide)
{
    auto p = StripePattern::create(8, "CGMRGWBG");
    ASSERT_TRUE(p) << p.message();
    EXPECT_EQ(p->colorLetters(), "CGMRGWBG");
    EXPECT_DOUBLE_EQ(p->edgeColumn(0), 7.5);  // edge before stripe 1 at x = 1*8 - 0.5
    expectValid(*p);
}

TEST(StripePattern, ValidationNamesTheConstraintAndPlace)
{
    auto letter = StripePattern::create(8, "RGXB", 1);
    ASSERT_FALSE(letter);
    EXPECT_EQ(letter.message(), "colors[2] is 'X': each stripe must be one of the letters K B G C R M Y W");

    auto same = StripePattern::create(8, "RGGB", 1);
    ASSERT_FALSE(same);
    EXPECT_EQ(same.message(), "stripes 1 and 2 are both 'G': neighbouring stripes must differ");

    // R->G->R: blue never changes across edges 0 and 1.
    auto channel = StripePattern::create(8, "RGRB", 2);
    ASSERT_FALSE(channel);
    EXPECT_NE(channel.message().find("edges 0 and 1"), std::string::npos) << channel.message();
    EXPECT_NE(channel.message().find("blue unchanged"), std::string::npos) << channel.message();

    // RGB repeated: the window of 2 at edge 0 (R-G+ G-B+) comes again at edge 3.
    auto window = StripePattern::create(8, "RGBRGB", 2);
    ASSERT_FALSE(window);
    EXPECT_EQ(window.message(),
              "the window of 2 edge symbols at edge 0 (R-G+ G-B+) repeats at edge 3: windows must be unique");

    auto width = StripePattern::create(0, "RGB", 1);
    ASSERT_FALSE(width);
    EXPECT_NE(width.message().find("stripe_width is 0"), std::string::npos);
}

TEST(StripePattern, PicksTheSmallestUniqueWindow)
{
    auto p = StripePattern::create(8, "RGBRGB");  // windows of 2 repeat, of 3 do not
    ASSERT_TRUE(p) << p.message();
    EXPECT_EQ(p->window(), 3);
}

TEST(StripePattern, LookupTablesFindEveryPosition)
{
    auto p = StripePattern::generate(128, 4, 8, 5);
    ASSERT_TRUE(p);
    for (int k = 0; k + p->window() <= p->edgeCount(); ++k)
        EXPECT_EQ(p->findWindow(p->edgeSymbols().subspan(k, p->window())), k);
    int listed = 0;
    for (int s = 0; s < kSymbolCount; ++s) {
        for (int edge : p->edgesWithSymbol(static_cast<SymbolCode>(s))) {
            EXPECT_EQ(p->edgeSymbol(edge), s);
            ++listed;
        }
    }
    EXPECT_EQ(listed, p->edgeCount());
    const std::vector<SymbolCode> absent(4, kNullSymbol);
    EXPECT_EQ(p->findWindow(absent), -1);
    EXPECT_EQ(p->findWindow(p->edgeSymbols().subspan(0, 3)), -1);  // wrong length
}

TEST(StripePattern, SlideFollowsThePixelConvention)
{
    auto p = StripePattern::create(4, "RGBW", 1);
    ASSERT_TRUE(p) << p.message();
    const cv::Mat slide = p->renderSlide(20, 3, 0.3);
    ASSERT_EQ(slide.size(), cv::Size(20, 3));
    const int off = 179;  // round((1 - 0.3) * 255)
    // Stripe 0 (R) covers x in [-0.5, 3.5): pixels 0..3; stripe 1 (G) pixels 4..7.
    EXPECT_EQ(slide.at<cv::Vec3b>(1, 3), cv::Vec3b(off, off, 255));
    EXPECT_EQ(slide.at<cv::Vec3b>(1, 4), cv::Vec3b(off, 255, off));
    EXPECT_EQ(slide.at<cv::Vec3b>(1, 8), cv::Vec3b(255, off, off));
    EXPECT_EQ(slide.at<cv::Vec3b>(1, 15), cv::Vec3b(255, 255, 255));
    EXPECT_EQ(slide.at<cv::Vec3b>(1, 16), cv::Vec3b(0, 0, 0));  // beyond the pattern
}
