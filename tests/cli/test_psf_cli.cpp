// `--filter psf` on the command line (render/psf.h, docs/psf.md): a filtered render writes its
// image and says in --stats how many cells and paths the filter used; bad psf.* values, psf keys
// without the filter and a filtered reference are refused before anything is written, naming the
// key; `rll filters` lists the filters and the psf keys from their table.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "rll/core/image.h"
#include "rll/render/psf.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;
namespace fs = std::filesystem;

namespace {

std::vector<std::string> render_args(const fs::path& out, std::vector<std::string> extra) {
  std::vector<std::string> args = {
      "render", "builtin:cornell-box", "--res", "32x24", "--spp", "2", "--quiet",
      "-o",     out.string()};
  args.insert(args.end(), extra.begin(), extra.end());
  return args;
}

}  // namespace

TEST(PsfCli, FilteredRenderReportsItsCellsAndPaths) {
  TempDir dir;
  const fs::path out = dir / "psf.exr", stats = dir / "psf.json";
  const CommandResult r =
      run_rll(render_args(out, {"--filter", "psf", "--sampler", "power", "--stats", stats.string(),
                                "--set", "psf.width=2"}));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  ASSERT_TRUE(fs::exists(out));
  const nlohmann::json j = nlohmann::json::parse(read_text(stats));
  const nlohmann::json& f = j.at("filter");
  EXPECT_EQ(f.at("name"), "psf");
  EXPECT_EQ(f.at("width"), 2.0);
  EXPECT_EQ(f.at("depth"), 1);
  EXPECT_EQ(f.at("batches"), 2);
  EXPECT_GT(f.at("cells_used").get<double>(), 0);
  EXPECT_GT(f.at("paths_filtered").get<double>(), 0);
  EXPECT_LT(f.at("cells_per_batch").get<double>(), f.at("paths_filtered").get<double>() / 2);
  EXPECT_GT(f.at("filtered_share").get<double>(), 0.3);
  EXPECT_LE(f.at("filtered_share").get<double>(), 1.0);
  // Unfiltered: the stats say so.
  const CommandResult plain = run_rll(render_args(out, {"--stats", stats.string()}));
  ASSERT_EQ(plain.exit_code, 0) << plain.output;
  EXPECT_EQ(nlohmann::json::parse(read_text(stats)).at("filter").at("name"), "none");
}

