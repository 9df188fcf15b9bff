// Renders split by samples over jobs (`rll render --task I/N`), merged exactly (`rll merge`), and
// learnt states that travel between renders (`--rll-state`).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "rll/core/image.h"
#include "rll/render/share.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;
namespace fs = std::filesystem;

namespace {

const std::vector<std::string> kBox = {"builtin:cornell-box", "--res", "40x30", "--threads", "2", "--quiet"};

std::vector<std::string> render_args(std::vector<std::string> extra) {
  std::vector<std::string> args = {"render"};
  args.insert(args.end(), kBox.begin(), kBox.end());
  args.insert(args.end(), extra.begin(), extra.end());
  return args;
}

void expect_ok(const CommandResult& r) { ASSERT_EQ(r.exit_code, 0) << r.output; }

void expect_refused(const CommandResult& r, std::initializer_list<std::string> parts) {
  EXPECT_GE(r.exit_code, 1) << r.output;
  EXPECT_LT(r.exit_code, 128) << r.output;
  expect_mentions(r.output, parts);
}

// Renders the 4 shares of a 4 x `spp` render into dir/share.I.exr.
std::vector<std::string> render_shares(const TempDir& dir, const std::vector<std::string>& flags, int spp) {
  std::vector<std::string> files;
  for (int i = 0; i < 4; ++i) {
    files.push_back((dir / ("share." + std::to_string(i) + ".exr")).string());
    std::vector<std::string> extra = flags;
    extra.insert(extra.end(), {"--spp", std::to_string(spp), "--task", std::to_string(i) + "/4", "-o", files.back()});
    expect_ok(run_rll(render_args(extra)));
  }
  return files;
}

}  // namespace

TEST(ClusterCli, MergedSharesAreTheSingleRender) {
  for (const std::vector<std::string>& flags :
       {std::vector<std::string>{"--integrator", "direct", "--sampler", "tree"},
        std::vector<std::string>{"--integrator", "path", "--sampler", "power", "--seed", "9"}}) {
    TempDir dir;
    std::vector<std::string> shares = render_shares(dir, flags, 3);
    std::vector<std::string> single = flags;
    single.insert(single.end(), {"--spp", "12", "-o", (dir / "single.exr").string()});
    expect_ok(run_rll(render_args(single)));
    std::vector<std::string> merge = {"merge", (dir / "merged.exr").string()};
    merge.insert(merge.end(), shares.begin(), shares.end());
    merge.insert(merge.end(), {"--check-against", (dir / "single.exr").string(), "--tolerance", "1e-6"});
    const CommandResult r = run_rll(merge);
    expect_ok(r);
    expect_mentions(r.output, {"merged 4 of 4 shares", "12 spp"});
    const ExrFile merged = read_exr_file(dir / "merged.exr");
    const Image one = read_image(dir / "single.exr");
    EXPECT_LE(max_relative_difference(merged.image, one), 1e-6);
    ASSERT_EQ(merged.counts.size(), one.pixel_count());
    for (uint32_t n : merged.counts) ASSERT_EQ(n, 12u);
    // Merges merge: two halves, then the halves.
    expect_ok(run_rll({"merge", (dir / "a.exr").string(), shares[0], shares[3], "--allow-missing"}));
    expect_ok(run_rll({"merge", (dir / "b.exr").string(), shares[2], shares[1], "--allow-missing"}));
    expect_ok(run_rll({"merge", (dir / "ab.exr").string(), (dir / "b.exr").string(), (dir / "a.exr").string(),
                       "--check-against", (dir / "single.exr").string(), "--tolerance", "1e-6"}));
    // The check can fail: half the shares are not the single render.
    expect_refused(run_rll({"merge", (dir / "half.exr").string(), shares[0], shares[1], "--allow-missing",
                            "--check-against", (dir / "single.exr").string()}),
                   {"differs", "single.exr"});
  }
}

TEST(ClusterCli, LearningSamplersSharesMerge) {
  TempDir dir;
  std::vector<std::string> shares = render_shares(dir, {"--integrator", "direct", "--sampler", "rll"}, 2);
  std::vector<std::string> merge = {"merge", (dir / "merged.exr").string()};
  merge.insert(merge.end(), shares.begin(), shares.end());
  const CommandResult r = run_rll(merge);
  expect_ok(r);
  expect_mentions(r.output, {"8 spp"});
}

