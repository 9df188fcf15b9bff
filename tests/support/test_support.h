// Shared helpers for rll's tests: temporary folders, running the program, small renders and
// the statistics the tests assert with.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "rll/core/error.h"

#include "rll/core/image.h"
#include "rll/core/memory_budget.h"
#include "rll/core/rng.h"
#include "rll/lighttree/light_tree.h"
#include "rll/render/integrator.h"
#include "rll/scene/scene.h"

namespace rll::test {

// A fresh folder under the system temp dir, removed with everything in it on destruction.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  const std::filesystem::path& path() const { return m_path; }
  std::filesystem::path operator/(const std::string& name) const { return m_path / name; }
  // Writes a text file in the folder and returns its path.
  std::filesystem::path write(const std::string& name, const std::string& text) const;

 private:
  std::filesystem::path m_path;
};

// The message of the rll::Error that `f` throws; a test failure if it throws none.
template <typename F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected an rll::Error";
  return "";
}

// Expects `message` to contain every one of `parts`.
inline void expect_mentions(const std::string& message, std::initializer_list<std::string> parts) {
  for (const auto& p : parts)
    EXPECT_NE(message.find(p), std::string::npos) << "'" << p << "' not in: " << message;
}

// Runs `read` with the address space allowed to grow by `extra_bytes` at most, then exits: 0
// when it threw an rll::Error (whose message goes to stderr) that is not a failed allocation, or
// when it returned and `may_succeed`; else non-zero. Run in a death test's child: a false size
// claim must be refused without the memory it claims (and without a std::bad_alloc).
[[noreturn]] void run_in_bounded_memory(const std::function<void()>& read, size_t extra_bytes,
                                        bool may_succeed = false);
// `read` refused within 1.5 GiB of address space, with a message matching `pattern`.
#define EXPECT_REFUSED_IN_BOUNDED_MEMORY(read, pattern)                           \
  EXPECT_EXIT(::rll::test::run_in_bounded_memory([&] { read; }, size_t(3) << 29), \
              ::testing::ExitedWithCode(0), pattern)

struct CommandResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};
// Runs the rll program with the given arguments (shell-quoted here). With `timeout_seconds` > 0
// it is killed after that long (exit code 137), so that a command that would run forever fails
// a test instead of hanging it; `wall` receives the wall time.
CommandResult run_rll(const std::vector<std::string>& args, int timeout_seconds = 0,
                      double* wall = nullptr);
// The whole content of a file (empty if it cannot be read).
std::string read_text(const std::filesystem::path& p);
// Runs rll and checks a clean failure: an exit code in [1, 127] (128 + signal is a crash) and
// every one of `mentions` in the output.
void expect_clean_failure(const std::vector<std::string>& args,
                          std::initializer_list<std::string> mentions);
// Runs `rll render <scene> -o <dir>/<output> --quiet --spp 1` and checks a clean failure (an
// exit code in [1, 127]) naming every one of `mentions`, with no image written; returns the
// output for further checks.
std::string render_refused(const TempDir& dir, const std::filesystem::path& scene,
                           std::initializer_list<std::string> mentions,
                           const std::string& output = "out.png");

struct RenderRequest {
  std::string sampler = "power";
  IntegratorSettings integrator;
  int spp = 4;
  uint64_t seed = 1;
  int threads = 0;
  std::vector<std::string> set;  // key=value parameters
  PointSet points = PointSet::Sobol;
};
// A built-in scene (builtin:NAME) at the given film size, finalized.
// A request for `sampler` with `integrator` ("direct" or "path") at `max_depth`, its strategy
// set when not empty ("mis", "nee", "bsdf").
RenderRequest request(const std::string& sampler, const std::string& integrator, int max_depth,
                      const std::string& strategy, int spp, uint64_t seed,
                      PointSet points = PointSet::Sobol);

// Finalized, without a light tree: build_light_tree makes one (and orders the lights), as a
// render session does.
Scene small_builtin_scene(const std::string& name, int width, int height);

// Renders a finalized scene (a copy, with a light tree of its own, as a session would): the mean
// image.
Image render_scene(const Scene& scene, const RenderRequest& request);
// The same over a scene whose lights `tree` (build_light_tree) has ordered: no tree of its own.
Image render_scene(const Scene& scene, const LightTree& tree, const RenderRequest& request);

// Mean over all pixels and channels.
double image_mean(const Image& image);

// Mean and standard error of a per-pixel statistic: the image split into `blocks` groups of
// pixels whose means are treated as independent samples (pixels are rendered independently).
struct Estimate {
  double mean = 0, stderr_ = 0;
};
Estimate block_estimate(const Image& image, int blocks = 64);

// True if |a - b| is within `z` combined standard errors (plus `abs_tol`).
bool agree(const Estimate& a, const Estimate& b, double z = 4.0, double abs_tol = 0.0);

// Per-pixel difference test between two independent renders of the same scene: the mean of
// (a - b) over pixels, with its standard error, must be consistent with zero.
Estimate difference_estimate(const Image& a, const Image& b);
// difference_estimate over each of nx x ny image regions (row by row), so that a bias confined to
// one part of the image (one box of a room, where a learnt cut went wrong) cannot hide in the mean.
// a and b agree over the image and in each of 4 x 4 regions (`what` names them in failures).
// The regional bound is Bonferroni-corrected: 16 regions at z = 4.5 falsely fail with
// probability 1e-4 together.
// Empty if two independent renders agree in mean over the image and in each of 4 x 4 regions
// (z = 4.5 each: 17 bounds falsely fail with probability about 1e-4 together); else the first
// disagreement. The standard errors come from the per-pixel differences of the two images.
std::string region_disagreement(const Image& a, const Image& b);

void expect_images_agree(const Image& a, const Image& b, const std::string& what);
// Region (rx, ry) of the image cut into nx x ny regions (row by row: region_differences' regions).
Image image_region(const Image& image, int rx, int ry, int nx, int ny);

// Mean and standard error over independent renders (seeds) of the image's mean and of each of its
// 4 x 4 regions' means, for renders whose pixels are not independent samples (path-space
// filtering's shared cells, ReSTIR's spatial and temporal reuse); their renders are.
struct SeedEstimates {
  Estimate image;
  std::vector<Estimate> regions;  // row by row
};
SeedEstimates over_seeds(const std::vector<Image>& renders);
std::vector<Estimate> region_differences(const Image& a, const Image& b, int nx, int ny);

// A small memory budget (core/memory_budget.h) for as long as it lives, so that readers' size
// checks are tested without allocating much.
struct BudgetScope {
  explicit BudgetScope(size_t bytes) { set_memory_budget_bytes(bytes); }
  ~BudgetScope() { set_memory_budget_bytes(0); }
};

}  // namespace rll::test
