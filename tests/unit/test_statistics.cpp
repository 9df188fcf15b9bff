#include <gtest/gtest.h>

#include <cmath>

#include "support/statistics.h"

using namespace rll::test;

TEST(Statistics, ChiSquareSurvivalMatchesTables) {
  // Critical values from standard chi-square tables.
  EXPECT_NEAR(chi2_survival(3.841, 1), 0.05, 2e-4);
  EXPECT_NEAR(chi2_survival(18.307, 10), 0.05, 2e-4);
  EXPECT_NEAR(chi2_survival(124.342, 100), 0.05, 2e-4);
  EXPECT_NEAR(chi2_survival(6.635, 1), 0.01, 1e-4);
  EXPECT_NEAR(chi2_survival(0.0, 5), 1.0, 1e-12);
}

TEST(Statistics, PoolsSmallBinsAndFlagsZeroBins) {
  std::vector<double> expected = {100, 100, 1, 1, 1, 1, 1};
  std::vector<double> observed = {95, 103, 2, 0, 1, 1, 1};
  auto r = chi_square(observed, expected);
  EXPECT_EQ(r.dof, 2);  // bins: pooled small ones (5), 100, 100
  EXPECT_FALSE(r.sample_in_zero_bin);
  EXPECT_GT(r.p_value, 0.5);
  expected.push_back(0);
  observed.push_back(1);
  EXPECT_TRUE(chi_square(observed, expected).sample_in_zero_bin);
  EXPECT_EQ(chi_square(observed, expected).p_value, 0);
}

TEST(Statistics, SidakCorrection) {
  EXPECT_NEAR(sidak_alpha(0.01, 1), 0.01, 1e-12);
  double a = sidak_alpha(0.01, 100);
  EXPECT_NEAR(1 - std::pow(1 - a, 100), 0.01, 1e-12);
}