TEST(ClusterCli, MergeRefusesSharesOfOtherRenders) {
  TempDir dir;
  const std::vector<std::string> flags = {"--integrator", "direct", "--sampler", "tree"};
  std::vector<std::string> shares = render_shares(dir, flags, 2);
  auto other = [&](const std::string& name, std::vector<std::string> extra) {
    std::vector<std::string> args = flags;
    args.insert(args.end(), extra.begin(), extra.end());
    args.insert(args.end(), {"-o", (dir / name).string()});
    expect_ok(run_rll(render_args(args)));
    return (dir / name).string();
  };
  const std::string out = (dir / "merged.exr").string();
  expect_refused(run_rll({"merge", out, shares[0], other("seed.exr", {"--spp", "2", "--task", "1/4", "--seed", "5"})}),
                 {"seed.exr", "seed"});
  expect_refused(run_rll({"merge", out, shares[0], other("spp.exr", {"--spp", "3", "--task", "1/4"})}),
                 {"spp.exr", "samples per pixel of each share"});
  expect_refused(run_rll({"merge", out, shares[0], other("n.exr", {"--spp", "2", "--task", "1/3"})}),
                 {"n.exr", "number of shares"});
  expect_refused(run_rll({"merge", out, shares[0], other("set.exr", {"--spp", "2", "--task", "1/4", "--max-depth", "2"})}),
                 {"set.exr", "max_depth"});
  std::vector<std::string> res = {"render", "builtin:cornell-box", "--res", "40x20", "--quiet", "--spp", "2",
                                  "--task", "1/4", "-o", (dir / "res.exr").string()};
  res.insert(res.end(), flags.begin(), flags.end());
  expect_ok(run_rll(res));
  expect_refused(run_rll({"merge", out, shares[0], (dir / "res.exr").string()}), {"res.exr", "differs"});
  expect_refused(run_rll({"merge", out, shares[0], shares[1], shares[1]}), {"share 1 of 4", "twice"});
  expect_refused(run_rll({"merge", out, shares[0], shares[1]}), {"2, 3", "missing", "--allow-missing"});
  expect_ok(run_rll(render_args({"--spp", "2", "-o", (dir / "plain.png").string()})));
  expect_refused(run_rll({"merge", out, shares[0], (dir / "plain.png").string()}), {"plain.png", ".exr"});
  EXPECT_FALSE(fs::exists(out));
  expect_refused(run_rll({"merge", shares[0], shares[0], shares[1]}), {"is the input file", "refusing to write over it"});
}

TEST(ClusterCli, TaskFlagsAreChecked) {
  TempDir dir;
  const std::string out = (dir / "s.exr").string();
  expect_refused(run_rll(render_args({"--task", "0/4", "-o", out})), {"--task", "--spp"});
  expect_refused(run_rll(render_args({"--task", "0/4", "--spp", "2", "--time", "1", "-o", out})), {"--time"});
  expect_refused(run_rll(render_args({"--task", "0/4", "--spp", "2", "-o", (dir / "s.png").string()})), {".exr"});
  expect_refused(run_rll(render_args({"--task", "4/4", "--spp", "2", "-o", out})), {"4/4", "below N"});
  expect_refused(run_rll(render_args({"--task", "1", "--spp", "2", "-o", out})), {"I/N"});
  expect_refused(run_rll(render_args({"--task", "-1/4", "--spp", "2", "-o", out})), {"I/N"});
  expect_refused(run_rll(render_args({"--task", "0/0", "--spp", "2", "-o", out})), {"N must be"});
  expect_refused(run_rll(render_args({"--task", "0/1000", "--spp", "1073742", "-o", out})), {"more than"});
  EXPECT_FALSE(fs::exists(out));
}

