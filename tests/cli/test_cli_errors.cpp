// The `rll` program on bad input: a non-zero exit (never a crash: exit code < 128), a message
// naming the file (and line) or the flag, and no image written.
#include <gtest/gtest.h>

#include <filesystem>

#include "support/test_support.h"

using namespace rll::test;
namespace fs = std::filesystem;

namespace {

const char* kTriangle = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";

// Runs `rll render <args...> -o <dir>/out.png` and checks the failure: exit code in [1, 127],
// every one of `mentions` in the output, and no image left behind.
void expect_render_error(const TempDir& dir, std::vector<std::string> args,
                         std::initializer_list<std::string> mentions,
                         const std::string& output = "out.png") {
  const fs::path out = dir / output;
  args.insert(args.begin(), "render");
  args.insert(args.end(), {"-o", out.string(), "--quiet"});
  expect_clean_failure(args, mentions);
  EXPECT_FALSE(fs::exists(out));
}

}  // namespace

TEST(CliErrors, MissingSceneFile) {
  TempDir dir;
  expect_render_error(dir, {(dir / "nothere.json").string()}, {"nothere.json", "not found"});
  expect_render_error(dir, {(dir / "nothere.obj").string()}, {"nothere.obj", "not found"});
}

TEST(CliErrors, MalformedJson) {
  TempDir dir;
  auto p = dir.write("bad.json", "{\n  \"film\": {\"width\": 8,, \"height\": 8}\n}\n");
  expect_render_error(dir, {p.string()}, {"bad.json:2:", "invalid JSON"});
}

TEST(CliErrors, UnknownJsonField) {
  TempDir dir;
  auto p = dir.write("typo.json", R"({"camer": {"position": [0, 0, 1], "target": [0, 0, 0]}})");
  expect_render_error(dir, {p.string()}, {"typo.json", "unknown field \"camer\" in /"});
}

TEST(CliErrors, MalformedObj) {
  TempDir dir;
  auto p = dir.write("bad.obj", std::string(kTriangle) + "f 1 2 3\nf 1 2 7\n");
  expect_render_error(dir, {p.string()}, {"bad.obj:5:", "index 7"});
  auto q = dir.write("garbage.obj", std::string(kTriangle) + "v 1 two 3\nf 1 2 3\n");
  expect_render_error(dir, {q.string()}, {"garbage.obj:4:", "'two'"});
}

TEST(CliErrors, MalformedObjReferencedFromJson) {
  TempDir dir;
  dir.write("mesh.obj", std::string(kTriangle) + "f 1 2 0\n");
  auto p = dir.write("scene.json", R"({"shapes": [{"file": "mesh.obj"}]})");
  expect_render_error(dir, {p.string()}, {"scene.json", "/shapes/0", "mesh.obj:4:"});
}

TEST(CliErrors, NanVertex) {
  TempDir dir;
  auto p = dir.write("nan.obj", "v 0 0 0\nv 1 0 0\nv 0 NaN 0\nf 1 2 3\n");
  expect_render_error(dir, {p.string()}, {"nan.obj:3:", "NaN"});
}

TEST(CliErrors, InfiniteVertex) {
  TempDir dir;
  auto p = dir.write("inf.obj", "v 0 0 0\nv 1e40 0 0\nv 0 1 0\nf 1 2 3\n");
  expect_render_error(dir, {p.string()}, {"inf.obj:2:", "finite"});
  auto q = dir.write("inf2.obj", "v 0 0 0\nv 1 0 0\nv 0 1 -inf\nf 1 2 3\n");
  expect_render_error(dir, {q.string()}, {"inf2.obj:3:"});
}

TEST(CliErrors, SceneWithoutLights) {
  TempDir dir;
  auto p = dir.write("dark.obj", std::string(kTriangle) + "f 1 2 3\n");
  expect_render_error(dir, {p.string()}, {"dark.obj", "no lights"});
  auto q = dir.write("dark.json",
                     R"({"shapes": [{"type": "box", "min": [0, 0, 0], "max": [1, 1, 1]}]})");
  expect_render_error(dir, {q.string()}, {"dark.json", "no lights"});
}

TEST(CliErrors, MissingMaterialLibrary) {
  TempDir dir;
  auto p = dir.write("m.obj", "mtllib gone.mtl\n" + std::string(kTriangle) + "f 1 2 3\n");
  expect_render_error(dir, {p.string()}, {"m.obj:1:", "gone.mtl"});
}

