#include <gtest/gtest.h>

#include <cmath>

#include "rll/core/error.h"
#include "rll/eval/compare.h"
#include "rll/eval/metrics.h"

using namespace rll;

TEST(CompareSummary, SpreadMedianAndRange) {
  Spread odd = spread_of({3, 1, 2});
  EXPECT_EQ(odd.median, 2);
  EXPECT_EQ(odd.min, 1);
  EXPECT_EQ(odd.max, 3);
  EXPECT_EQ(odd.values, (std::vector<double>{3, 1, 2}));  // repeat order kept
  EXPECT_EQ(spread_of({4, 1, 3, 2}).median, 2.5);
  EXPECT_EQ(spread_of({}).median, 0);
}

TEST(CompareSummary, Efficiency) {
  EXPECT_DOUBLE_EQ(*efficiency(0.5, 4.0), 0.5);
  EXPECT_FALSE(efficiency(0.0, 1.0).has_value());
  EXPECT_FALSE(efficiency(1.0, 0.0).has_value());
}

namespace {
RunResult run(const std::string& sampler, int repeat, double relmse, double seconds) {
  RunResult r;
  r.sampler = sampler;
  r.repeat = repeat;
  r.relmse = relmse;
  r.mse = relmse / 10;
  r.seconds = seconds;
  r.spp = 10 + repeat;
  r.peak_rss_bytes = 1000 + repeat;
  return r;
}
}  // namespace

TEST(CompareSummary, RatiosArePerRepeatToTheFirstSampler) {
  // Repeat 1 ran on a slower machine state: both errors doubled; the ratio is unaffected.
  std::vector<RunResult> runs = {run("b", 0, 0.1, 2), run("a", 0, 0.2, 2), run("a", 1, 0.4, 2),
                                 run("b", 1, 0.1, 2)};
  runs[0].sampler_bytes = 64;
  auto s = summarize({"a", "b"}, runs);
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[0].name, "a");
  EXPECT_EQ(s[0].relmse_ratio.median, 1.0);
  EXPECT_EQ(s[1].relmse_ratio.values, (std::vector<double>{0.5, 0.25}));
  EXPECT_DOUBLE_EQ(s[1].relmse_ratio.median, 0.375);
  EXPECT_DOUBLE_EQ(s[0].relmse.median, 0.3);
  EXPECT_DOUBLE_EQ(s[0].efficiency.min, 1.0 / (0.4 * 2));
  EXPECT_DOUBLE_EQ(s[0].efficiency.max, 1.0 / (0.2 * 2));
  EXPECT_EQ(s[1].spp.values, (std::vector<double>{10, 11}));
  EXPECT_EQ(*s[1].sampler_bytes, 64);
  EXPECT_FALSE(s[0].sampler_bytes.has_value());
  EXPECT_EQ(s[1].peak_rss_bytes, 1001u);
  ASSERT_EQ(s[1].runs.size(), 2u);
  EXPECT_EQ(s[1].runs[1]->repeat, 1);
}

TEST(CompareSummary, InconsistentRunsAreErrors) {
  EXPECT_THROW(summarize({"a", "b"}, {run("a", 0, 1, 1), run("b", 1, 1, 1)}), Error);
  EXPECT_THROW(summarize({"a"}, {run("a", 0, 1, 1), run("a", 0, 1, 1)}), Error);
  EXPECT_THROW(summarize({"a"}, {run("c", 0, 1, 1)}), Error);
  EXPECT_THROW(summarize({"a", "b"}, {run("a", 0, 1, 1)}), Error);
}

TEST(CompareSummary, JsonHasEveryField) {
  std::vector<RunResult> runs = {run("a", 0, 0.2, 2), run("a", 1, 0.4, 2)};
  runs[0].checkpoints = {{0.5, 2, 0.8, 0.08}, {2, 10, 0.2, 0.02}};
  runs[0].visible_ratio = 0.25;
  runs[1].visible_ratio = 0.75;
  auto s = summarize({"a"}, runs);
  nlohmann::json j = sampler_summary_json(s[0]);
  EXPECT_EQ(j["visible_sample_ratio"]["median"], 0.5);
  EXPECT_EQ(j["runs"][1]["visible_sample_ratio"], 0.75);
  for (const char* k : {"spp", "seconds", "setup_seconds", "relmse", "mse", "efficiency",
                        "relmse_ratio", "visible_sample_ratio"}) {
    ASSERT_TRUE(j.contains(k)) << k;
    for (const char* f : {"median", "min", "max", "values"})
      EXPECT_TRUE(j[k].contains(f)) << k << "." << f;
  }
  EXPECT_TRUE(j["memory"].contains("sampler_bytes"));
  EXPECT_EQ(j["memory"]["peak_rss_bytes"], 1001);
  EXPECT_EQ(j["runs"][0]["checkpoints"][1][2], 0.2);
}

TEST(CompareSummary, TableShowsMedianRangeRatioAndEfficiency) {
  auto s = summarize({"a", "b"}, {run("a", 0, 0.2, 2), run("b", 0, 0.1, 2), run("a", 1, 0.4, 2),
                                  run("b", 1, 0.1, 2)});
  const std::string t = format_table(s);
  EXPECT_NE(t.find("relMSE median [min, max]"), std::string::npos) << t;
  EXPECT_NE(t.find("3.000e-01 [2.000e-01, 4.000e-01]"), std::string::npos) << t;
  EXPECT_NE(t.find("0.375"), std::string::npos) << t;  // b's ratio
  EXPECT_NE(t.find("5"), std::string::npos) << t;      // b's efficiency 1 / (0.1 * 2)
  const auto cells = table_cells(s);
  ASSERT_EQ(cells.size(), 3u);
  EXPECT_EQ(cells[2][0], "b");
  EXPECT_EQ(cells[0][5], "trimmed relMSE");
  EXPECT_EQ(cells[0][9], "efficiency");
  EXPECT_EQ(cells[2][9], "5");
  EXPECT_EQ(cells[2][10], "5");  // no setup time
  EXPECT_EQ(cells[0][11], "visible");
}

TEST(CompareSummary, CheckpointsAreSpacedLogarithmicallyAndEndAtTheFinalImage) {
  Image ref(2, 2, Rgb(1.0f));
  Film film(2, 2);
  ConvergenceRecorder rec(ref, nullptr, 2);  // two per decade: at least x3.16 apart
  RenderProgress p;
  for (int pass = 1; pass <= 200; ++pass) {
    for (int y = 0; y < 2; ++y)
      for (int x = 0; x < 2; ++x) film.add(x, y, Rgb(pass % 2 ? 2.0f : 0.0f));
    p.passes = pass;
    p.spp_done = pass;
    p.seconds = 0.01 * pass;
    rec.after_pass(p, film);
  }
  rec.finish(p, film.resolve());
  const auto& c = rec.checkpoints();
  ASSERT_GE(c.size(), 3u);
  for (size_t i = 1; i + 1 < c.size(); ++i)
    EXPECT_GE(c[i].seconds, c[i - 1].seconds * std::sqrt(10.0) - 1e-12);
  EXPECT_EQ(c.back().spp, 200);
  EXPECT_EQ(c.back().relmse, 0.0);  // 100 samples of 2 and 100 of 0: exactly the reference
  EXPECT_GT(c.front().relmse, 0.0);
  EXPECT_NEAR(c.front().relmse, 1.0 / 1.01, 1e-6);  // one sample of 2 against 1
}