TEST(ClusterCli, LearntStateTravels) {
  TempDir dir;
  const std::string state = (dir / "room.rllstate").string();
  const std::vector<std::string> room = {"render", "builtin:cornell-boxes-room", "--res", "32x24", "--integrator",
                                         "direct", "--quiet", "--spp", "8"};
  auto args = [&](std::vector<std::string> extra) {
    std::vector<std::string> a = room;
    a.insert(a.end(), extra.begin(), extra.end());
    return a;
  };
  expect_refused(run_rll(args({"--rll-state", state, "--rll-state-mode", "load", "-o", (dir / "x.exr").string()})),
                 {"room.rllstate", "not found"});
  expect_ok(run_rll(args({"--rll-state", state, "-o", (dir / "train.exr").string()})));
  ASSERT_TRUE(fs::exists(state));
  const auto stamp = fs::last_write_time(state);
  // Loaded in load mode: the file is read, never written; the render is the same for any
  // number of threads, and differs from a cold one.
  expect_ok(run_rll(args({"--rll-state", state, "--rll-state-mode", "load", "--threads", "1", "-o",
                          (dir / "warm1.exr").string()})));
  expect_ok(run_rll(args({"--rll-state", state, "--rll-state-mode", "load", "--threads", "2", "-o",
                          (dir / "warm2.exr").string()})));
  expect_ok(run_rll(args({"-o", (dir / "cold.exr").string()})));
  EXPECT_EQ(fs::last_write_time(state), stamp);
  const Image w1 = read_image(dir / "warm1.exr"), w2 = read_image(dir / "warm2.exr"), cold = read_image(dir / "cold.exr");
  EXPECT_EQ(max_relative_difference(w1, w2), 0.0);
  EXPECT_GT(max_relative_difference(w1, cold), 0.0);
  // Refusals: another resolution, another sampler, a sampler without state, not a state file.
  std::vector<std::string> other_res = args({"--rll-state", state, "-o", (dir / "r.exr").string()});
  other_res[3] = "32x16";
  expect_refused(run_rll(other_res), {"room.rllstate", "another scene or resolution"});
  expect_refused(run_rll(args({"--rll-state", state, "--sampler", "fermat", "-o", (dir / "f.exr").string()})),
                 {"'rll'", "'fermat'"});
  expect_refused(run_rll(args({"--rll-state", state, "--sampler", "tree", "-o", (dir / "t.exr").string()})),
                 {"'tree'", "nothing"});
  expect_refused(run_rll(args({"--rll-state", (dir / "cold.exr").string(), "--rll-state-mode", "load", "-o",
                               (dir / "n.exr").string()})),
                 {"not an rll sampler state"});
  expect_refused(run_rll(args({"--rll-state", state, "--rll-state-mode", "sometimes", "-o", (dir / "n.exr").string()})),
                 {"--rll-state-mode"});
}

TEST(ClusterCli, ErrorMeasuresAnyImageAgainstAReference) {
  TempDir dir;
  const std::string ref = (dir / "ref.exr").string(), var = (dir / "ref.variance.exr").string();
  expect_ok(run_rll({"reference", "builtin:cornell-box", "--res", "40x30", "--integrator", "direct", "--spp", "32",
                     "--sampler", "tree", "--cache-dir", (dir / "cache").string(), "--quiet", "-o", ref}));
  ASSERT_TRUE(fs::exists(var));
  expect_ok(run_rll(render_args({"--integrator", "direct", "--sampler", "power", "--spp", "2", "-o",
                                 (dir / "x.exr").string()})));
  const CommandResult self = run_rll({"error", ref, ref, "--json"});
  expect_ok(self);
  const nlohmann::json zero = nlohmann::json::parse(self.output.substr(self.output.find('{')));
  EXPECT_EQ(zero["relmse"].get<double>(), 0.0);
  const CommandResult plain = run_rll({"error", (dir / "x.exr").string(), ref, "--json"});
  const CommandResult corrected =
      run_rll({"error", (dir / "x.exr").string(), ref, "--json", "--reference-variance", var});
  expect_ok(plain);
  expect_ok(corrected);
  const nlohmann::json p = nlohmann::json::parse(plain.output.substr(plain.output.find('{')));
  const nlohmann::json c = nlohmann::json::parse(corrected.output.substr(corrected.output.find('{')));
  EXPECT_GT(p["relmse"].get<double>(), 0.0);
  // The reference's noise is subtracted: less error, said so.
  EXPECT_LT(c["mse"].get<double>(), p["mse"].get<double>());
  EXPECT_TRUE(c["reference_noise_subtracted"].get<bool>());
  expect_ok(run_rll({"render", "builtin:cornell-box", "--res", "20x30", "--quiet", "--spp", "1", "-o",
                     (dir / "small.exr").string()}));
  expect_refused(run_rll({"error", (dir / "small.exr").string(), ref}), {"20x30", "40x30"});
}

TEST(ClusterCli, AnAnimationsStateLoadsAtItsNextRender) {
  // The state saved after the last frame belongs to the scene as loaded (frame 0), not to the
  // lights where the last frame left them.
  TempDir dir;
  const std::string state = (dir / "dynamic.rllstate").string();
  const std::vector<std::string> args = {"render", "builtin:cornell-boxes-dynamic", "--res", "32x24", "--integrator",
                                         "direct", "--spp", "4", "--frames", "2", "--rll-state", state,
                                         "-o", (dir / "d.exr").string()};
  expect_ok(run_rll(args));
  const CommandResult again = run_rll(args);
  expect_ok(again);
  expect_mentions(again.output, {"starts from the state learnt in", "dynamic.rllstate"});
}
