// Chi-square tests of direction samplers (BSDFs, lights): (cos theta, phi) histograms whose
// expected counts come from integrating the sampler's own pdf over every bin, and the Sidak
// budget shared by this suite's chi-square tests.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "rll/core/math.h"
#include "rll/core/rng.h"
#include "support/statistics.h"

namespace rll::test {

// Probability that any chi-square test of this suite's BSDF, light and warp tests (unit and stat
// programs) fails by chance at its fixed seed, and an upper bound on how many such tests there
// are. Each uses the Sidak-corrected level chi2_alpha(); raise the bound when adding tests (a
// stat test checks it against the case lists).
inline constexpr double kSuiteAlpha = 0.01;
inline constexpr int kSuiteChi2Tests = 100;
inline double chi2_alpha() {
  return sidak_alpha(kSuiteAlpha, kSuiteChi2Tests);
}

// A fixed seed per test case, from its name (FNV-1a), so that cases draw different numbers.
inline uint64_t seed_of(const std::string& name) {
  uint64_t h = 0xcbf29ce484222325ull;
  for (unsigned char ch : name) h = (h ^ ch) * 0x100000001b3ull;
  return h;
}

// The statistic, degrees of freedom and p-value, or why the test failed outright.
std::string describe(const ChiSquareResult& r);

// Bins of the sphere of directions in (cos theta, phi) around frame.n, cos theta in
// [cos_min, 1]: all of it by default, or a cap around frame.n that holds the whole support of a
// density concentrated there (directions below the cap count in its lowest row). Equal-sized
// bins in those coordinates have equal solid angle: d(omega) = d(cos) d(phi).
struct SphereBins {
  Frame frame;
  int cos_bins = 20, phi_bins = 40;
  double cos_min = -1;
  // Quadrature starts from this many sub-cells per bin and side: raise it for densities whose
  // support has thin parts (an adaptive rule cannot refine what no node has seen).
  int quadrature_start = 4;
  int count() const { return cos_bins * phi_bins; }
  int index(const Vec3& w) const;
  Vec3 direction(double cos_theta, double phi) const;
};

// Integral of a solid-angle density over every bin, by adaptive Gauss-Legendre quadrature in
// (theta, phi); `tolerance` is the absolute error allowed per bin, or a relative 1e-4 of
// the bin's integral where that is larger (far below the noise of any count the tests draw).
std::vector<double> integrate_bins(const SphereBins& bins,
                                   const std::function<double(const Vec3&)>& pdf,
                                   double tolerance = 1e-8);

// A direction sampler under test: a direction, or nullopt when it gives up (such samples are
// expected with probability 1 - integral of the pdf).
using DirectionSampler = std::function<std::optional<Vec3>(Pcg32&)>;

struct SphereChi2 {
  ChiSquareResult chi2;
  std::string failure;      // a sample whose own pdf is zero
  double pdf_integral = 0;  // the pdf integrated over the sphere
  double failure_rate = 0;  // fraction of samples that gave up
  bool passes(double alpha) const { return failure.empty() && chi2.p_value >= alpha; }
  std::string describe() const { return failure.empty() ? test::describe(chi2) : failure; }
};
// Draws `samples` directions and compares their histogram with n * (pdf integrated per bin),
// plus one bin for samples that gave up. A sample whose own pdf is zero fails outright.
SphereChi2 sphere_chi2(const SphereBins& bins, size_t samples, uint64_t seed,
                       const DirectionSampler& sample,
                       const std::function<double(const Vec3&)>& pdf);

}  // namespace rll::test
