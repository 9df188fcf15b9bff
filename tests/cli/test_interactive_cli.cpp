// `rll interactive` (frames of 1 spp, learning carried across them, stage times) and the renderer
// that `rll render --wavefront` and `rll compare --wavefront` report: the --stats JSON's
// structure and invariants, and clear errors for bad flags.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "rll/wavefront/wavefront.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;

namespace {

// The stats of `rll interactive SCENE` at a tiny resolution, after checking that it succeeded.
nlohmann::json interactive_stats(const TempDir& tmp, const std::string& scene, int frames,
                                 int warmup, std::vector<std::string> extra = {}) {
  const std::string stats = (tmp / "stats.json").string();
  std::vector<std::string> args = {"interactive", scene,
                                   "--res",       "16x12",
                                   "--frames",    std::to_string(frames),
                                   "--warmup",    std::to_string(warmup),
                                   "--stats",     stats};
  args.insert(args.end(), extra.begin(), extra.end());
  const CommandResult r = run_rll(args, 120);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  for (int f = 0; f < frames; ++f) expect_mentions(r.output, {fmt::format("frame {} ", f)});
  expect_mentions(r.output, {"CPU wavefront", "median of"});
  return nlohmann::json::parse(read_text(stats));
}

// What every interactive --stats file must hold: a frame each, every stage time >= 0, the
// stages within the frame's total (rounding aside), the summary's spread ordered, and the
// sampler's passes one per frame (the learning carried from frame to frame).
void expect_valid_stats(const nlohmann::json& j, int frames, int warmup) {
  EXPECT_EQ(j.at("renderer"), "wavefront");
  EXPECT_EQ(j.at("device"), "cpu");
  EXPECT_EQ(j.at("resolution"), nlohmann::json({16, 12}));
  EXPECT_EQ(j.at("spp_per_frame"), 1);
  EXPECT_EQ(j.at("frames_requested"), frames);
  EXPECT_EQ(j.at("warmup"), warmup);
  EXPECT_FALSE(j.at("interrupted").get<bool>());
  ASSERT_EQ(j.at("stages").size(), kWavefrontStages);
  for (size_t s = 0; s < kWavefrontStages; ++s) EXPECT_EQ(j["stages"][s], kWavefrontStageNames[s]);
  const nlohmann::json& fs = j.at("frames");
  ASSERT_EQ(fs.size(), size_t(frames));
  for (int f = 0; f < frames; ++f) {
    SCOPED_TRACE(fmt::format("frame {}", f));
    const nlohmann::json& fr = fs[size_t(f)];
    EXPECT_EQ(fr.at("frame"), f);
    EXPECT_EQ(fr.at("samples"), 16 * 12);
    EXPECT_EQ(fr.at("rays").at("camera"), 16 * 12);
    const double total = fr.at("ms_total").get<double>();
    EXPECT_GT(total, 0);
    double sum = 0;
    ASSERT_EQ(fr.at("ms_stages").size(), kWavefrontStages);
    for (const char* name : kWavefrontStageNames) {
      const double ms = fr["ms_stages"].at(name).get<double>();
      EXPECT_GE(ms, 0) << name;
      sum += ms;
    }
    EXPECT_LE(sum, total * (1 + 1e-9) + 1e-9);
    EXPECT_GT(fr["ms_stages"]["closest_hit"].get<double>(), 0);
  }
  const nlohmann::json& summary = j.at("summary");
  auto expect_spread = [&](const nlohmann::json& sp, const std::string& what) {
    const double lo = sp.at("min"), med = sp.at("median"), hi = sp.at("max");
    EXPECT_GE(lo, 0) << what;
    EXPECT_LE(lo, med) << what;
    EXPECT_LE(med, hi) << what;
  };
  expect_spread(summary.at("ms_total"), "total");
  // The summary leaves the warm-up out: its least total is one of the measured frames'.
  double least = 1e300;
  for (int f = warmup; f < frames; ++f)
    least = std::min(least, fs[size_t(f)]["ms_total"].get<double>());
  EXPECT_EQ(summary["ms_total"]["min"].get<double>(), least);
  for (const char* name : kWavefrontStageNames)
    expect_spread(summary.at("ms_stages").at(name), name);
  // One end_pass per frame: what a frame learnt is what the next samples from.
  EXPECT_EQ(j.at("sampler").at("name"), "rll");
  EXPECT_EQ(j["sampler"].at("passes"), frames);
}

}  // namespace

TEST(InteractiveCli, StaticSceneFramesCarryTheLearning) {
  TempDir tmp;
  const nlohmann::json j = interactive_stats(tmp, "builtin:cornell-boxes-room", 4, 1,
                                             {"-o", (tmp / "accumulated.exr").string()});
  expect_valid_stats(j, 4, 1);
  EXPECT_FALSE(j.at("animated").get<bool>());
  EXPECT_TRUE(std::filesystem::exists(tmp / "accumulated.exr"));
}

