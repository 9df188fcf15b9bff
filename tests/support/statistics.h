// Goodness-of-fit statistics for the sampler tests.
#pragma once

#include <vector>

namespace rll::test {

// Regularized upper incomplete gamma Q(a, x) = Gamma(a, x) / Gamma(a).
double gamma_q(double a, double x);
// P(X >= chi2) for X chi-square distributed with `dof` degrees of freedom.
double chi2_survival(double chi2, double dof);

struct ChiSquareResult {
  double chi2 = 0;
  int dof = 0;
  double p_value = 1;
  bool sample_in_zero_bin = false;  // an observation where the expected count is 0
};
// Pearson's test of observed counts against expected counts (same total). Bins with expected
// count below `min_expected` are pooled, in ascending order of expectation, until each pooled
// bin reaches it; a bin with zero expectation but observations is reported, not pooled.
ChiSquareResult chi_square(const std::vector<double>& observed, const std::vector<double>& expected,
                           double min_expected = 5.0);

// Per-test significance that keeps the family-wise error at `alpha` over `tests` tests (Sidak).
double sidak_alpha(double alpha, int tests);

}  // namespace rll::test
