// `rll compare` and `rll reference` end to end: the files a compare writes, the reference cache,
// the HTML report in a headless browser, and bad flags.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <stb/stb_image.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "rll/eval/metrics.h"
#include "rll/eval/raster.h"
#include "support/test_support.h"

using namespace rll;
using test::read_text;
using test::run_rll;
namespace fs = std::filesystem;

namespace {


bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// One small comparison shared by the tests that only read its output: power and uniform on a
// 24x24 Cornell box, 4 spp, 2 repeats.
class CompareOutput : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    s_dir = new test::TempDir();
    s_result = new test::CommandResult(
        run_rll({"compare", "builtin:cornell-box", "--res", "24x24", "--samplers", "power,uniform",
                 "--spp", "4", "--repeats", "2", "--reference-spp", "64", "--cache-dir",
                 (*s_dir / "cache").string(), "--out", (*s_dir / "out").string(), "--quiet"}));
  }
  static void TearDownTestSuite() {
    delete s_result;
    delete s_dir;
  }
  void SetUp() override { ASSERT_EQ(s_result->exit_code, 0) << s_result->output; }
  static fs::path out(const std::string& name) { return *s_dir / "out" / name; }
  static nlohmann::json summary() { return nlohmann::json::parse(read_text(out("summary.json"))); }

  static test::TempDir* s_dir;
  static test::CommandResult* s_result;
};
test::TempDir* CompareOutput::s_dir = nullptr;
test::CommandResult* CompareOutput::s_result = nullptr;

}  // namespace

TEST_F(CompareOutput, SummaryHasEveryFieldPerSampler) {
  const nlohmann::json j = summary();
  ASSERT_EQ(j["samplers"].size(), 2u);
  EXPECT_EQ(j["samplers"][0]["name"], "power");
  EXPECT_EQ(j["samplers"][1]["name"], "uniform");
  for (const auto& s : j["samplers"]) {
    for (const char* k :
         {"spp", "seconds", "setup_seconds", "relmse", "mse", "efficiency", "relmse_ratio"}) {
      ASSERT_TRUE(s.contains(k) && s[k].is_object()) << k;
      EXPECT_EQ(s[k]["values"].size(), 2u) << k;
      EXPECT_LE(s[k]["min"].get<double>(), s[k]["median"].get<double>()) << k;
      EXPECT_LE(s[k]["median"].get<double>(), s[k]["max"].get<double>()) << k;
    }
    EXPECT_EQ(s["spp"]["median"], 4);
    EXPECT_GT(s["relmse"]["min"].get<double>(), 0);
    EXPECT_GT(s["seconds"]["min"].get<double>(), 0);
    EXPECT_TRUE(s["memory"].contains("sampler_bytes"));
    EXPECT_GT(s["memory"]["peak_rss_bytes"].get<double>(), 1e6);
    EXPECT_EQ(s["runs"].size(), 2u);
    EXPECT_FALSE(s["runs"][0]["checkpoints"].empty());
    const double relmse = s["relmse"]["values"][0], seconds = s["seconds"]["values"][0];
    EXPECT_NEAR(s["efficiency"]["values"][0].get<double>(), 1 / (relmse * seconds),
                1e-9 / (relmse * seconds));
  }
  EXPECT_EQ(j["samplers"][0]["relmse_ratio"]["median"], 1.0);
  // Interleaved, the starting sampler rotating per repeat; each repeat its own seed.
  EXPECT_EQ(j["order"], nlohmann::json::parse(R"([["power","uniform"],["uniform","power"]])"));
  EXPECT_EQ(j["samplers"][0]["runs"][1]["seed"], 2);
  EXPECT_EQ(j["reference"]["spp"], 64);
  EXPECT_EQ(j["budget"]["spp"], 4);
}

