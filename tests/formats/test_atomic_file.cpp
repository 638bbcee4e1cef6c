#include "firmware/formats/atomic_file.hpp"

#include <gtest/gtest.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <sys/resource.h>

using namespace stria::firmware;
namespace fs = std::filesystem;

namespace {

fs::path freshDir(const char* name)
{
    const fs::path dir = fs::temp_directory_path() / name;
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

int filesIn(const fs::path& dir)
{
    int n = 0;
    for ([[maybe_unused]] const auto& entry : fs::directory_iterator(dir)) ++n;
    return n;
}

}  // namespace

TEST(AtomicFile, WritesAndReplaces)
{
    const fs::path dir = freshDir("stria-atomic-ok");
    const std::string path = (dir / "a.txt").string();
    ASSERT_TRUE(writeFileAtomically(path, std::string("first")));
    ASSERT_TRUE(writeFileAtomically(path, std::string("second")));
    std::ifstream in(path);
    std::string text;
    in >> text;
    EXPECT_EQ(text, "second");
    EXPECT_EQ(filesIn(dir), 1);  // no temporaries left behind
}

TEST(AtomicFile, MissingDirectoryIsNamed)
{
    const auto s = writeFileAtomically("/nonexistent-dir/out.ply", std::string("x"));
    ASSERT_FALSE(s);
    EXPECT_EQ(s.message(), "cannot create '/nonexistent-dir/out.ply': No such file or directory");
}

TEST(AtomicFile, AbandonedFileLeavesNothing)
{
    const fs::path dir = freshDir("stria-atomic-abandon");
    {
        auto file = AtomicFile::create((dir / "b.bin").string());
        ASSERT_TRUE(file);
        ASSERT_TRUE(file->write("abc", 3));
        EXPECT_EQ(filesIn(dir), 1);  // the temporary
    }  // destroyed without commit()
    EXPECT_EQ(filesIn(dir), 0);
}

// A write that fails part-way (here: the file size limit, standing in for a
// full disk) must leave neither the final file nor a temporary, and the old
// file must survive.
TEST(AtomicFile, FailedWriteKeepsTheOldFile)
{
    const fs::path dir = freshDir("stria-atomic-full");
    const std::string path = (dir / "c.bin").string();
    ASSERT_TRUE(writeFileAtomically(path, std::string("old")));

    std::signal(SIGXFSZ, SIG_IGN);
    rlimit old{};
    getrlimit(RLIMIT_FSIZE, &old);
    rlimit small = old;
    small.rlim_cur = 4096;
    ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &small), 0);
    const std::vector<unsigned char> big(100000, 7);
    const auto s = writeFileAtomically(path, big);
    setrlimit(RLIMIT_FSIZE, &old);

    ASSERT_FALSE(s);
    EXPECT_NE(s.message().find("cannot write '" + path + "': File too large"), std::string::npos) << s.message();
    EXPECT_EQ(fs::file_size(path), 3u);
    EXPECT_EQ(filesIn(dir), 1);
}
