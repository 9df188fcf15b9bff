// `rll compare` and its reference: references rendered in two halves whose noise is subtracted
// from every error, damaged cache entries replaced rather than breaking every later run, stale
// temporaries cleaned, and reference files that cannot be a reference refused.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>

#include "rll/core/image.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;
namespace fs = std::filesystem;

namespace {

CommandResult compare(const TempDir& dir, const std::string& out,
                      std::vector<std::string> extra = {}) {
  std::vector<std::string> args = {"compare", "builtin:cornell-box", "--samplers", "power,tree",
                                   "--spp", "4", "--res", "32x24", "--cache-dir",
                                   (dir / "cache").string(), "--out", (dir / out).string(),
                                   "--quiet"};
  if (std::find(extra.begin(), extra.end(), "--reference") == extra.end())
    extra.insert(extra.end(), {"--reference-spp", "32"});
  args.insert(args.end(), extra.begin(), extra.end());
  return run_rll(args);
}

nlohmann::json summary(const TempDir& dir, const std::string& out) {
  std::ifstream f(dir / out / "summary.json");
  return nlohmann::json::parse(f);
}

std::vector<fs::path> cache_files(const TempDir& dir, const std::string& suffix) {
  std::vector<fs::path> found;
  for (const auto& e : fs::directory_iterator(dir / "cache")) {
    const std::string name = e.path().filename().string();
    if (name.size() >= suffix.size() && name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0)
      found.push_back(e.path());
  }
  return found;
}

}  // namespace

TEST(ReferenceCache, ReferenceHasHalvesAndItsNoiseIsSubtracted) {
  TempDir dir;
  CommandResult r = compare(dir, "a");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(cache_files(dir, ".half.exr").size(), 1u);
  const nlohmann::json j = summary(dir, "a");
  ASSERT_TRUE(j["reference"].contains("noise_relmse")) << j["reference"].dump();
  EXPECT_GT(j["reference"]["noise_relmse"].get<double>(), 0.0);
  for (const auto& s : j["samplers"])
    for (const char* metric : {"relmse", "trimmed_relmse", "mrse", "mse", "efficiency_with_setup"})
      EXPECT_TRUE(s.contains(metric) && !s[metric].is_null()) << metric;
  // The same run measured against the reused reference gives the same, corrected numbers (to
  // float rounding: the cache keeps the mean and one half, and the other is recomputed).
  r = compare(dir, "b");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json k = summary(dir, "b");
  EXPECT_EQ(k["reference"]["source"], "cache");
  const double a = j["samplers"][0]["relmse"]["median"], b = k["samplers"][0]["relmse"]["median"];
  EXPECT_NEAR(b / a, 1.0, 1e-6);
}

TEST(ReferenceCache, DamagedEntryIsReplacedAndStaleTemporariesRemoved) {
  TempDir dir;
  ASSERT_EQ(compare(dir, "a").exit_code, 0);
  const auto main = cache_files(dir, "seed1000003.exr");
  ASSERT_EQ(main.size(), 1u);
  fs::resize_file(main[0], 300);  // truncated, as by a full disk or a killed copy
  // A temporary of a write whose process is gone (pid 2^22 + 1 is above Linux's largest pid_max),
  // and one of a live process (this test's own) that must stay.
  const fs::path stale = main[0].string() + ".tmp-4194305-0";
  const fs::path live = main[0].string() + ".tmp-" + std::to_string(::getpid()) + "-0";
  std::ofstream(stale) << "x";
  std::ofstream(live) << "x";
  CommandResult r = compare(dir, "b");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  expect_mentions(r.output, {"damaged", "deleted"});
  EXPECT_EQ(summary(dir, "b")["reference"]["source"], "rendered");
  EXPECT_FALSE(fs::exists(stale));
  EXPECT_TRUE(fs::exists(live));
  // The replacement is whole: a third run reuses it.
  r = compare(dir, "c");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(summary(dir, "c")["reference"]["source"], "cache");
}

TEST(ReferenceCache, ReferenceFileWithNanOrLowDynamicRangeIsRefused) {
  TempDir dir;
  Image nan_image(32, 24, Rgb(0.5f));
  nan_image[7] = Rgb(std::numeric_limits<float>::quiet_NaN());
  write_image(dir / "nan.exr", nan_image);
  CommandResult r = compare(dir, "a", {"--reference", (dir / "nan.exr").string()});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_LT(r.exit_code, 128);
  expect_mentions(r.output, {"nan.exr", "NaN"});

  write_image(dir / "ldr.png", Image(32, 24, Rgb(0.5f)));
  r = compare(dir, "b", {"--reference", (dir / "ldr.png").string()});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_LT(r.exit_code, 128);
  expect_mentions(r.output, {"ldr.png", "8-bit", ".exr"});
}

TEST(ReferenceCache, PlotMetricIsChecked) {
  TempDir dir;
  expect_clean_failure({"compare", "builtin:cornell-box", "--spp", "1", "--plot-metric", "psnr",
                        "--out", (dir / "x").string()},
                       {"psnr", "trimmed_relmse"});
  CommandResult r = compare(dir, "a", {"--plot-metric", "trimmed_relmse"});
  EXPECT_EQ(r.exit_code, 0) << r.output;
}
