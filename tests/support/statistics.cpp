#include "support/statistics.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace rll::test {

namespace {
// Series for the lower regularized gamma P(a, x), good for x < a + 1.
double gamma_p_series(double a, double x) {
  double sum = 1.0 / a, term = sum;
  for (int n = 1; n < 10000; ++n) {
    term *= x / (a + n);
    sum += term;
    if (std::abs(term) < std::abs(sum) * 1e-15) break;
  }
  return sum * std::exp(-x + a * std::log(x) - std::lgamma(a));
}
// Continued fraction for Q(a, x) (modified Lentz), good for x >= a + 1.
double gamma_q_fraction(double a, double x) {
  const double tiny = 1e-300;
  double b = x + 1 - a, c = 1 / tiny, d = 1 / b, h = d;
  for (int i = 1; i < 10000; ++i) {
    double an = -i * (i - a);
    b += 2;
    d = an * d + b;
    if (std::abs(d) < tiny) d = tiny;
    c = b + an / c;
    if (std::abs(c) < tiny) c = tiny;
    d = 1 / d;
    double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1) < 1e-15) break;
  }
  return std::exp(-x + a * std::log(x) - std::lgamma(a)) * h;
}
}  // namespace

double gamma_q(double a, double x) {
  if (x <= 0) return 1;
  return x < a + 1 ? 1 - gamma_p_series(a, x) : gamma_q_fraction(a, x);
}

double chi2_survival(double chi2, double dof) { return gamma_q(0.5 * dof, 0.5 * chi2); }

double sidak_alpha(double alpha, int tests) { return 1 - std::pow(1 - alpha, 1.0 / std::max(1, tests)); }

ChiSquareResult chi_square(const std::vector<double>& observed, const std::vector<double>& expected,
                           double min_expected) {
  ChiSquareResult r;
  std::vector<size_t> order(expected.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return expected[a] < expected[b]; });
  double pool_obs = 0, pool_exp = 0;
  int bins = 0;
  auto add_bin = [&](double o, double e) {
    r.chi2 += (o - e) * (o - e) / e;
    ++bins;
  };
  for (size_t i : order) {
    if (expected[i] <= 0) {
      if (observed[i] > 0) r.sample_in_zero_bin = true;
      continue;
    }
    if (expected[i] < min_expected || pool_exp > 0) {
      pool_obs += observed[i];
      pool_exp += expected[i];
      if (pool_exp >= min_expected) {
        add_bin(pool_obs, pool_exp);
        pool_obs = pool_exp = 0;
      }
      continue;
    }
    add_bin(observed[i], expected[i]);
  }
  if (pool_exp > 0) add_bin(pool_obs, pool_exp);  // a last small pool
  r.dof = std::max(0, bins - 1);
  r.p_value = r.dof > 0 ? chi2_survival(r.chi2, r.dof) : 1.0;
  if (r.sample_in_zero_bin) r.p_value = 0;
  return r;
}

}  // namespace rll::test
