// The shared button Debouncer (hal/debouncer.hpp) over timelines of raw GPIO
// edges, as GpiodButton feeds it from the kernel's edge events.
#include "hal/debouncer.hpp"

#include <gtest/gtest.h>

#include <utility>
#include <vector>

namespace stria::hal {
namespace {

constexpr std::int64_t kMs = 1'000'000;

struct Edge {
    std::int64_t ms;
    bool active;
};

// Replays edges while polling every millisecond up to endMs; returns the
// times (ms) at which presses were reported.
std::vector<std::int64_t> pressTimes(const std::vector<Edge>& edges, std::int64_t endMs, std::int64_t debounceMs = 20)
{
    Debouncer debouncer(debounceMs * kMs);
    std::vector<std::int64_t> presses;
    std::size_t next = 0;
    for (std::int64_t t = 0; t <= endMs; ++t) {
        for (; next < edges.size() && edges[next].ms == t; ++next) debouncer.edge(t * kMs, edges[next].active);
        if (debouncer.pressBy(t * kMs)) presses.push_back(t);
    }
    return presses;
}

TEST(Debouncer, CleanPressIsReportedOnceAfterTheDebounceTime)
{
    EXPECT_EQ(pressTimes({{100, true}, {400, false}}, 1000), std::vector<std::int64_t>{120});
}

TEST(Debouncer, ContactBounceOnPressAndReleaseGivesExactlyOnePress)
{
    // Typical tactile switch: 5 ms of chatter when closing and when opening.
    const std::vector<Edge> edges = {{100, true}, {101, false}, {102, true}, {104, false}, {105, true},
                                     {500, false}, {501, true}, {502, false}, {503, true}, {505, false}};
    EXPECT_EQ(pressTimes(edges, 1000), std::vector<std::int64_t>{125});
}

TEST(Debouncer, GlitchShorterThanDebounceIsNoPress)
{
    EXPECT_TRUE(pressTimes({{100, true}, {110, false}, {300, true}, {319, false}}, 1000).empty());
}

TEST(Debouncer, TwoSeparatePressesAreTwoPresses)
{
    EXPECT_EQ(pressTimes({{100, true}, {200, false}, {300, true}, {301, false}, {302, true}, {400, false}}, 1000),
              (std::vector<std::int64_t>{120, 322}));
}

TEST(Debouncer, DeadlineTellsWhenToLookAgain)
{
    Debouncer debouncer(20 * kMs);
    EXPECT_FALSE(debouncer.deadline().has_value());
    debouncer.edge(100 * kMs, true);
    debouncer.edge(103 * kMs, false);
    debouncer.edge(104 * kMs, true);
    ASSERT_TRUE(debouncer.deadline().has_value());
    EXPECT_EQ(*debouncer.deadline(), 124 * kMs);
    EXPECT_FALSE(debouncer.pressBy(123 * kMs));
    EXPECT_TRUE(debouncer.pressBy(124 * kMs));
    EXPECT_FALSE(debouncer.deadline().has_value());
}

}  // namespace
}  // namespace stria::hal
