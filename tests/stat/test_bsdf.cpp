// Bsdf::sample against Bsdf::pdf: chi-square goodness of fit of the sampled directions, the pdf's
// integral over the sphere, and the white-furnace albedo, for every material, roughness and
// incident angle in bsdf_cases().
#include <gtest/gtest.h>

#include "support/bsdf_cases.h"
#include "support/sphere_chi2.h"

using namespace rll;
using namespace rll::test;

namespace {

class BsdfSampling : public ::testing::TestWithParam<BsdfCase> {};

TEST_P(BsdfSampling, SampledDirectionsFollowPdf) {
  const BsdfCase& c = GetParam();
  const Bsdf bsdf = c.bsdf();
  const Vec3 wo = c.wo();
  SphereBins bins;
  bins.frame = Frame(c.ng());
  SphereChi2 r = bsdf_chi2(bsdf, wo, bins, 400000, seed_of(c.name()));
  EXPECT_TRUE(r.passes(chi2_alpha())) << r.describe();
  // The pdf of a reflection-only BSDF holds at most all of the sphere's mass; a Lambertian lobe
  // of a front-facing wo holds exactly all of it.
  EXPECT_LE(r.pdf_integral, 1 + 1e-4);
  if (c.type == MaterialType::Diffuse && c.tilt == 0) {
    EXPECT_NEAR(r.pdf_integral, 1.0, 1e-4);
  }
  RecordProperty("p_value", std::to_string(r.chi2.p_value));
  RecordProperty("pdf_integral", std::to_string(r.pdf_integral));
  RecordProperty("failure_rate", std::to_string(r.failure_rate));
}

// White furnace: the directional albedo integral of f cos over the hemisphere, estimated with the
// BSDF's own samples, may not exceed 1 for a white material.
TEST_P(BsdfSampling, WhiteFurnaceAlbedoAtMostOne) {
  const BsdfCase& c = GetParam();
  Material m = test_material(c.type, c.roughness);
  m.albedo = Rgb(1);
  m.specular = Rgb(1);
  if (c.type == MaterialType::Conductor) m.k = Rgb(1e4f);  // a perfect mirror: Fresnel = 1
  const Vec3 wo = c.wo();
  const Bsdf bsdf(m, m.albedo, c.ns(), c.ng(), wo);
  Pcg32 rng(seed_of(c.name()));
  const int n = 100000;
  double sum = 0, sum2 = 0;
  for (int i = 0; i < n; ++i) {
    BsdfSample s;
    float u_lobe = rng.next_float();
    Vec2 u{rng.next_float(), rng.next_float()};
    double v = 0;
    if (bsdf.sample(wo, u_lobe, u, s)) v = s.f.y * absdot(s.wi, bsdf.shading_normal()) / s.pdf;
    sum += v;
    sum2 += v * v;
  }
  const double mean = sum / n, se = std::sqrt(std::max(0.0, sum2 / n - mean * mean) / n);
  RecordProperty("albedo", std::to_string(mean));
  EXPECT_LE(mean, 1 + 5 * se + 1e-3) << "albedo " << mean << " +- " << se;
  if (c.type == MaterialType::Diffuse && c.tilt == 0) {
    EXPECT_NEAR(mean, 1.0, 1e-5);  // cosine sampling of a white Lambertian: every sample is 1
  }
}

INSTANTIATE_TEST_SUITE_P(AllMaterials, BsdfSampling, ::testing::ValuesIn(bsdf_cases()),
                         [](const auto& info) { return info.param.name(); });

struct GgxCase {
  float alpha, theta_o;
  Vec3 wo() const { return {std::sin(radians(theta_o)), 0, std::cos(radians(theta_o))}; }
};

std::vector<GgxCase> ggx_cases() {
  std::vector<GgxCase> cases;
  for (float alpha : {0.05f, 0.15f, 0.4f, 1.0f})
    for (float theta : {0.0f, 30.0f, 60.0f, 80.0f, 89.0f}) cases.push_back({alpha, theta});
  return cases;
}

class GgxVisibleNormals : public ::testing::TestWithParam<GgxCase> {};

// Heitz's visible-normal sampling against the density it is meant to follow.
TEST_P(GgxVisibleNormals, SamplesFollowVisibleNormalDensity) {
  const GgxCase& c = GetParam();
  const Ggx ggx{c.alpha};
  const Vec3 wo = c.wo();
  SphereBins bins;
  auto sample = [&](Pcg32& rng) -> std::optional<Vec3> {
    return ggx.sample_visible(wo, {rng.next_float(), rng.next_float()});
  };
  auto pdf = [&](const Vec3& m) { return double(ggx.visible_d(wo, m)); };
  SphereChi2 r =
      sphere_chi2(bins, 200000, uint64_t(c.alpha * 1000) * 100 + uint64_t(c.theta_o), sample, pdf);
  EXPECT_TRUE(r.passes(chi2_alpha())) << r.describe();
  EXPECT_NEAR(r.pdf_integral, 1.0, 1e-3);
  RecordProperty("p_value", std::to_string(r.chi2.p_value));
}

INSTANTIATE_TEST_SUITE_P(Alphas, GgxVisibleNormals, ::testing::ValuesIn(ggx_cases()),
                         [](const auto& info) {
                           return fmt::format("a{:03d}_o{:02d}",
                                              int(std::lround(info.param.alpha * 100)),
                                              int(info.param.theta_o));
                         });

}  // namespace

// Every chi-square test of the suite is counted in kSuiteChi2Tests, the basis of the Sidak
// correction; the BSDF and GGX ones are generated from these lists.
size_t glass_chi2_test_count();  // tests/stat/test_bsdf_glass.cpp
size_t bsdf_chi2_test_count() {
  return bsdf_cases().size() + ggx_cases().size() + glass_chi2_test_count();
}
