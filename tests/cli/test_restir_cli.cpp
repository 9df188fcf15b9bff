// `rll render --sampler restir:...` (issue 47, docs/restir.md): the spec renders with the wavefront
// renderer and ReSTIR's stages; restir.* keys without a restir sampler, bad values and
// --filter psf with restir are refused naming the key before anything is written; `rll samplers`
// lists restir and its keys.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "support/test_support.h"

using namespace rll;
using namespace rll::test;
namespace fs = std::filesystem;

namespace {

CommandResult render(const TempDir& dir, std::vector<std::string> extra) {
  std::vector<std::string> args = {
      "render", "builtin:cornell-boxes-room",     "--res", "16x12", "--spp", "2", "--quiet",
      "-o",     (dir.path() / "out.exr").string()};
  args.insert(args.end(), extra.begin(), extra.end());
  return run_rll(args, 120);
}

}  // namespace

TEST(RestirCli, SpecRendersWithTheWavefrontAndItsStages) {
  const TempDir dir;
  const fs::path stats = dir.path() / "stats.json";
  const CommandResult r =
      render(dir, {"--sampler", "restir:source=rll:candidates=8", "--stats", stats.string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::exists(dir.path() / "out.exr"));
  const nlohmann::json j = nlohmann::json::parse(read_text(stats));
  EXPECT_EQ(j.dump().find("\"renderer\":\"megakernel\""), std::string::npos) << j.dump();
  EXPECT_NE(j.dump().find("restir"), std::string::npos) << "its memory is reported";
}

TEST(RestirCli, BadKeysAreRefusedNamingThem) {
  const TempDir dir;
  auto refused = [&](std::vector<std::string> extra, std::initializer_list<std::string> parts) {
    const CommandResult r = render(dir, extra);
    EXPECT_NE(r.exit_code, 0) << r.output;
    expect_mentions(r.output, parts);
    EXPECT_FALSE(fs::exists(dir.path() / "out.exr"));
  };
  refused({"--sampler", "tree", "--set", "restir.candidates=4"}, {"restir.candidates", "restir"});
  refused({"--sampler", "restir:candidates=0"}, {"restir.candidates"});
  refused({"--sampler", "restir", "--set", "restir.weights=fair"}, {"restir.weights", "biased"});
  refused({"--sampler", "restir:source=nosuch"}, {"restir.source"});
  refused({"--sampler", "restir:source=rht"}, {"restir.source=rht"});
  refused({"--sampler", "restir", "--filter", "psf"}, {"--filter psf", "restir"});
  refused({"--sampler", "restir:radiuss=3"}, {"radiuss", "radius"});
}

TEST(RestirCli, SamplersListsRestirAndItsKeys) {
  const CommandResult list = run_rll({"samplers"});
  ASSERT_EQ(list.exit_code, 0);
  EXPECT_NE(list.output.find("restir"), std::string::npos);
  const CommandResult keys = run_rll({"samplers", "--params", "restir"});
  ASSERT_EQ(keys.exit_code, 0) << keys.output;
  expect_mentions(keys.output, {"restir.source", "restir.candidates", "restir.temporal",
                                "restir.history", "restir.spatial", "restir.radius",
                                "restir.weights", "restir.normal", "restir.depth"});
}

// Frames of an animated scene (lights switching and sliding): each frame reuses the last one's
// reservoirs, re-evaluated against the frame's lights; every frame renders, none with a
// non-finite sample.
TEST(RestirCli, AnimatedFramesReuseTheLastFrame) {
  const TempDir dir;
  const fs::path stats = dir.path() / "stats.json";
  const CommandResult r =
      run_rll({"render", "builtin:cornell-boxes-dynamic", "--res", "24x18", "--spp", "1",
               "--frames", "4", "--sampler", "restir", "--quiet", "-o",
               (dir.path() / "f.exr").string(), "--stats", stats.string()},
              120);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (int f = 0; f < 4; ++f)
    EXPECT_TRUE(fs::exists(dir.path() / fmt::format("f.{:04d}.exr", f))) << f;
  const nlohmann::json j = nlohmann::json::parse(read_text(stats));
  EXPECT_EQ(j.at("nonfinite_samples").get<int>(), 0);
}
