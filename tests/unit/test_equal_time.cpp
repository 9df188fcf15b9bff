// Equal time that is equal (issue 45): a time-budgeted render sizes its passes to end at the
// budget, and compare says how far each run's seconds are from it.
#include <gtest/gtest.h>

#include "rll/eval/compare.h"
#include "rll/render/render.h"

using namespace rll;

TEST(EqualTime, PassIsSizedToTheBudgetLeft) {
  // Room for the whole scheduled pass: the schedule's size.
  EXPECT_EQ(pass_size_for_budget(8, 10.0, 0.5), 8);
  EXPECT_EQ(pass_size_for_budget(8, 4.0, 0.5), 8);  // exactly fits
  // Less room: as many whole samples per pixel as fit.
  EXPECT_EQ(pass_size_for_budget(8, 3.99, 0.5), 7);
  EXPECT_EQ(pass_size_for_budget(8, 1.2, 0.5), 2);
  EXPECT_EQ(pass_size_for_budget(64, 2.5, 0.1), 25);
  // Under one sample per pixel left (or the budget already spent): one, which the budget cuts.
  EXPECT_EQ(pass_size_for_budget(8, 0.3, 0.5), 1);
  EXPECT_EQ(pass_size_for_budget(8, -1.0, 0.5), 1);
  // No rate measured yet (the first pass): the schedule's size.
  EXPECT_EQ(pass_size_for_budget(4, 0.001, 0.0), 4);
  EXPECT_EQ(pass_size_for_budget(4, 0.001, -1.0), 4);
}

namespace {
RunResult timed_run(const std::string& sampler, int repeat, double seconds, double budget,
                    double mean_spp) {
  RunResult r;
  r.sampler = sampler;
  r.repeat = repeat;
  r.relmse = 0.1;
  r.seconds = seconds;
  r.budget = budget;
  r.spp = int(mean_spp);
  r.mean_spp = mean_spp;
  return r;
}
}  // namespace

TEST(EqualTime, CompareReportsSecondsAgainstTheBudgetAndTheSamplesTaken) {
  // (The summaries point into the runs: they are kept.)
  const std::vector<RunResult> runs = {
      timed_run("a", 0, 10.1, 10, 37.5), timed_run("b", 0, 10.5, 10, 20.25),
      timed_run("a", 1, 9.9, 10, 36.0), timed_run("b", 1, 9.6, 10, 19.0)};
  const auto s = summarize({"a", "b"}, runs);
  EXPECT_DOUBLE_EQ(s[0].budget_ratio.median, 1.0);
  EXPECT_DOUBLE_EQ(s[1].budget_ratio.max, 1.05);
  EXPECT_DOUBLE_EQ(s[0].mean_spp.median, 36.75);
  const nlohmann::json j = sampler_summary_json(s[1]);
  EXPECT_DOUBLE_EQ(j["seconds_per_budget"]["min"].get<double>(), 0.96);
  EXPECT_DOUBLE_EQ(j["mean_spp"]["median"].get<double>(), 19.625);
  EXPECT_EQ(j["runs"][0]["budget"], 10.0);
  EXPECT_EQ(j["runs"][0]["mean_spp"], 20.25);
  // The table's spp is the mean taken, not the complete count.
  EXPECT_EQ(table_cells(s)[1][1], "36.75");

  // b's runs are 5% over and 4% under: two warnings naming them; a's are within 3%.
  const std::vector<std::string> w = budget_warnings(s);
  ASSERT_EQ(w.size(), 2u);
  EXPECT_NE(w[0].find("b (repeat 1) took 10.500 s of a 10 s budget (+5.0%"), std::string::npos)
      << w[0];
  EXPECT_NE(w[1].find("b (repeat 2) took 9.600 s of a 10 s budget (-4.0%"), std::string::npos)
      << w[1];
  // Without a budget (equal spp) nothing is said, and no ratio is kept.
  const std::vector<RunResult> spp_runs = {timed_run("a", 0, 3, 0, 16)};
  const auto spp = summarize({"a"}, spp_runs);
  EXPECT_TRUE(budget_warnings(spp).empty());
  EXPECT_TRUE(spp[0].budget_ratio.values.empty());
  EXPECT_TRUE(sampler_summary_json(spp[0])["seconds_per_budget"].is_null());
}
