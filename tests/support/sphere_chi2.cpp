#include "support/sphere_chi2.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace rll::test {

std::string describe(const ChiSquareResult& r) {
  if (r.sample_in_zero_bin) return "a sample fell in a bin whose expected count is 0";
  return fmt::format("chi2 = {:.2f} with {} dof, p = {:.3g}", r.chi2, r.dof, r.p_value);
}

int SphereBins::index(const Vec3& w) const {
  Vec3 l = frame.to_local(w);
  // cos theta from the angle, not from l.z, whose float rounding near the pole would blur caps
  // narrower than a few 1e-7 in cos theta.
  double c = std::cos(std::atan2(std::hypot(double(l.x), double(l.y)), double(l.z)));
  double phi = std::atan2(double(l.y), double(l.x));
  if (phi < 0) phi += 2 * M_PI;
  int ci = std::clamp(int((c - cos_min) / (1 - cos_min) * cos_bins), 0, cos_bins - 1);
  int pi = std::min(phi_bins - 1, int(phi / (2 * M_PI) * phi_bins));
  return ci * phi_bins + pi;
}

Vec3 SphereBins::direction(double c, double phi) const {
  double s = std::sqrt(std::max(0.0, 1 - c * c));
  return frame.to_world(Vec3(float(s * std::cos(phi)), float(s * std::sin(phi)), float(c)));
}

namespace {

// Adaptive product Gauss-Legendre quadrature over rectangles: a rectangle is split in four until
// the four halves agree with the whole to the tolerance. The rule never evaluates the edges, where
// densities jump (the horizon lies on bin edges).
class AdaptiveQuadrature {
 public:
  AdaptiveQuadrature(const std::function<double(double, double)>& f, int max_depth)
      : m_f(f), m_max_depth(max_depth) {}

  double integrate(double x0, double x1, double y0, double y1, double tolerance) const {
    return refine(x0, x1, y0, y1, rule(x0, x1, y0, y1), tolerance, m_max_depth);
  }

 private:
  // 4-point Gauss-Legendre in each dimension: exact for polynomials of degree 7.
  double rule(double x0, double x1, double y0, double y1) const {
    static constexpr double node[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563,
                                       0.8611363115940526};
    static constexpr double weight[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461,
                                         0.3478548451374538};
    const double xm = 0.5 * (x0 + x1), xr = 0.5 * (x1 - x0);
    const double ym = 0.5 * (y0 + y1), yr = 0.5 * (y1 - y0);
    double s = 0;
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j)
        s += weight[i] * weight[j] * m_f(xm + xr * node[i], ym + yr * node[j]);
    return s * xr * yr;
  }

  double refine(double x0, double x1, double y0, double y1, double whole, double tolerance,
                int depth) const {
    const double xm = 0.5 * (x0 + x1), ym = 0.5 * (y0 + y1);
    const double q[4] = {rule(x0, xm, y0, ym), rule(xm, x1, y0, ym), rule(x0, xm, ym, y1),
                         rule(xm, x1, ym, y1)};
    const double sum = q[0] + q[1] + q[2] + q[3];
    // The relative bound keeps peaks from being refined to an absolute precision they do not
    // need (and below the float rounding noise of the densities under test).
    if (depth <= 0 || std::abs(sum - whole) <= std::max(tolerance, 1e-4 * std::abs(sum)))
      return sum;
    const double t = tolerance / 4;
    return refine(x0, xm, y0, ym, q[0], t, depth - 1) + refine(xm, x1, y0, ym, q[1], t, depth - 1) +
           refine(x0, xm, ym, y1, q[2], t, depth - 1) + refine(xm, x1, ym, y1, q[3], t, depth - 1);
  }

  const std::function<double(double, double)>& m_f;
  int m_max_depth;
};

}  // namespace

std::vector<double> integrate_bins(const SphereBins& bins,
                                   const std::function<double(const Vec3&)>& pdf,
                                   double tolerance) {
  // Integrated over (theta, phi) with d(omega) = sin(theta) d(theta) d(phi): peaks at the pole,
  // which are needles in cos theta, keep a width in theta that the first nodes can see.
  const std::function<double(double, double)> f = [&](double theta, double phi) {
    return pdf(bins.direction(std::cos(theta), phi)) * std::sin(theta);
  };
  AdaptiveQuadrature quadrature(f, 8);
  // Each bin starts from a grid of sub-cells so that a narrow peak cannot slip between the first
  // nodes. Edges come from integers so that on the whole sphere cos theta = 0 is exactly an edge.
  const int kStart = std::max(1, bins.quadrature_start);
  const int nc = bins.cos_bins * kStart, np = bins.phi_bins * kStart;
  auto theta_edge = [&](int k) {
    if (bins.cos_min == -1) return std::acos(double(2 * k - nc) / nc);
    return std::acos(bins.cos_min + (1 - bins.cos_min) * k / nc);
  };
  auto phi_edge = [&](int k) { return 2 * M_PI * k / np; };
  std::vector<double> result(size_t(bins.count()), 0.0);
  for (int ci = 0; ci < bins.cos_bins; ++ci)
    for (int pi = 0; pi < bins.phi_bins; ++pi) {
      double sum = 0;
      for (int a = ci * kStart; a < (ci + 1) * kStart; ++a)
        for (int b = pi * kStart; b < (pi + 1) * kStart; ++b)
          sum += quadrature.integrate(theta_edge(a + 1), theta_edge(a), phi_edge(b),
                                      phi_edge(b + 1), tolerance / (kStart * kStart));
      result[size_t(ci) * bins.phi_bins + pi] = std::max(0.0, sum);
    }
  return result;
}

SphereChi2 sphere_chi2(const SphereBins& bins, size_t samples, uint64_t seed,
                       const DirectionSampler& sample,
                       const std::function<double(const Vec3&)>& pdf) {
  SphereChi2 out;
  const size_t n_bins = size_t(bins.count());
  std::vector<double> observed(n_bins + 1, 0.0);  // the last bin: samples that gave up
  Pcg32 rng(seed);
  for (size_t i = 0; i < samples; ++i) {
    std::optional<Vec3> w = sample(rng);
    if (!w) {
      observed[n_bins] += 1;
      continue;
    }
    if (!(pdf(*w) > 0) && out.failure.empty())
      out.failure =
          fmt::format("sample {} = ({}, {}, {}) has pdf {}", i, w->x, w->y, w->z, pdf(*w));
    observed[size_t(bins.index(*w))] += 1;
  }
  std::vector<double> expected = integrate_bins(bins, pdf);
  out.pdf_integral = std::accumulate(expected.begin(), expected.end(), 0.0);
  for (double& e : expected) e *= double(samples);
  expected.push_back(std::max(0.0, 1 - out.pdf_integral) * double(samples));
  out.failure_rate = observed[n_bins] / double(samples);
  out.chi2 = chi_square(observed, expected);
  return out;
}

}  // namespace rll::test
