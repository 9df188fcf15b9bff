// The checks every output and input goes through (rll/core/file_checks.h) and the atomic writer
// that uses them: devices, pipes, folders and read-only files are never replaced, links are
// written through, identity is by file, not by spelling.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include "rll/core/file_checks.h"
#include "rll/core/image.h"
#include "rll/core/paths.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;
namespace fs = std::filesystem;

namespace {

bool is_named_pipe(const fs::path& p) {
  struct stat st {};
  return ::lstat(p.c_str(), &st) == 0 && S_ISFIFO(st.st_mode);
}

}  // namespace

TEST(FileChecks, OutputsThatAreNotRegularFilesAreRefused) {
  TempDir dir;
  const fs::path fifo = dir / "pipe.json";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  expect_mentions(error_of([&] { check_output_file(fifo, "--stats"); }),
                  {"--stats", "pipe.json", "FIFO"});
  expect_mentions(error_of([&] { write_file_atomic(fifo, "{}"); }), {"pipe.json", "FIFO"});
  EXPECT_TRUE(is_named_pipe(fifo)) << "the FIFO was replaced by a file";
  expect_mentions(error_of([&] { check_output_file(dir.path(), "-o"); }), {"folder"});
  // A link to the FIFO is judged by what it points at.
  fs::create_symlink(fifo, dir / "link.json");
  expect_mentions(error_of([&] { write_file_atomic(dir / "link.json", "{}"); }),
                  {"pipe.json", "FIFO", "link.json"});
  EXPECT_TRUE(fs::is_symlink(dir / "link.json"));
}

TEST(FileChecks, ReadOnlyOutputIsRefusedEvenForRoot) {
  TempDir dir;
  const fs::path ro = dir.write("ro.json", "keep");
  fs::permissions(ro, fs::perms::owner_read | fs::perms::group_read | fs::perms::others_read);
  expect_mentions(error_of([&] { write_file_atomic(ro, "new"); }), {"ro.json", "read-only"});
  EXPECT_EQ(read_text(ro), "keep");
}

TEST(FileChecks, LinksAreWrittenThroughNotReplaced) {
  TempDir dir;
  fs::create_directories(dir / "real");
  const fs::path target = dir.write("real/data.json", "old");
  fs::create_symlink(fs::path("real") / "data.json", dir / "link.json");
  write_file_atomic(dir / "link.json", "new");
  EXPECT_TRUE(fs::is_symlink(dir / "link.json"));
  EXPECT_EQ(read_text(target), "new");
  // The temporary lay beside the target: nothing but the link is left beside the link.
  for (const auto& e : fs::directory_iterator(dir.path()))
    EXPECT_TRUE(e.path().filename() == "link.json" || e.path().filename() == "real") << e.path();
  // A dangling link creates its target.
  fs::create_symlink(fs::path("real") / "new.json", dir / "dangling.json");
  write_file_atomic(dir / "dangling.json", "made");
  EXPECT_EQ(read_text(dir / "real" / "new.json"), "made");
  EXPECT_TRUE(fs::is_symlink(dir / "dangling.json"));
}

TEST(FileChecks, InputsThatAreNotRegularFilesAreRefused) {
  TempDir dir;
  const fs::path fifo = dir / "scene.obj";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  expect_mentions(error_of([&] { check_input_file(fifo, "scene"); }),
                  {"scene", "scene.obj", "FIFO"});
  expect_mentions(error_of([&] { check_input_file(dir.path(), "--rll-state"); }),
                  {"--rll-state", "folder"});
  check_input_file(dir / "missing.obj", "scene");  // left to the reader
  check_input_file(dir.write("ok.obj", ""), "scene");
}

TEST(FileChecks, SameFileIsByIdentityNotSpelling) {
  TempDir dir;
  const fs::path a = dir.write("a.exr", "x");
  EXPECT_TRUE(same_file(a, dir.path() / "." / "a.exr"));
  fs::create_symlink(a, dir / "link.exr");
  EXPECT_TRUE(same_file(a, dir / "link.exr"));
  fs::create_hard_link(a, dir / "hard.exr");
  EXPECT_TRUE(same_file(a, dir / "hard.exr"));
  EXPECT_FALSE(same_file(a, dir.write("b.exr", "x")));
  // Files that do not exist yet compare by their canonical paths.
  EXPECT_TRUE(same_file(dir / "new.exr", dir.path() / "sub" / ".." / "new.exr"));
  EXPECT_FALSE(same_file(dir / "new.exr", dir / "other.exr"));
}

TEST(FileChecks, OverLongNamesAreRefusedBeforeAnyWrite) {
  TempDir dir;
  const fs::path p = dir / (std::string(240, 'n') + ".exr");
  expect_mentions(error_of([&] { check_output_file(p, "-o"); }), {"-o", "file name", "bytes"});
}

TEST(FileChecks, StaleTemporariesOfTheTargetAreRemovedWhenItIsWritten) {
  TempDir dir;
  // PIDs above the kernel's limit (2^22) never run.
  const fs::path stale = dir.write("out.json.tmp-2147483646-0", "stale");
  const fs::path other = dir.write("other.json.tmp-2147483646-0", "not ours to clean now");
  const fs::path alive = dir.write(fmt::format("out.json.tmp-{}-99", ::getppid()), "in use");
  write_file_atomic(dir / "out.json", "{}");
  EXPECT_FALSE(fs::exists(stale));
  EXPECT_TRUE(fs::exists(other));
  EXPECT_TRUE(fs::exists(alive));
}

TEST(FileChecks, NumberedPathsSortInOrderPastNineThousandNineHundredNinetyNine) {
  EXPECT_EQ(numbered_path("a/out.exr", 0, 1), fs::path("a/out.exr"));
  EXPECT_EQ(numbered_path("a/out.exr", 7, 10), fs::path("a/out.0007.exr"));
  EXPECT_EQ(numbered_path("out.png", 9999, 10000), fs::path("out.9999.png"));
  EXPECT_EQ(numbered_path("out.png", 9999, 10001), fs::path("out.09999.png"));
  EXPECT_EQ(numbered_path("out.png", 10000, 10001), fs::path("out.10000.png"));
  EXPECT_LT(numbered_path("out.png", 9999, 100000).string(),
            numbered_path("out.png", 10000, 100000).string());
}