// `rll interactive --filter psf`: its frames filtered, its --stats naming the filter.
TEST(PsfCli, InteractiveFiltersItsFrames) {
  TempDir dir;
  const fs::path stats = dir / "frames.json";
  const CommandResult r =
      run_rll({"interactive", "builtin:cornell-box", "--res", "24x16", "--frames", "2", "--quiet",
               "--filter", "psf", "--sampler", "power", "--stats", stats.string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(read_text(stats));
  EXPECT_EQ(j.at("filter").at("name"), "psf");
  EXPECT_EQ(j.at("filter").at("width"), 3.0);
}

// psf.temporal: interactive's frames blend the last frame's cells, counted in --stats with the
// host table's memory; `render --frames` blends too; a bad weight is refused naming the key.
TEST(PsfCli, TemporalReuseBlendsFramesAndSaysSo) {
  TempDir dir;
  const fs::path stats = dir / "frames.json";
  const CommandResult r =
      run_rll({"interactive", "builtin:cornell-box", "--res", "24x16", "--frames", "3", "--quiet",
               "--filter", "psf", "--sampler", "power", "--set", "psf.temporal=0.5", "--stats",
               stats.string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json f = nlohmann::json::parse(read_text(stats)).at("filter");
  EXPECT_EQ(f.at("temporal"), 0.5);
  EXPECT_EQ(f.at("batches"), 3);
  EXPECT_GT(f.at("cells_reused").get<double>(), 0);
  EXPECT_LE(f.at("cells_reused").get<double>(), f.at("cells_used").get<double>());
  EXPECT_EQ(f.at("temporal_bytes"), 24 * 16 * kPsfTemporalBytesPerPixel);
  const fs::path out = dir / "f.exr", render_stats = dir / "render.json";
  const CommandResult frames =
      run_rll(render_args(out, {"--filter", "psf", "--frames", "2", "--set", "psf.temporal=0.9",
                                "--stats", render_stats.string()}));
  ASSERT_EQ(frames.exit_code, 0) << frames.output;
  EXPECT_GT(
      nlohmann::json::parse(read_text(render_stats)).at("filter").at("cells_reused").get<double>(),
      0);
  // A still render blends nothing and allocates no second table.
  const fs::path still_stats = dir / "still.json";
  const CommandResult still = run_rll(render_args(
      out, {"--filter", "psf", "--set", "psf.temporal=0.9", "--stats", still_stats.string()}));
  ASSERT_EQ(still.exit_code, 0) << still.output;
  EXPECT_EQ(nlohmann::json::parse(read_text(still_stats)).at("filter").at("temporal_bytes"), 0);
  expect_clean_failure({"render", "builtin:cornell-box", "--filter", "psf", "--set",
                        "psf.temporal=1", "-o", (dir / "x.png").string()},
                       {"psf.temporal", "[0, 1)"});
}

TEST(PsfCli, BadValuesAndMisplacedKeysAreRefusedNamingThem) {
  TempDir dir;
  const fs::path out = dir / "x.png";
  struct Case {
    std::vector<std::string> extra;
    std::vector<std::string> mentions;
  };
  for (const Case& c : std::vector<Case>{
           {{"--filter", "psf", "--set", "psf.width=0"}, {"psf.width", "(0, 1000000]"}},
           {{"--filter", "psf", "--set", "psf.clamp=-1"}, {"psf.clamp"}},
           {{"--filter", "psf", "--set", "psf.max_prob=x"}, {"psf.max_prob"}},
           {{"--filter", "psf", "--set", "psf.depth=5"}, {"psf.depth", "--max-depth"}},
           {{"--filter", "psf", "--set", "psf.bogus=1"}, {"psf.bogus"}},
           {{"--set", "psf.width=2"}, {"psf.width", "--filter psf"}},
           {{"--filter", "bilateral"}, {"--filter", "bilateral"}},
           {{"--filter", "psf", "--sampler", "power:psf.width=-2"}, {"psf.width"}}}) {
    const CommandResult r = run_rll(render_args(out, c.extra));
    SCOPED_TRACE(r.output);
    EXPECT_GE(r.exit_code, 1);
    EXPECT_LT(r.exit_code, 128);
    for (const std::string& m : c.mentions)
      EXPECT_NE(r.output.find(m), std::string::npos) << "missing: " << m;
    EXPECT_FALSE(fs::exists(out));
  }
}

TEST(PsfCli, ReferenceRefusesTheFilter) {
  TempDir dir;
  expect_clean_failure({"reference", "builtin:cornell-box", "--res", "8x8", "--spp", "2",
                        "--filter", "psf", "--cache-dir", (dir / "cache").string()},
                       {"--filter psf", "reference", "unfiltered"});
  EXPECT_FALSE(fs::exists(dir / "cache"));
}

TEST(PsfCli, FiltersCommandListsTheFilterAndItsKeys) {
  const CommandResult names = run_rll({"filters"});
  ASSERT_EQ(names.exit_code, 0) << names.output;
  EXPECT_EQ(names.output, "none\npsf\n");
  const CommandResult keys = run_rll({"filters", "--params", "psf"});
  ASSERT_EQ(keys.exit_code, 0) << keys.output;
  for (const char* k : {"psf.depth=-1", "psf.width=3", "psf.max_prob=32", "psf.min_dist=0",
                        "psf.clamp=100", "psf.temporal=0", "psf.demodulate=1"})
    EXPECT_NE(keys.output.find(k), std::string::npos) << k << " in " << keys.output;
  expect_clean_failure({"filters", "--params", "bilateral"}, {"bilateral", "psf"});
}