TEST(InteractiveCli, AnimatedSceneFollowsItsFrames) {
  TempDir tmp;
  const nlohmann::json j =
      interactive_stats(tmp, "builtin:cornell-boxes-dynamic", 3, 0, {"--integrator", "direct"});
  expect_valid_stats(j, 3, 0);
  EXPECT_TRUE(j.at("animated").get<bool>());
  EXPECT_EQ(j.at("integrator").at("name"), "direct");
}

// One frame is measured by default: the warm-up then leaves it in the summary.
TEST(InteractiveCli, OneFrameIsItsOwnSummary) {
  TempDir tmp;
  const std::string stats = (tmp / "one.json").string();
  const CommandResult r = run_rll(
      {"interactive", "builtin:cornell-box", "--res", "8x6", "--frames", "1", "--stats", stats},
      60);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(read_text(stats));
  EXPECT_EQ(j.at("warmup"), 0);
  EXPECT_EQ(j.at("summary").at("ms_total").at("median"), j.at("frames")[0].at("ms_total"));
}

TEST(InteractiveCli, DefaultsAre1080pAndTheWavefrontInHelp) {
  const CommandResult r = run_rll({"interactive", "--help"}, 30);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  expect_mentions(r.output,
                  {"1920x1080", "--frames", "--warmup", "--stats", "--sampler", "CPU wavefront"});
}

TEST(InteractiveCli, BadFlagsAreClearErrors) {
  TempDir tmp;
  const std::string scene = "builtin:cornell-box";
  expect_clean_failure({"interactive", scene, "--frames", "0"}, {"--frames"});
  expect_clean_failure({"interactive", scene, "--frames", "abc"}, {"--frames"});
  expect_clean_failure({"interactive", scene, "--frames", "3", "--warmup", "3"},
                       {"--warmup 3", "--frames 3"});
  expect_clean_failure({"interactive", scene, "--warmup", "-1"}, {"--warmup"});
  expect_clean_failure({"interactive", scene, "--res", "0x10"}, {"--res"});
  expect_clean_failure({"interactive", scene, "--sampler", "nope"}, {"--sampler", "nope"});
  expect_clean_failure(
      {"interactive", scene, "--res", "8x8", "--stats", (tmp / "stats.txt").string()},
      {"--stats", ".json"});
  expect_clean_failure({"interactive", scene, "--res", "8x8", "-o", (tmp / "x.bmp").string()},
                       {"-o"});
  expect_clean_failure({"interactive", scene, "--res", "8x8", "-o", (tmp / "same.json").string(),
                        "--stats", (tmp / "same.json").string()},
                       {"-o"});
  expect_clean_failure({"interactive", "builtin:no-such-scene", "--res", "8x8"}, {"no-such-scene"});
}

// The renderer each command reports: `wavefront` with --wavefront, `megakernel` without.
TEST(WavefrontCli, RenderStatsNameTheRenderer) {
  TempDir tmp;
  for (const bool wavefront : {true, false}) {
    SCOPED_TRACE(wavefront);
    const std::string stats = (tmp / "render.json").string();
    std::vector<std::string> args = {
        "render", "builtin:cornell-box",         "--res",  "12x12", "--spp", "2", "--stats", stats,
        "-o",     (tmp / "render.png").string(), "--quiet"};
    if (wavefront) args.push_back("--wavefront");
    const CommandResult r = run_rll(args, 120);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const nlohmann::json j = nlohmann::json::parse(read_text(stats));
    EXPECT_EQ(j.at("renderer"), wavefront ? "wavefront" : "megakernel");
    EXPECT_EQ(j.at("spp"), 2);
  }
}

TEST(WavefrontCli, CompareSummaryNamesTheRenderer) {
  TempDir tmp;
  for (const bool wavefront : {true, false}) {
    SCOPED_TRACE(wavefront);
    const std::string out = (tmp / (wavefront ? "wf" : "mk")).string();
    std::vector<std::string> args = {"compare",         "builtin:cornell-box",
                                     "--res",           "12x12",
                                     "--samplers",      "power",
                                     "--spp",           "2",
                                     "--reference-spp", "8",
                                     "--cache-dir",     (tmp / "cache").string(),
                                     "--out",           out,
                                     "--quiet"};
    if (wavefront) args.push_back("--wavefront");
    const CommandResult r = run_rll(args, 120);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const nlohmann::json j = nlohmann::json::parse(read_text(out + "/summary.json"));
    EXPECT_EQ(j.at("renderer"), wavefront ? "wavefront" : "megakernel");
  }
}