TEST_F(CompareOutput, ErrorsRecomputedFromTheWrittenImagesMatch) {
  // The reference's noise, subtracted from every error, comes with it.
  const Image ref = read_image(out("reference.exr"));
  const nlohmann::json j = summary();
  ASSERT_EQ(j["reference"]["variance_image"], "reference.variance.exr");
  const Image var = read_image(out("reference.variance.exr"));
  for (const auto& s : j["samplers"]) {
    const std::string name = s["name"];
    const Image first = read_image(out(name + ".exr"));
    const Image second = read_image(out(name + ".repeat2.exr"));
    const ErrorMetrics a = error_metrics(first, ref, &var), b = error_metrics(second, ref, &var);
    EXPECT_NEAR(a.relmse, s["relmse"]["values"][0].get<double>(), 1e-9);
    EXPECT_NEAR(a.trimmed_relmse, s["trimmed_relmse"]["values"][0].get<double>(), 1e-9);
    EXPECT_NEAR(a.mrse, s["mrse"]["values"][0].get<double>(), 1e-9);
    EXPECT_NEAR(b.mse, s["mse"]["values"][1].get<double>(), 1e-12);
    // Without the subtraction every error is larger by the reference's noise.
    EXPECT_GT(relmse(first, ref), a.relmse);
    const Image err = read_image(out(name + ".error.exr"));
    const auto map = relative_error_map(first, ref);
    EXPECT_NEAR(err[7].x, map[7], 1e-6);
  }
}

TEST_F(CompareOutput, ConvergencePlotIsAPng) {
  if (!figures_built()) GTEST_SKIP() << "built with -DRLL_FIGURES=OFF: no PNG figures";
  int w = 0, h = 0, n = 0;
  ASSERT_TRUE(stbi_info(out("convergence.png").c_str(), &w, &h, &n));
  EXPECT_GT(w, 300);
  EXPECT_GT(h, 200);
}

TEST_F(CompareOutput, SideBySideHoldsEverySamplerAndTheReference) {
  if (!figures_built()) GTEST_SKIP() << "built with -DRLL_FIGURES=OFF: no PNG figures";
  // Two samplers and the reference, 4 pixels apart, each tone-mapped from its .exr.
  int w = 0, h = 0, n = 0;
  ASSERT_TRUE(stbi_info(out("side-by-side.png").c_str(), &w, &h, &n));
  const Image ref = read_image(out("reference.exr"));
  EXPECT_EQ(w, 3 * ref.width() + 2 * 4);
  EXPECT_GT(h, ref.height());  // a caption band under the images
  const Image row = read_image(out("side-by-side.png"));
  const Image uniform = read_image(out("uniform.exr"));
  const int x = ref.width() / 2, y = ref.height() / 2;
  EXPECT_NEAR(row.at(ref.width() + 4 + x, y).y, std::min(uniform.at(x, y).y, 1.0f), 0.02f);
  EXPECT_NEAR(row.at(2 * (ref.width() + 4) + x, y).y, std::min(ref.at(x, y).y, 1.0f), 0.02f);
  EXPECT_EQ(summary()["files"]["side_by_side"], "side-by-side.png");
}

TEST_F(CompareOutput, PrintsTheTableAndTheReportPath) {
  EXPECT_TRUE(contains(s_result->output, "relMSE median [min, max]")) << s_result->output;
  EXPECT_TRUE(contains(s_result->output, "efficiency"));
  EXPECT_TRUE(contains(s_result->output, "report: " + out("report.html").string()))
      << s_result->output;
}

namespace {

const fs::path kChromium = "/usr/bin/chromium";

// Loads a copy of `report` with tests/cli/report_selftest.js (which uses the report's controls
// the way a user would) in headless Chromium, in folder `dir`; returns the page's own <body> tag
// as the DOM ends with it. Fails the test where Chromium fails, logs an uncaught error, or the
// self-test does not pass.
std::string run_selftest(const fs::path& report, const fs::path& dir) {
  std::string html = read_text(report);
  const std::string selftest = read_text(fs::path(RLL_SOURCE_DIR) / "tests/cli/report_selftest.js");
  EXPECT_FALSE(selftest.empty());
  const size_t body = html.rfind("</body>");
  EXPECT_NE(body, std::string::npos);
  if (body == std::string::npos) return "";
  html.insert(body, "<script>" + selftest + "</script>\n");
  const fs::path page = dir / "selftest.html";
  std::ofstream(page) << html;
  const fs::path dom = dir / "dom.html", log = dir / "chromium.log";
  const std::string cmd =
      "timeout 120 " + kChromium.string() +
      " --headless --no-sandbox --disable-gpu --disable-quic --no-first-run"
      " --disable-background-networking --disable-component-update --disable-sync"
      " --user-data-dir=" +
      (dir / "chromium-profile").string() +
      " --enable-logging=stderr --v=0 --virtual-time-budget=20000 --dump-dom 'file://" +
      page.string() + "' > '" + dom.string() + "' 2> '" + log.string() + "'";
  EXPECT_EQ(std::system(cmd.c_str()), 0) << read_text(log);
  const std::string d = read_text(dom), l = read_text(log);
  EXPECT_FALSE(contains(l, "Uncaught")) << l;
  EXPECT_TRUE(contains(d, "<table id=\"summary\">")) << d.substr(0, 2000);
  EXPECT_TRUE(contains(d, "data-ready=\"1\"")) << "the report's script did not finish";
  // The first <body: the page's own tag, not text quoted in a script.
  const size_t at = d.find("<body");
  const std::string tag = at == std::string::npos ? "" : d.substr(at, d.find('>', at) - at + 1);
  EXPECT_TRUE(contains(tag, "data-selftest=\"ok\""))
      << (at == std::string::npos ? d.substr(0, 300) : d.substr(at, 300));
  return tag;
}

}  // namespace

