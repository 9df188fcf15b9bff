// sample_li against pdf_li for triangle lights, in both of its modes (uniform in solid angle for
// triangles that subtend more than 0.01 sr, uniform in area for the others): a chi-square test
// of the sampled directions against the solid-angle pdf, Monte Carlo estimates of the triangle's
// solid angle and vector irradiance against their analytic values, and uniformity of the area
// warp.
#include <gtest/gtest.h>

#include "rll/core/sampling.h"
#include "support/light_cases.h"
#include "support/sphere_chi2.h"

using namespace rll;
using namespace rll::test;

namespace {

// The point where the ray p + t w meets the light's triangle (Moller-Trumbore, in double). The
// triangle is grown by a relative 1e-4 so that sampled points on its edges, whose float
// directions are rounded, still hit it.
std::optional<Vec3> hit_triangle(const Light& l, const Vec3& p, const Vec3& w) {
  constexpr double eps = 1e-4;
  const double e1[3] = {double(l.p1.x) - l.p0.x, double(l.p1.y) - l.p0.y, double(l.p1.z) - l.p0.z};
  const double e2[3] = {double(l.p2.x) - l.p0.x, double(l.p2.y) - l.p0.y, double(l.p2.z) - l.p0.z};
  const double d[3] = {w.x, w.y, w.z};
  const double s[3] = {double(p.x) - l.p0.x, double(p.y) - l.p0.y, double(p.z) - l.p0.z};
  auto cross3 = [](const double* a, const double* b, double* r) {
    r[0] = a[1] * b[2] - a[2] * b[1];
    r[1] = a[2] * b[0] - a[0] * b[2];
    r[2] = a[0] * b[1] - a[1] * b[0];
  };
  auto dot3 = [](const double* a, const double* b) {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  };
  double pv[3], qv[3];
  cross3(d, e2, pv);
  const double det = dot3(e1, pv);
  if (det == 0) return std::nullopt;
  const double u = dot3(s, pv) / det;
  if (u < -eps || u > 1 + eps) return std::nullopt;
  cross3(s, e1, qv);
  const double v = dot3(d, qv) / det;
  if (v < -eps || u + v > 1 + eps) return std::nullopt;
  const double t = dot3(e2, qv) / det;
  if (t <= 0) return std::nullopt;
  return Vec3(float(p.x + t * w.x), float(p.y + t * w.y), float(p.z + t * w.z));
}

// Bins around the direction to the triangle, on a cap that holds all of it.
SphereBins bins_towards(const LightCase& c) {
  SphereBins bins;
  const Vec3 axis = normalize(c.light.centroid() - c.p);
  bins.frame = Frame(axis);
  double max_angle = 0;
  for (const Vec3& v : {c.light.p0, c.light.p1, c.light.p2})
    max_angle = std::max(max_angle, double(safe_acos(dot(axis, normalize(v - c.p)))));
  bins.cos_min = max_angle < 1.4 ? std::cos(1.1 * max_angle + 1e-3) : -1.0;
  bins.cos_bins = 12;
  bins.phi_bins = 24;
  return bins;
}

std::vector<LightCase> chi2_light_cases() {
  std::vector<LightCase> cases = triangle_light_cases();
  std::erase_if(cases, [](const LightCase& c) { return c.thin; });
  return cases;
}

class TriangleLightChi2 : public ::testing::TestWithParam<LightCase> {};
class TriangleLight : public ::testing::TestWithParam<LightCase> {};

TEST_P(TriangleLightChi2, SampledDirectionsFollowSolidAnglePdf) {
  const LightCase& c = GetParam();
  auto sample = [&](Pcg32& rng) -> std::optional<Vec3> {
    LightLiSample s = sample_li(c.light, c.p, {rng.next_float(), rng.next_float()});
    if (!(s.pdf > 0)) return std::nullopt;
    return s.wi;
  };
  auto pdf = [&](const Vec3& w) -> double {
    std::optional<Vec3> y = hit_triangle(c.light, c.p, w);
    if (!y || is_black(emitted_radiance(c.light, -w))) return 0;
    return pdf_li(c.light, c.p, *y);
  };
  SphereChi2 r = sphere_chi2(bins_towards(c), 200000, seed_of(c.name), sample, pdf);
  EXPECT_TRUE(r.passes(chi2_alpha())) << r.describe();
  // pdf_li integrates to 1 over the triangle's solid angle, and sample_li always succeeds.
  EXPECT_NEAR(r.pdf_integral, 1.0, 2e-3);
  EXPECT_EQ(r.failure_rate, 0);
  RecordProperty("p_value", std::to_string(r.chi2.p_value));
}

// E[1/pdf] is the solid angle; E[w/pdf] the vector irradiance (Lambert).
TEST_P(TriangleLight, EstimatesSolidAngleAndIrradiance) {
  const LightCase& c = GetParam();
  const Light& l = c.light;
  Pcg32 rng(seed_of(c.name) + 1);
  const int n = 200000;
  double sum[4] = {0, 0, 0, 0}, sum2[4] = {0, 0, 0, 0};
  for (int i = 0; i < n; ++i) {
    LightLiSample s = sample_li(l, c.p, {rng.next_float(), rng.next_float()});
    ASSERT_GT(s.pdf, 0);
    const double v[4] = {1 / s.pdf, s.wi.x / s.pdf, s.wi.y / s.pdf, s.wi.z / s.pdf};
    for (int k = 0; k < 4; ++k) {
      sum[k] += v[k];
      sum2[k] += v[k] * v[k];
    }
  }
  const auto phi = triangle_vector_irradiance(c.p, l.p0, l.p1, l.p2);
  const double expected[4] = {reference_solid_angle(c.p, l.p0, l.p1, l.p2), phi[0], phi[1], phi[2]};
  const char* what[4] = {"solid angle", "irradiance x", "irradiance y", "irradiance z"};
  for (int k = 0; k < 4; ++k) {
    const double mean = sum[k] / n;
    const double se = std::sqrt(std::max(0.0, sum2[k] / n - mean * mean) / n);
    // With solid-angle sampling 1/pdf is the constant float solid angle: se = 0, float precision.
    EXPECT_NEAR(mean, expected[k], 5 * se + 2e-5 * std::abs(expected[0]))
        << what[k] << ": estimate " << mean << " +- " << se << ", analytic " << expected[k];
  }
}

auto light_case_name = [](const auto& info) { return info.param.name; };
INSTANTIATE_TEST_SUITE_P(Configurations, TriangleLightChi2, ::testing::ValuesIn(chi2_light_cases()),
                         light_case_name);
INSTANTIATE_TEST_SUITE_P(Configurations, TriangleLight, ::testing::ValuesIn(triangle_light_cases()),
                         light_case_name);

// The square-to-triangle warp under sample_li is uniform in area: K^2 congruent sub-triangles
// of the barycentric domain each expect n / K^2 samples.
TEST(TriangleSampling, UniformOverArea) {
  constexpr int K = 12;
  const size_t n = 200000;
  std::vector<double> observed(size_t(2 * K * K), 0.0), expected(observed.size(), 0.0);
  // Cell (i, j) with i + j < K holds a lower sub-triangle and, if i + j < K - 1, an upper one.
  auto index = [&](double b0, double b1) {
    int i = std::min(K - 1, int(b0 * K)), j = std::min(K - 1, int(b1 * K));
    bool upper = (b0 * K - i) + (b1 * K - j) > 1;
    return size_t(2 * (i * K + j) + (upper ? 1 : 0));
  };
  for (int i = 0; i < K; ++i)
    for (int j = 0; j < K; ++j) {
      if (i + j < K) expected[size_t(2 * (i * K + j))] = double(n) / (K * K);
      if (i + j < K - 1) expected[size_t(2 * (i * K + j) + 1)] = double(n) / (K * K);
    }
  Pcg32 rng(77);
  for (size_t s = 0; s < n; ++s) {
    Vec2 b = sample_uniform_triangle({rng.next_float(), rng.next_float()});
    ASSERT_GE(b.x, 0);
    ASSERT_GE(b.y, 0);
    ASSERT_LE(b.x + b.y, 1.0f);
    observed[index(b.x, b.y)] += 1;
  }
  ChiSquareResult r = chi_square(observed, expected);
  EXPECT_GE(r.p_value, chi2_alpha()) << describe(r);
}

}  // namespace

size_t light_chi2_test_count() {
  return chi2_light_cases().size() + 1;
}
