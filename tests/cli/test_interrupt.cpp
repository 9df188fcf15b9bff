// Ctrl-C (SIGINT) stops a render at the next tile and still writes the image so far, with a
// non-zero exit; the image is complete (written atomically), never a partial file.
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <thread>

#include "rll/core/image.h"
#include "support/test_support.h"

extern char** environ;

using namespace rll;
using namespace rll::test;

TEST(Interrupt, SigintWritesTheImageSoFar) {
  TempDir dir;
  const std::string image = (dir / "partial.exr").string(), stats = (dir / "stats.json").string();
  std::vector<std::string> args = {RLL_BINARY, "render", "builtin:cornell-box", "--res", "64x64", "--spp", "1000000",
                                   "--quiet", "-o", image, "--stats", stats};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  ASSERT_EQ(posix_spawn(&pid, RLL_BINARY, nullptr, nullptr, argv.data(), environ), 0);
  // Let it render a while (scene set-up included), then interrupt.
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  ASSERT_EQ(::kill(pid, SIGINT), 0);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status)) << "killed by a signal instead of stopping cleanly";
  EXPECT_EQ(WEXITSTATUS(status), 130);
  Image img = read_image(image);
  EXPECT_EQ(img.width(), 64);
  EXPECT_EQ(img.height(), 64);
  double sum = 0;
  for (const auto& p : img.pixels()) sum += p.x + p.y + p.z;
  EXPECT_GT(sum, 0) << "the samples rendered before the interrupt must be in the image";
  EXPECT_TRUE(std::filesystem::exists(stats));
  for (const auto& e : std::filesystem::directory_iterator(dir.path()))
    EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos) << "temporary file left: " << e.path();
}