TEST_F(CompareOutput, ReportLoadsInChromiumWithoutScriptErrors) {
  if (!fs::exists(kChromium))
    GTEST_SKIP() << "chromium is not installed (make test installs it): report not loaded";
  EXPECT_FALSE(contains(run_selftest(out("report.html"), s_dir->path()), "data-cell-chart"));
  const std::string d = read_text(s_dir->path() / "dom.html");
  EXPECT_FALSE(contains(d, "id=\"cell-chart\"")) << "a cell chart without a learning sampler";
  EXPECT_TRUE(
      contains(d, "<td><span class=\"swatch\" style=\"background:#1f77b4\"></span>power</td>"));
}

// The cell chart of a compare with rll and the oracle: per probed cell, rll's baked table and the
// oracle's probabilities each sum to 1 over the cell's clusters, and so do the tree's; and in
// Chromium a click on a pixel of rll's image (and of its cell-id map) shows that cell's bars.
// With --aov every sampler's diagnostics are views of their own, each flipped with the reference
// and back in Chromium.
TEST(Compare, ReportChartsRllsCellsAgainstTheTreeAndTheOracle) {
  test::TempDir tmp;
  auto r = run_rll({"compare", "builtin:cornell-boxes-room", "--res", "32x24", "--samplers",
                    "power,rll,oracle", "--spp", "8", "--reference-spp", "32", "--set",
                    "oracle.points=4", "--set", "oracle.rays=2", "--set",
                    "oracle.discovery_spp=4", "--aov", "cell,probability,entropy,visible,rewards",
                    "--cache-dir", (tmp / "cache").string(), "--out", (tmp / "out").string(),
                    "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string html = read_text(tmp / "out" / "report.html");
  // Every sampler's probability and visible maps; the cells' maps of rll and the oracle (power
  // has no cells: those maps would show nothing and are left out).
  for (const char* name : {"cell", "probability", "entropy", "visible", "rewards"})
    for (int entry = 0; entry < 3; ++entry) {
      const bool cells = std::string(name) != "probability" && std::string(name) != "visible";
      EXPECT_EQ(contains(html, fmt::format("data-map=\"aov-{}-{}\"", name, entry)),
                entry > 0 || !cells)
          << name << " of entry " << entry;
    }
  EXPECT_EQ(nlohmann::json::parse(read_text(tmp / "out" / "summary.json"))["aov"],
            "cell,probability,entropy,visible,rewards");
  const std::string open = "<script type=\"application/json\" class=\"cell-data\">";
  const size_t at = html.find(open);
  ASSERT_NE(at, std::string::npos);
  EXPECT_EQ(html.find(open, at + 1), std::string::npos) << "one chart: rll's";
  const size_t from = at + open.size();
  const auto d = nlohmann::json::parse(html.substr(from, html.find("</script>", from) - from));
  EXPECT_EQ(d["sampler"], "rll");
  EXPECT_EQ(d["entry"], 1);
  EXPECT_TRUE(d["oracle"].get<bool>());
  EXPECT_EQ(d["stride"], 1);  // 768 pixels: every one is probed
  EXPECT_EQ(d["probes"].size(), 32u * 24u);
  const size_t cells = d["cells"].size();
  ASSERT_GT(cells, 3u);
  size_t with_cell = 0;
  for (const auto& p : d["probes"]) {
    ASSERT_LT(p.get<int>(), int(cells));
    with_cell += p.get<int>() >= 0;
  }
  EXPECT_GT(with_cell, 32u * 24u / 2) << "most pixels see a surface with a cell";
  size_t learnt_cells = 0;
  for (const auto& c : d["cells"]) {
    // The 24 largest clusters one by one, the others summed (the chart's rows).
    double learnt = 0, tree = 0, oracle = 0;
    if (c.contains("rest")) {
      EXPECT_EQ(c["learnt"].size(), 24u);
      learnt = c["rest"]["learnt"];
      tree = c["rest"]["tree"];
      oracle = c["rest"]["oracle"];
    }
    for (double v : c["learnt"]) learnt += v;
    for (double v : c["tree"]) tree += v;
    for (double v : c["oracle"]) oracle += v;
    EXPECT_NEAR(learnt, 1, 5e-3) << c.dump();
    EXPECT_NEAR(oracle, 1, 5e-3) << c.dump();
    if (tree != 0) {  // 0 where the point faces away from every light
      EXPECT_NEAR(tree, 1, 5e-3) << c.dump();
    }
    EXPECT_EQ(c["b"].size(), c["learnt"].size());
    learnt_cells += c["cut"].get<bool>();
  }
  EXPECT_GT(learnt_cells, cells / 2) << "most cells have a learnt cut after 8 passes";
  if (!fs::exists(kChromium))
    GTEST_SKIP() << "chromium is not installed (make test installs it): chart not clicked";
  const std::string body = run_selftest(tmp / "out" / "report.html", tmp.path());
  EXPECT_TRUE(contains(body, "data-cell-chart=\"checked\"")) << "the chart was not clicked: " << body;
  EXPECT_TRUE(contains(body, "data-diagnostics=\"12\"")) << "the maps were not flipped: " << body;
}

TEST(Compare, AovRefusesUnknownNamesAndTheWavefront) {
  test::TempDir tmp;
  auto r = run_rll({"compare", "builtin:cornell-box", "--res", "16x16", "--samplers", "power",
                    "--spp", "1", "--aov", "cell,colour", "--out", (tmp / "out").string()});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_TRUE(contains(r.output, "--aov: unknown diagnostic 'colour'")) << r.output;
  r = run_rll({"compare", "builtin:cornell-box", "--res", "16x16", "--samplers", "power", "--spp",
               "1", "--aov", "visible", "--wavefront", "--out", (tmp / "out").string()});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_TRUE(contains(r.output, "--aov: the diagnostics are measured by the megakernel"))
      << r.output;
}

TEST(Compare, EqualTimeStopsAtTheBudget) {
  test::TempDir tmp;
  auto r = run_rll({"compare", "builtin:cornell-box", "--res", "16x16", "--samplers", "power",
                    "--time", "0.3", "--reference-spp", "16", "--cache-dir",
                    (tmp / "cache").string(), "--out", (tmp / "out").string(), "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(read_text(tmp / "out" / "summary.json"));
  const auto& s = j["samplers"][0];
  EXPECT_EQ(j["budget"]["time"], 0.3);
  EXPECT_GE(s["seconds"]["median"].get<double>(), 0.3);
  EXPECT_LT(s["seconds"]["median"].get<double>(), 2.0);
  EXPECT_GT(s["spp"]["median"].get<double>(), 4);
  // Checkpoints: increasing in time, the last one the final image.
  const auto& cps = s["runs"][0]["checkpoints"];
  ASSERT_GE(cps.size(), 3u);
  for (size_t i = 1; i < cps.size(); ++i)
    EXPECT_GT(cps[i][0].get<double>(), cps[i - 1][0].get<double>());
  EXPECT_EQ(cps.back()[2], s["relmse"]["values"][0]);
  EXPECT_EQ(cps.back()[1], s["spp"]["values"][0]);
}

TEST(Reference, CacheIsReusedAndInvalidatedWhenTheSceneChanges) {
  test::TempDir tmp;
  const std::string cache = (tmp / "cache").string();
  auto reference = [&](std::vector<std::string> extra, const std::string& res = "16x16",
                       const std::string& spp = "16") {
    std::vector<std::string> args = {"reference", "builtin:cornell-box", "--res", res,      "--spp",
                                     spp,         "--cache-dir",         cache,   "--quiet"};
    args.insert(args.end(), extra.begin(), extra.end());
    return run_rll(args);
  };
  auto first = reference({"-o", (tmp / "ref.exr").string()});
  ASSERT_EQ(first.exit_code, 0) << first.output;
  EXPECT_TRUE(contains(first.output, "rendered 16 spp")) << first.output;
  EXPECT_TRUE(fs::exists(tmp / "ref.exr"));

  auto again = reference({});
  EXPECT_TRUE(contains(again.output, "reused")) << again.output;
  auto fewer = reference({}, "16x16", "8");  // --spp is a minimum: 16 will do
  EXPECT_TRUE(contains(fewer.output, "reused")) << fewer.output;

  // compare finds it too (its runs use seeds 1.., the reference 1000003).
  auto cmp = run_rll({"compare", "builtin:cornell-box", "--res", "16x16", "--samplers", "power",
                      "--spp", "1", "--reference-spp", "16", "--cache-dir", cache, "--out",
                      (tmp / "out").string(), "--quiet"});
  ASSERT_EQ(cmp.exit_code, 0) << cmp.output;
  EXPECT_TRUE(contains(cmp.output, "reference: reused")) << cmp.output;
  EXPECT_EQ(read_image(tmp / "out" / "reference.exr")[100].y, read_image(tmp / "ref.exr")[100].y);

  // Another film size or integrator is another scene or setting: rendered afresh.
  EXPECT_TRUE(contains(reference({}, "16x12").output, "rendered"));
  EXPECT_TRUE(contains(reference({"--max-depth", "2"}).output, "rendered"));
  EXPECT_TRUE(contains(reference({}, "16x16", "32").output, "rendered 32 spp"));
  EXPECT_TRUE(contains(reference({"--force"}).output, "rendered"));
}

TEST(Reference, EditingTheSceneFileInvalidatesItsReference) {
  test::TempDir tmp;
  const std::string cache = (tmp / "cache").string();
  // A lit floor: an emissive quad above a diffuse one.
  const std::string geometry =
      "mtllib m.mtl\nv -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nv -0.2 1 -0.2\nv 0.2 1 -0.2\n"
      "v 0.2 1 0.2\nv -0.2 1 0.2\nusemtl floor\nf 1 4 3\nf 1 3 2\nusemtl lamp\nf 5 6 7\nf 5 7 8\n";
  tmp.write("m.mtl", "newmtl floor\nKd 0.5 0.5 0.5\nnewmtl lamp\nKe 4 4 4\n");
  const fs::path scene = tmp.write("room.obj", geometry);
  auto reference = [&] {
    return run_rll({"reference", scene.string(), "--res", "8x8", "--spp", "4", "--cache-dir", cache,
                    "--quiet"});
  };
  auto cached_entries = [&] {
    int n = 0;
    for (const auto& e : fs::directory_iterator(cache)) n += e.path().extension() == ".json";
    return n;
  };
  auto first = reference();
  ASSERT_EQ(first.exit_code, 0) << first.output;
  EXPECT_TRUE(contains(first.output, "rendered")) << first.output;
  EXPECT_TRUE(contains(reference().output, "reused"));

  // A brighter lamp, in the material file the scene refers to: the old reference is stale.
  tmp.write("m.mtl", "newmtl floor\nKd 0.5 0.5 0.5\nnewmtl lamp\nKe 8 8 8\n");
  auto edited = reference();
  EXPECT_TRUE(contains(edited.output, "rendered")) << edited.output;
  EXPECT_TRUE(contains(reference().output, "reused"));
  EXPECT_EQ(cached_entries(), 1);  // the stale entry of this scene file was deleted

  // Moving a vertex is a change too.
  std::string moved = geometry;
  moved.replace(moved.find("v -1 0 -1\n"), 10, "v -1 0 -1.5\n");
  tmp.write("room.obj", moved);
  EXPECT_TRUE(contains(reference().output, "rendered"));
}

// A variant carries the integrator's keys for itself: "tree:nee.candidates=4" renders what
// `rll render --sampler tree --set nee.candidates=4` renders (to the bit, the same seed), beside
// plain tree in one compare; were the key dropped, the variant's image would be plain tree's.
TEST(Compare, VariantsCarryTheirOwnIntegratorKeys) {
  test::TempDir tmp;
  const std::string out = (tmp / "out").string(), cache = (tmp / "cache").string();
  auto r = run_rll({"compare", "builtin:cornell-boxes-room", "--res", "24x18", "--samplers",
                    "tree,tree:nee.candidates=4", "--spp", "4", "--reference-spp", "4",
                    "--cache-dir", cache, "--out", out, "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(std::ifstream(tmp / "out" / "summary.json"));
  ASSERT_EQ(j["samplers"].size(), 2u);
  EXPECT_EQ(j["samplers"][1]["name"], "tree:nee.candidates=4");
  const Image plain = read_image(tmp / "out" / j["samplers"][0]["image"].get<std::string>());
  const Image variant = read_image(tmp / "out" / j["samplers"][1]["image"].get<std::string>());
  auto rendered = run_rll({"render", "builtin:cornell-boxes-room", "--res", "24x18", "--sampler",
                           "tree", "--set", "nee.candidates=4", "--spp", "4", "--quiet", "-o",
                           (tmp / "m4.exr").string()});
  ASSERT_EQ(rendered.exit_code, 0) << rendered.output;
  auto spec = run_rll({"render", "builtin:cornell-boxes-room", "--res", "24x18", "--sampler",
                       "tree:nee.candidates=4", "--spp", "4", "--quiet", "-o",
                       (tmp / "spec.exr").string()});
  ASSERT_EQ(spec.exit_code, 0) << spec.output;
  const Image m4 = read_image(tmp / "m4.exr"), by_spec = read_image(tmp / "spec.exr");
  EXPECT_TRUE(variant.pixels() == m4.pixels());
  EXPECT_TRUE(by_spec.pixels() == m4.pixels());
  EXPECT_FALSE(plain.pixels() == m4.pixels());
  // A variant's integrator key is checked as --set's is; rht resamples its own candidates.
  auto bad = run_rll({"compare", "builtin:cornell-box", "--res", "8x8", "--samplers",
                      "tree:nee.candidates=0", "--spp", "1", "--cache-dir", cache, "--out", out,
                      "--quiet"});
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_TRUE(contains(bad.output, "nee.candidates")) << bad.output;
  auto rht = run_rll({"compare", "builtin:cornell-box", "--res", "8x8", "--samplers",
                      "rht:nee.candidates=4", "--spp", "1", "--cache-dir", cache, "--out", out,
                      "--quiet"});
  EXPECT_NE(rht.exit_code, 0);
  EXPECT_TRUE(contains(rht.output, "resamples its own candidates")) << rht.output;
}

TEST(Compare, BadFlagsGiveClearErrors) {
  test::TempDir tmp;
  const std::string out = (tmp / "out").string(), cache = (tmp / "cache").string();
  auto compare = [&](std::vector<std::string> extra) {
    std::vector<std::string> args = {
        "compare", "builtin:cornell-box", "--res", "8x8", "--cache-dir", cache, "--out", out,
        "--quiet"};
    args.insert(args.end(), extra.begin(), extra.end());
    return run_rll(args);
  };
  auto expect_error = [](const test::CommandResult& r, const std::string& message) {
    EXPECT_NE(r.exit_code, 0) << r.output;
    EXPECT_TRUE(contains(r.output, message)) << "expected '" << message << "' in: " << r.output;
  };
  expect_error(compare({"--samplers", "power,nope", "--spp", "1"}), "unknown light sampler 'nope'");
  expect_error(compare({"--samplers", "power,power", "--spp", "1"}), "'power' is listed twice");
  expect_error(compare({"--samplers", "power,", "--spp", "1"}), "empty sampler name");
  expect_error(compare({"--samplers", "power"}), "give exactly one budget");
  expect_error(compare({"--samplers", "power", "--spp", "1", "--time", "1"}), "excludes");
  expect_error(compare({"--samplers", "power", "--spp", "1", "--repeats", "0"}), "--repeats");
  expect_error(compare({"--samplers", "power", "--spp", "1", "--set", "power.nope=1"}),
               "power.nope");
  expect_error(compare({"--samplers", "power", "--spp", "1", "--seed", "5", "--repeats", "3",
                        "--reference-seed", "7"}),
               "--reference-seed 7");
  auto wrong_size = run_rll({"reference", "builtin:cornell-box", "--res", "4x4", "--spp", "1",
                             "--cache-dir", cache, "-o", (tmp / "small.exr").string(), "--quiet"});
  ASSERT_EQ(wrong_size.exit_code, 0) << wrong_size.output;
  expect_error(
      compare({"--samplers", "power", "--spp", "1", "--reference", (tmp / "small.exr").string()}),
      "the image is 4x4 but the scene renders at 8x8");
  expect_error(
      compare({"--samplers", "power", "--spp", "1", "--reference", (tmp / "missing.exr").string()}),
      "not found");
  expect_error(run_rll({"reference", "builtin:cornell-box", "--spp", "0", "--cache-dir", cache}),
               "--spp");
}

TEST(Samplers, ListsTheRegisteredSamplers) {
  auto r = run_rll({"samplers"});
  ASSERT_EQ(r.exit_code, 0);
  EXPECT_TRUE(contains(r.output, "power\n")) << r.output;
  EXPECT_TRUE(contains(r.output, "uniform\n")) << r.output;
}
