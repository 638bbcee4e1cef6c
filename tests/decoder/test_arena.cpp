// WorkspaceArena (pipeline/decoder/arena.hpp): the decoder workspace's one
// block, and the arrays planned in it.
#include "pipeline/decoder/arena.hpp"
#include "pipeline/decoder/workspace.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <string>

namespace stria::pipeline {
namespace {

std::uintptr_t address(const void* p) { return reinterpret_cast<std::uintptr_t>(p); }

TEST(WorkspaceArena, ArraysAreAlignedValueInitialisedAndApart)
{
    WorkspaceArena arena;
    ArenaArray<std::uint8_t> bytes;
    ArenaArray<Region> regions;
    ArenaArray<std::int32_t> ints;
    arena.reserve(bytes, 1001);
    arena.reserve(regions, 300);
    arena.reserve(ints, 5);
    EXPECT_FALSE(bytes);
    EXPECT_EQ(arena.bytes(), 0u);
    const std::size_t size = arena.allocate();
    EXPECT_EQ(size, arena.bytes());
    EXPECT_EQ(size % 4096, 0u);
    EXPECT_GE(size, 1001 + 300 * sizeof(Region) + 5 * sizeof(std::int32_t));
    ASSERT_TRUE(bytes && regions && ints);
    for (std::uintptr_t a : {address(bytes.get()), address(regions.get()), address(ints.get())})
        EXPECT_EQ(a % WorkspaceArena::kAlignment, 0u);
    // In order, apart, within the block.
    EXPECT_GE(address(regions.get()), address(bytes.get() + 1001));
    EXPECT_GE(address(ints.get()), address(regions.get() + 300));
    EXPECT_LE(address(ints.get() + 5), address(bytes.get()) + size);
    // As std::make_unique<T[]>(n) gives them: zeros, and Region's own defaults.
    int nonzero = 0, undecoded = 0;
    for (int i = 0; i < 1001; ++i) nonzero += bytes[i] != 0;
    for (int i = 0; i < 300; ++i) undecoded += regions[i].stripe == -1 && regions[i].reference == -1;
    EXPECT_EQ(nonzero, 0);
    EXPECT_EQ(undecoded, 300);
    // Writable end to end.
    bytes[1000] = 7;
    ints[4] = -3;
    EXPECT_EQ(bytes[1000], 7);
    EXPECT_EQ(ints[4], -3);
}

// What the kernel offers: "always [madvise] never" names the mode in brackets.
std::string transparentHugePageMode()
{
    std::ifstream in("/sys/kernel/mm/transparent_hugepage/enabled");
    std::string line;
    if (!std::getline(in, line)) return "";
    const std::size_t open = line.find('['), close = line.find(']');
    return open == std::string::npos || close == std::string::npos ? "" : line.substr(open + 1, close - open - 1);
}

TEST(WorkspaceArena, ABlockOfHugePagesIsTwoMegabyteAlignedAndAdvised)
{
    WorkspaceArena arena;
    ArenaArray<std::int32_t> labels;
    arena.reserve(labels, 3 * WorkspaceArena::kHugePage / sizeof(std::int32_t) + 17);
    arena.allocate();
    labels[0] = 1;
#if defined(__linux__)
    EXPECT_EQ(address(labels.get()) % WorkspaceArena::kHugePage, 0u);
    const std::string mode = transparentHugePageMode();
    // The advice is taken where the kernel has transparent huge pages and
    // they are not switched off; without them madvise fails, and the block
    // is in 4 KB pages.
    if (mode == "always" || mode == "madvise") {
        EXPECT_TRUE(arena.hugePagesAdvised()) << "mode " << mode;
    }
    if (mode.empty()) {
        EXPECT_FALSE(arena.hugePagesAdvised());
    }
#else
    EXPECT_FALSE(arena.hugePagesAdvised());
#endif
}

TEST(WorkspaceArena, ASmallBlockIsAnOrdinaryAllocation)
{
    WorkspaceArena arena;
    ArenaArray<float> values;
    arena.reserve(values, 10);
    EXPECT_EQ(arena.allocate(), 4096u);
    EXPECT_FALSE(arena.hugePagesAdvised());
    EXPECT_EQ(values[9], 0.0f);
}

#if defined(__SANITIZE_ADDRESS__)
// Under AddressSanitizer a stage that writes past its array's end is still
// caught, though the next array follows in the same block.
TEST(WorkspaceArenaDeathTest, WritingPastAnArrayIsReportedUnderAddressSanitizer)
{
    WorkspaceArena arena;
    ArenaArray<std::int32_t> first, second;
    arena.reserve(first, 16);
    arena.reserve(second, 16);
    arena.allocate();
    volatile std::int32_t* p = first.get();
    EXPECT_DEATH(p[16] = 1, "use-after-poison");
}
#endif

}  // namespace
}  // namespace stria::pipeline
