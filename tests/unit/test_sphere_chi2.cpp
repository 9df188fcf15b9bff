// The direction chi-square machinery itself: bin integrals are exact for known densities, a
// sampler that follows its pdf passes, one that does not is rejected, and a sample where the pdf
// is zero fails outright.
#include <gtest/gtest.h>

#include <numeric>

#include "rll/core/sampling.h"
#include "support/sphere_chi2.h"

using namespace rll;
using namespace rll::test;

namespace {

double uniform_pdf(const Vec3&) {
  return 1 / (4 * M_PI);
}
double cosine_pdf(const Vec3& w) {
  return w.z > 0 ? w.z / M_PI : 0.0;
}

TEST(SphereChi2, BinIntegralsAreExact) {
  SphereBins bins;
  auto u = integrate_bins(bins, uniform_pdf);
  for (double v : u) ASSERT_NEAR(v, 1.0 / bins.count(), 1e-12);
  // Cosine density over the bin cos in [c0, c1]: (c1^2 - c0^2) / 2 / pi * (2 pi / phi_bins).
  auto c = integrate_bins(bins, cosine_pdf);
  for (int ci = 0; ci < bins.cos_bins; ++ci) {
    double c0 = -1 + 2.0 * ci / bins.cos_bins, c1 = c0 + 2.0 / bins.cos_bins;
    double expected = c0 >= 0 ? (c1 * c1 - c0 * c0) / bins.phi_bins : 0.0;
    for (int pi = 0; pi < bins.phi_bins; ++pi)
      ASSERT_NEAR(c[size_t(ci) * bins.phi_bins + pi], expected, 1e-9) << ci << ", " << pi;
  }
  EXPECT_NEAR(std::accumulate(c.begin(), c.end(), 0.0), 1.0, 1e-7);  // directions are floats
}

TEST(SphereChi2, AcceptsTheRightPdfAndRejectsAWrongOne) {
  SphereBins bins;
  bins.frame = Frame(normalize(Vec3(0.3f, -0.2f, 1)));  // any frame: the density is uniform
  auto uniform = [](Pcg32& rng) -> std::optional<Vec3> {
    return sample_uniform_sphere({rng.next_float(), rng.next_float()});
  };
  SphereChi2 right = sphere_chi2(bins, 100000, 1, uniform, uniform_pdf);
  EXPECT_TRUE(right.passes(chi2_alpha())) << right.describe();
  EXPECT_NEAR(right.pdf_integral, 1, 1e-9);
  // 10% too many samples in the upper hemisphere of the frame.
  auto lopsided = [&](const Vec3& w) {
    return uniform_pdf(w) * (bins.frame.to_local(w).z > 0 ? 1.1 : 0.9);
  };
  SphereChi2 wrong = sphere_chi2(bins, 100000, 1, uniform, lopsided);
  EXPECT_FALSE(wrong.passes(chi2_alpha())) << wrong.describe();
}

TEST(SphereChi2, GivingUpIsExpectedOnlyWherePdfMassIsMissing) {
  SphereBins bins;
  // Cosine samples, but half of them given up: the pdf must integrate to 1/2 to match.
  auto half = [](Pcg32& rng) -> std::optional<Vec3> {
    if (rng.next_float() < 0.5f) return std::nullopt;
    return sample_cosine_hemisphere({rng.next_float(), rng.next_float()});
  };
  SphereChi2 halved =
      sphere_chi2(bins, 100000, 2, half, [](const Vec3& w) { return cosine_pdf(w) / 2; });
  EXPECT_TRUE(halved.passes(chi2_alpha())) << halved.describe();
  EXPECT_NEAR(halved.failure_rate, 0.5, 0.01);
  SphereChi2 full = sphere_chi2(bins, 100000, 2, half, cosine_pdf);
  EXPECT_FALSE(full.passes(chi2_alpha())) << full.describe();
}

TEST(SphereChi2, SampleWithZeroPdfFailsOutright) {
  SphereBins bins;
  auto below = [](Pcg32& rng) -> std::optional<Vec3> {
    Vec3 w = sample_cosine_hemisphere({rng.next_float(), rng.next_float()});
    return rng.next_float() < 0.001f ? Vec3(w.x, w.y, -w.z) : w;  // a few below the surface
  };
  SphereChi2 r = sphere_chi2(bins, 20000, 3, below, cosine_pdf);
  EXPECT_FALSE(r.passes(chi2_alpha()));
  EXPECT_NE(r.failure.find("pdf 0"), std::string::npos) << r.describe();
}

}  // namespace