TEST(CliErrors, BadFlags) {
  TempDir dir;
  const std::string scene = "builtin:cornell-box";
  expect_render_error(dir, {scene, "--sppp", "4"}, {"--sppp"});
  expect_render_error(dir, {scene, "--res", "8x8", "--spp", "1", "--sampler", "nope"}, {"nope"});
  expect_render_error(dir, {scene, "--res", "8x8", "--spp", "1", "--set", "rll.nope=1"},
                      {"rll.nope"});
  expect_render_error(dir, {scene, "--res", "0x10"}, {"--res", "0x10"});
  expect_render_error(dir, {scene, "--res", "10by10"}, {"--res", "10by10"});
  expect_render_error(dir, {scene, "--res", "8x8", "--spp", "1"}, {"out.txt", ".png"}, "out.txt");
}

TEST(CliErrors, AGoodSceneStillRenders) {
  // The counterpart of the cases above: the same kind of files, well formed, render.
  TempDir dir;
  dir.write("lamp.mtl", "newmtl lamp\nKe 2 2 2\n");
  auto p =
      dir.write("lit.obj", "mtllib lamp.mtl\n" + std::string(kTriangle) + "usemtl lamp\nf 1 2 3\n");
  CommandResult r = run_rll({"render", p.string(), "--res", "8x8", "--spp", "1", "--quiet", "-o",
                             (dir / "o.png").string()});
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::exists(dir / "o.png"));
}

// Resampled next-event estimation: M bounded (no allocation per sample), and the wavefront
// renderer, which has no resampling yet, refuses it rather than render one light sample.
TEST(CliErrors, NeeCandidates) {
  TempDir dir;
  for (const char* m : {"0", "65", "x"})
    expect_render_error(dir,
                        {"builtin:cornell-box", "--res", "8x8", "--spp", "1", "--set",
                         std::string("nee.candidates=") + m},
                        {"nee.candidates"});
  // Its target: one of the listed values, the error naming the key and the values.
  expect_render_error(dir,
                      {"builtin:cornell-box", "--res", "8x8", "--spp", "1", "--set",
                       "nee.target=shadowed"},
                      {"nee.target", "unshadowed", "learnt"});
  // Candidates from one cluster: a listed value, more than one candidate, a sampler that draws
  // a cluster first, and a rule inside the cluster that does not depend on how it was chosen.
  const std::vector<std::string> base = {"builtin:cornell-box", "--res", "8x8", "--spp", "1"};
  auto with = [&](std::vector<std::string> more) {
    std::vector<std::string> a = base;
    a.insert(a.end(), more.begin(), more.end());
    return a;
  };
  expect_render_error(dir, with({"--set", "nee.draw=clusters"}), {"nee.draw", "full", "cluster"});
  expect_render_error(dir, with({"--sampler", "rll", "--set", "nee.draw=cluster"}),
                      {"nee.draw", "nee.candidates"});
  expect_render_error(
      dir, with({"--sampler", "tree", "--set", "nee.draw=cluster", "--set", "nee.candidates=4"}),
      {"nee.draw", "tree"});
  expect_render_error(
      dir,
      with({"--sampler", "rll", "--set", "nee.draw=cluster", "--set", "nee.candidates=4", "--set",
            "rll.defensive=tree", "--set", "rll.within=power"}),
      {"nee.draw", "rll.defensive", "rll.within"});
  CommandResult ok = run_rll({"render", "builtin:cornell-box", "--res", "8x8", "--spp", "2",
                              "--sampler", "rll", "--set", "nee.draw=cluster", "--set",
                              "nee.candidates=4", "--quiet", "-o", (dir / "c.exr").string()});
  EXPECT_EQ(ok.exit_code, 0) << ok.output;
}

// rht's parameters are checked against their ranges, the error naming the key; rht draws several
// samples per vertex, which the wavefront renderer and resampled NEE do not take: both refuse it
// by name.
// The learning samplers share their settings' code; an error names the sampler's own key, never
// the other's (a bad fermat.alpha once said rll.alpha).
TEST(CliErrors, LearningParametersNameTheirSampler) {
  TempDir dir;
  for (const char* sampler : {"rll", "fermat"}) {
    const std::string p = sampler;
    auto args = [&](const std::string& kv) {
      return std::vector<std::string>{"builtin:cornell-box", "--res", "8x8", "--spp", "1",
                                      "--sampler", p, "--set", p + "." + kv};
    };
    for (const char* kv : {"alpha=5", "alpha=0", "cut_size=1", "cut_size=5000", "initial_cut=0",
                           "epsilon=0", "T=0.5", "splits=-1", "capacity=0"}) {
      const std::string key = std::string(kv).substr(0, std::string(kv).find('='));
      expect_render_error(dir, args(kv), {p + "." + key});
      std::vector<std::string> again = {"render"};
      for (const auto& x : args(kv)) again.push_back(x);
      again.insert(again.end(), {"--quiet", "-o", (dir / "x.png").string()});
      const std::string other = std::string(p == "rll" ? "fermat." : "rll.") + key;
      EXPECT_EQ(run_rll(again).output.find(other), std::string::npos) << other;
    }
  }
}

