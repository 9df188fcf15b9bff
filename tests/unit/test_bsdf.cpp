// Single properties of the BSDFs: sample() agrees with pdf() and eval(), eval is reciprocal,
// nothing leaks below the geometric surface, GGX's distributions are normalised, Fresnel limits.
#include <gtest/gtest.h>

#include <numeric>

#include "rll/core/sampling.h"
#include "support/bsdf_cases.h"
#include "support/sphere_chi2.h"

using namespace rll;
using namespace rll::test;

namespace {

bool near_rel(float a, float b, float rel = 1e-5f) {
  return std::abs(a - b) <= rel * std::max(std::abs(a), std::abs(b)) + 1e-30f;
}

class BsdfCases : public ::testing::TestWithParam<BsdfCase> {};

TEST_P(BsdfCases, SampleReturnsItsPdfAndValue) {
  const BsdfCase& c = GetParam();
  const Bsdf bsdf = c.bsdf();
  const Vec3 wo = c.wo();
  Pcg32 rng(seed_of(c.name()));
  int sampled = 0;
  for (int i = 0; i < 2000; ++i) {
    BsdfSample s;
    float u_lobe = rng.next_float();
    Vec2 u{rng.next_float(), rng.next_float()};
    if (!bsdf.sample(wo, u_lobe, u, s)) continue;
    ++sampled;
    ASSERT_NEAR(length(s.wi), 1.0f, 1e-5f);
    ASSERT_GT(dot(s.wi, c.ng()), 0) << "a reflection below the geometric surface";
    ASSERT_GT(s.pdf, 0);
    ASSERT_TRUE(near_rel(s.pdf, bsdf.pdf(wo, s.wi))) << s.pdf << " vs " << bsdf.pdf(wo, s.wi);
    Rgb f = bsdf.eval(wo, s.wi);
    for (int k = 0; k < 3; ++k) ASSERT_TRUE(near_rel(s.f[k], f[k])) << s.f[k] << " vs " << f[k];
  }
  // wo below the surface (the om70 cases: behind the tilted shading normal) samples nothing.
  if (dot(wo, c.ns()) > 0)
    EXPECT_GT(sampled, 500);
  else
    EXPECT_EQ(sampled, 0);
}

TEST_P(BsdfCases, EvalIsReciprocal) {
  const BsdfCase& c = GetParam();
  const Bsdf bsdf = c.bsdf();
  Pcg32 rng(seed_of(c.name()) + 1);
  for (int i = 0; i < 2000; ++i) {
    Vec3 a = sample_cosine_hemisphere({rng.next_float(), rng.next_float()});
    Vec3 b = sample_uniform_sphere({rng.next_float(), rng.next_float()});
    Rgb fab = bsdf.eval(a, b), fba = bsdf.eval(b, a);
    for (int k = 0; k < 3; ++k)
      ASSERT_TRUE(near_rel(fab[k], fba[k], 1e-4f))
          << "f(a,b) = " << fab[k] << ", f(b,a) = " << fba[k];
    // pdf and value vanish together below the geometric surface.
    if (b.z <= 0) {
      ASSERT_EQ(bsdf.pdf(a, b), 0);
      ASSERT_TRUE(is_black(fab));
    }
  }
}

INSTANTIATE_TEST_SUITE_P(AllMaterials, BsdfCases, ::testing::ValuesIn(bsdf_cases()),
                         [](const auto& info) { return info.param.name(); });

double integrate_sphere(const std::function<double(const Vec3&)>& f) {
  SphereBins bins;
  bins.cos_bins = 20;
  bins.phi_bins = 8;
  auto v = integrate_bins(bins, f, 1e-9);
  return std::accumulate(v.begin(), v.end(), 0.0);
}

TEST(Ggx, ProjectedNormalDistributionIntegratesToOne) {
  for (float alpha : {0.05f, 0.15f, 0.4f, 1.0f}) {
    Ggx ggx{alpha};
    double integral =
        integrate_sphere([&](const Vec3& m) { return m.z > 0 ? ggx.d(m) * m.z : 0.0; });
    EXPECT_NEAR(integral, 1.0, 1e-3) << "alpha " << alpha;
  }
}

TEST(Ggx, VisibleNormalDensityIntegratesToOne) {
  for (float alpha : {0.05f, 0.15f, 0.4f, 1.0f})
    for (float theta : {0.0f, 30.0f, 60.0f, 80.0f, 89.0f}) {
      Ggx ggx{alpha};
      Vec3 wo(std::sin(radians(theta)), 0, std::cos(radians(theta)));
      double integral = integrate_sphere([&](const Vec3& m) { return ggx.visible_d(wo, m); });
      EXPECT_NEAR(integral, 1.0, 1e-3) << "alpha " << alpha << ", theta_o " << theta;
    }
}

TEST(Ggx, SmithMaskingLimits) {
  Ggx ggx{0.3f};
  EXPECT_FLOAT_EQ(ggx.g1(Vec3(0, 0, 1)), 1.0f);  // nothing is masked at normal incidence
  EXPECT_LT(ggx.g1(normalize(Vec3(1, 0, 0.01f))), 0.1f);
  EXPECT_LE(ggx.g(Vec3(0, 0, 1), normalize(Vec3(1, 0, 1))), ggx.g1(normalize(Vec3(1, 0, 1))));
}

TEST(Fresnel, DielectricLimits) {
  EXPECT_NEAR(fresnel_dielectric(1, 1.5f), 0.04f, 1e-6f);    // ((1.5-1)/(1.5+1))^2
  EXPECT_NEAR(fresnel_dielectric(0, 1.5f), 1.0f, 1e-6f);     // grazing
  EXPECT_NEAR(fresnel_dielectric(0.7f, 1.0f), 0.0f, 1e-7f);  // no interface
  EXPECT_EQ(fresnel_dielectric(-0.1f, 1.5f), 1.0f);  // from inside, beyond the critical angle
}

TEST(Fresnel, ConductorLimits) {
  // Normal incidence: ((eta-1)^2 + k^2) / ((eta+1)^2 + k^2).
  Rgb eta(1.66f, 0.88f, 0.52f), k(9.22f, 6.27f, 4.84f);
  Rgb f = fresnel_conductor(1, eta, k);
  for (int c = 0; c < 3; ++c) {
    float expected = (sqr(eta[c] - 1) + sqr(k[c])) / (sqr(eta[c] + 1) + sqr(k[c]));
    EXPECT_NEAR(f[c], expected, 1e-5f);
  }
  Rgb grazing = fresnel_conductor(0, eta, k);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(grazing[c], 1.0f, 1e-5f);
  // k = 0 is a dielectric.
  EXPECT_NEAR(fresnel_conductor(0.6f, Rgb(1.5f), Rgb(0)).x, fresnel_dielectric(0.6f, 1.5f), 1e-5f);
}

}  // namespace
