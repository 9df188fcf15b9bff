// Ctrl-C (SIGINT), SIGTERM and SIGHUP stop a render within its pass (a tile looks every 64
// samples) and still write the image so far, with the exit code 128 + signal; the image is
// complete (written atomically), never a partial file. A second signal does not cut the write
// short. An interrupted `reference -o` writes its sample counts; an interrupted merge leaves no
// temporary and says so.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <sstream>
#include <thread>

#include "rll/core/image.h"
#include "support/test_support.h"

extern char** environ;

using namespace rll;
using namespace rll::test;
namespace fs = std::filesystem;

TEST(Interrupt, SigintWritesTheImageSoFar) {
  TempDir dir;
  const std::string image = (dir / "partial.exr").string(), stats = (dir / "stats.json").string();
  std::vector<std::string> args = {RLL_BINARY, "render",  "builtin:cornell-box",
                                   "--res",    "64x64",   "--spp",
                                   "1000000",  "--quiet", "-o",
                                   image,      "--stats", stats};
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
    EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos)
        << "temporary file left: " << e.path();
}

namespace {

// Starts rll with `args`, its stderr and stdout into `log`.
pid_t spawn_rll(std::vector<std::string> args, const std::string& log) {
  args.insert(args.begin(), RLL_BINARY);
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 2, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 2, 1);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, RLL_BINARY, &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  return rc == 0 ? pid : -1;
}

// Sends `signals` in turn (no pause between them) after `delay`, and returns the wait status.
int signal_and_wait(pid_t pid, std::chrono::milliseconds delay,
                    std::initializer_list<int> signals) {
  std::this_thread::sleep_for(delay);
  for (int sig : signals) EXPECT_EQ(::kill(pid, sig), 0);
  int status = 0;
  EXPECT_EQ(::waitpid(pid, &status, 0), pid);
  return status;
}

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::vector<std::string> long_render(const std::string& image) {
  return {"render", "builtin:cornell-box", "--res", "64x64", "--spp", "1000000", "--quiet", "-o",
          image};
}

}  // namespace

TEST(Interrupt, SigtermAndSighupWriteTheImageSoFar) {
  for (int sig : {SIGTERM, SIGHUP}) {
    SCOPED_TRACE(sig);
    TempDir dir;
    const std::string image = (dir / "partial.exr").string(), log = (dir / "log.txt").string();
    const pid_t pid = spawn_rll(long_render(image), log);
    ASSERT_GT(pid, 0);
    const int status = signal_and_wait(pid, std::chrono::milliseconds(1500), {sig});
    ASSERT_TRUE(WIFEXITED(status)) << "killed by the signal: the image so far is lost";
    EXPECT_EQ(WEXITSTATUS(status), 128 + sig);
    EXPECT_GT(image_mean(read_image(image)), 0);
    expect_mentions(read_text(log), {"interrupted after", "partial.exr"});
  }
}

TEST(Interrupt, ASecondSignalStillWritesTheImage) {
  TempDir dir;
  const std::string image = (dir / "partial.exr").string(), log = (dir / "log.txt").string();
  const pid_t pid = spawn_rll(long_render(image), log);
  ASSERT_GT(pid, 0);
  // Two different signals, so that the second is not merged into the first while pending.
  const int status = signal_and_wait(pid, std::chrono::milliseconds(1500), {SIGINT, SIGTERM});
  ASSERT_TRUE(WIFEXITED(status)) << "killed by the second signal";
  EXPECT_TRUE(WEXITSTATUS(status) == 128 + SIGINT || WEXITSTATUS(status) == 128 + SIGTERM)
      << WEXITSTATUS(status);
  EXPECT_GT(image_mean(read_image(image)), 0);
  expect_mentions(read_text(log), {"already stopping", "partial.exr"});
}

TEST(Interrupt, CompareExits130AfterWritingWhatItHas) {
  TempDir dir;
  const std::string out = (dir / "cmp").string(), log = (dir / "log.txt").string();
  const pid_t pid = spawn_rll({"compare", "builtin:cornell-box", "--samplers", "power,tree",
                               "--time", "60", "--res", "32x24", "--reference-spp", "4",
                               "--cache-dir", (dir / "cache").string(), "--out", out, "--quiet"},
                              log);
  ASSERT_GT(pid, 0);
  const int status = signal_and_wait(pid, std::chrono::milliseconds(3000), {SIGINT});
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 130) << read_text(log);
  EXPECT_EQ(read_image(dir / "cmp" / "reference.exr").width(), 32);
  expect_mentions(read_text(log), {"interrupted during the run of 'power'", out});
}