TEST(CliErrors, RhtParameters) {
  TempDir dir;
  const std::vector<std::string> base = {"builtin:cornell-box", "--res", "8x8", "--spp", "1",
                                         "--sampler", "rht"};
  auto with = [&](std::vector<std::string> extra) {
    std::vector<std::string> a = base;
    a.insert(a.end(), extra.begin(), extra.end());
    return a;
  };
  for (const char* g : {"0", "-1", "nan", "inf", "2000", "x"})
    expect_render_error(dir, with({"--set", std::string("rht.gamma=") + g}), {"rht.gamma"});
  for (const char* r : {"0", "33", "x"})
    expect_render_error(dir, with({"--set", std::string("rht.reservoirs=") + r}),
                        {"rht.reservoirs"});
  for (const char* n : {"0", "9"})
    expect_render_error(dir, with({"--set", std::string("rht.samples=") + n}), {"rht.samples"});
  expect_render_error(dir, with({"--set", "nee.candidates=4"}), {"nee.candidates", "rht"});
  expect_render_error(dir, with({"--wavefront", "--set", "nee.candidates=2"}),
                      {"nee.candidates", "rht"});
  // The counterpart: good values render.
  CommandResult r = run_rll({"render", "builtin:cornell-box", "--res", "8x8", "--spp", "2",
                             "--sampler", "rht", "--set", "rht.gamma=0.5", "--set",
                             "rht.reservoirs=4", "--set", "rht.samples=2", "--quiet", "-o",
                             (dir / "ok.png").string()});
  EXPECT_EQ(r.exit_code, 0) << r.output;
  // The wavefront renders it too (its several shadow rays a vertex, docs/rht.md).
  r = run_rll({"render", "builtin:cornell-box", "--res", "8x8", "--spp", "2", "--sampler", "rht",
               "--wavefront", "--quiet", "-o", (dir / "wavefront.png").string()});
  EXPECT_EQ(r.exit_code, 0) << r.output;
}

// `rll samplers --params NAME` lists the keys its table reads (the same ranges the errors above
// come from); a sampler with none says so; an unknown name is an error listing the valid ones.
TEST(CliErrors, SamplersListTheirParameters) {
  struct Want {
    const char* name;
    std::vector<std::string> lines;
  };
  for (const Want& w : std::vector<Want>{
           {"rll", {"rll.alpha=0.02  (in (0, 1])", "rll.capacity=32768  (in [1, 16777216])",
                    "rll.forget=changes  (one of changes, floor)"}},
           {"fermat", {"fermat.cut_size=256  (in [2, 4096])", "fermat.reset_every=32"}},
           {"rht", {"rht.gamma=0.05  (in (0, 1000])", "rht.samples=4  (in [1, 8])"}},
           {"oracle", {"oracle.discovery_spp=16  (in [1, 1024])", "rll.cut_size=128"}},
           {"ltc", {"ltc.epsilon=0.1  (in (0, 1])", "ltc.bins=8  (in [1, 32])"}},
           {"tree", {"tree has no parameters of its own"}}}) {
    const CommandResult r = run_rll({"samplers", "--params", w.name});
    EXPECT_EQ(r.exit_code, 0) << w.name << ": " << r.output;
    for (const auto& line : w.lines) EXPECT_NE(r.output.find(line), std::string::npos) << line;
  }
  const CommandResult bad = run_rll({"samplers", "--params", "nosuch"});
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.output.find("unknown light sampler 'nosuch'"), std::string::npos) << bad.output;
  // The oracle's ranges hold: a discovery that could not fit is refused before it allocates.
  TempDir dir;
  for (const char* kv : {"oracle.discovery_spp=0", "oracle.discovery_spp=5000", "oracle.bounces=17",
                         "oracle.points=0", "oracle.rays=0", "oracle.refine=-1"}) {
    const std::string key = std::string(kv).substr(0, std::string(kv).find('='));
    expect_render_error(dir, {"builtin:cornell-box", "--res", "8x8", "--spp", "1", "--sampler",
                              "oracle", "--set", kv},
                        {key});
  }
  expect_render_error(dir, {"builtin:cornell-box", "--res", "4096x4096", "--spp", "1", "--sampler",
                            "oracle", "--set", "oracle.discovery_spp=1024", "--set",
                            "oracle.bounces=16"},
                      {"oracle's discovery", "oracle.discovery_spp=1024", "more than"});
}