namespace {

// Waits until process `pid` catches signal `sig` (its handler is installed: /proc's SigCgt).
bool wait_until_caught(pid_t pid, int sig) {
  for (int i = 0; i < 2000; ++i) {
    const std::string status = read_text(fmt::format("/proc/{}/status", pid));
    const size_t at = status.find("SigCgt:");
    if (at != std::string::npos) {
      const uint64_t mask = std::stoull(status.substr(at + 7), nullptr, 16);
      if (mask >> (sig - 1) & 1) return true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return false;
}

int wait_for(pid_t pid) {
  int status = 0;
  EXPECT_EQ(::waitpid(pid, &status, 0), pid);
  return status;
}

}  // namespace

TEST(Interrupt, AReferenceWritesItsSampleCountsSoFar) {
  TempDir dir;
  const fs::path out = dir / "ref.exr";
  const std::string log = (dir / "log").string();
  const pid_t pid =
      spawn_rll({"reference", "builtin:cornell-box", "--res", "32x32", "--spp", "100000000",
                 "--quiet", "--cache-dir", (dir / "c").string(), "-o", out.string()},
                log);
  ASSERT_GT(pid, 0);
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  ASSERT_EQ(::kill(pid, SIGINT), 0);
  const int status = wait_for(pid);
  ASSERT_TRUE(WIFEXITED(status)) << read_text(log);
  EXPECT_EQ(WEXITSTATUS(status), 130) << read_text(log);
  const ExrFile exr = read_exr_file(out);
  ASSERT_EQ(exr.counts.size(), exr.image.pixel_count()) << "no count channel: " << read_text(log);
  for (uint32_t n : exr.counts) ASSERT_GT(n, 0u);
}

TEST(Interrupt, AMergeSaysSoAndLeavesNoTemporary) {
  TempDir dir;
  // Shares large enough that the merge runs a while (0.2 s or more).
  std::vector<std::string> args = {"merge", (dir / "merged.exr").string()};
  for (int i = 0; i < 2; ++i) {
    const std::string share = (dir / fmt::format("share{}.exr", i)).string();
    CommandResult r =
        run_rll({"render", "builtin:cornell-box", "--res", "640x480", "--spp", "1", "--integrator",
                 "direct", "--quiet", "--task", fmt::format("{}/2", i), "-o", share});
    ASSERT_EQ(r.exit_code, 0) << r.output;
    args.push_back(share);
  }
  for (int sig : {SIGTERM, SIGINT, SIGHUP}) {
    SCOPED_TRACE(sig);
    fs::remove(dir / "merged.exr");
    const std::string log = (dir / "log").string();
    const pid_t pid = spawn_rll(args, log);
    ASSERT_GT(pid, 0);
    const bool caught = wait_until_caught(pid, sig);
    ASSERT_EQ(::kill(pid, sig), 0);
    EXPECT_TRUE(caught) << "merge never installed a handler for the signal";
    const int status = wait_for(pid);
    ASSERT_TRUE(WIFEXITED(status)) << "killed by the signal, saying nothing";
    EXPECT_EQ(WEXITSTATUS(status), 128 + sig) << read_text(log);
    expect_mentions(read_text(log), {"interrupted"});
    for (const auto& e : fs::directory_iterator(dir.path()))
      EXPECT_EQ(e.path().string().find(".tmp-"), std::string::npos) << "left: " << e.path();
  }
}

// Ctrl-C inside one long pass (a single pass of 1024 spp, 16 M samples, several seconds on two
// cores; a tile of it 262,144 samples): the render stops within a bound, not at the pass's or the tile's end,
// and writes the image so far, each pixel with the samples it took (the EXR's count channel):
// many none, and the pixels where the threads stopped a part of the 1024.
TEST(Interrupt, SigintStopsInsideALongPass) {
  TempDir dir;
  const fs::path out = dir / "partial.exr";
  const std::string log = (dir / "log").string();
  // The signal must come once the pass has begun: on a loaded machine the start (scene, BVH)
  // can take over a second, and a signal before it ends the program with nothing written, so a
  // try that came too early is made again with a longer wait (the pass lasts seconds more).
  int status = 0;
  double seconds = 0;
  for (int wait_ms : {1500, 4000, 8000}) {
    const pid_t pid = spawn_rll({"render", "builtin:cornell-box", "--res", "128x128", "--spp",
                                 "1024", "--pass-spp", "1024", "--max-pass-spp", "1024",
                                 "--quiet", "-o", out.string()},
                                log);
    ASSERT_GT(pid, 0);
    ASSERT_TRUE(wait_until_caught(pid, SIGINT)) << read_text(log);
    std::this_thread::sleep_for(std::chrono::milliseconds(wait_ms));
    const auto t0 = std::chrono::steady_clock::now();
    ASSERT_EQ(::kill(pid, SIGINT), 0);
    status = wait_for(pid);
    seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (read_text(log).find("nothing was written") == std::string::npos) break;
  }
  ASSERT_TRUE(WIFEXITED(status)) << read_text(log);
  EXPECT_EQ(WEXITSTATUS(status), 130) << read_text(log);
  // Writing a 128x128 EXR takes milliseconds; the bound leaves room for a loaded machine.
  EXPECT_LT(seconds, 5.0) << "the render did not stop inside its pass";
  const ExrFile exr = read_exr_file(out);
  ASSERT_EQ(exr.counts.size(), exr.image.pixel_count()) << "no count channel: " << read_text(log);
  uint64_t total = 0;
  size_t none = 0, part = 0;
  for (uint32_t n : exr.counts) {
    total += n;
    none += n == 0;
    part += n > 0 && n < 1024;
  }
  EXPECT_GT(total, 0u) << "the samples taken before the signal must be in the image";
  EXPECT_GT(none, 0u) << "the pass ran to its end";
  EXPECT_GT(part, 0u) << "the threads finished their pixels (or tiles) before stopping";
  for (size_t i = 0; i < exr.counts.size(); ++i) {
    const Rgb& p = exr.image[i];
    ASSERT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) << i;
    if (exr.counts[i] == 0) {
      EXPECT_EQ(p.x + p.y + p.z, 0.0f) << i;
    }
  }
  expect_mentions(read_text(log), {"interrupted after 0 spp", "partial.exr"});
}
