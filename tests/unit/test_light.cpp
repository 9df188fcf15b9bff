// Single properties of the lights: sample_li's pdf is pdf_li's, its point lies on the light and
// its direction and distance lead there, one-sided lights are dark from behind, and the delta
// lights and power formulas hold.
#include <gtest/gtest.h>

#include "rll/core/rng.h"
#include "support/light_cases.h"
#include "support/sphere_chi2.h"

using namespace rll;
using namespace rll::test;

namespace {

class TriangleLightCases : public ::testing::TestWithParam<LightCase> {};

TEST_P(TriangleLightCases, SampleMatchesPdfLi) {
  const LightCase& c = GetParam();
  const Light& l = c.light;
  Pcg32 rng(seed_of(c.name));
  for (int i = 0; i < 5000; ++i) {
    LightLiSample s = sample_li(l, c.p, {rng.next_float(), rng.next_float()});
    ASSERT_GT(s.pdf, 0);
    const float p = pdf_li(l, c.p, s.point);
    ASSERT_NEAR(s.pdf, p, 1e-4f * p) << "sample " << i;
    // The point is on the triangle: in its plane, with non-negative barycentrics.
    const Vec3 e1 = l.p1 - l.p0, e2 = l.p2 - l.p0, d = s.point - l.p0;
    ASSERT_NEAR(dot(d, l.n), 0, 1e-5f * (1 + length(d)));
    const float area2 = length(cross(e1, e2));
    const float b1 = dot(cross(d, e2), l.n) / area2, b2 = dot(cross(e1, d), l.n) / area2;
    ASSERT_GE(b1, -1e-5f);
    ASSERT_GE(b2, -1e-5f);
    ASSERT_LE(b1 + b2, 1 + 1e-5f);
    // Direction and distance lead from p to the point.
    ASSERT_NEAR(s.dist, length(s.point - c.p), 1e-5f * s.dist);
    const Vec3 to = c.p + s.wi * s.dist - s.point;
    ASSERT_LT(length(to), 1e-4f * (1 + s.dist));
    ASSERT_EQ(s.L, l.radiance);
  }
}

INSTANTIATE_TEST_SUITE_P(Configurations, TriangleLightCases,
                         ::testing::ValuesIn(triangle_light_cases()),
                         [](const auto& info) { return info.param.name; });

TEST(TriangleLight, OneSidedIsDarkFromBehind) {
  const Light front = make_triangle_light({0, 0, 1}, {0, 1, 1}, {1, 0, 1}, Rgb(2), false, 0);
  ASSERT_NEAR(front.n.z, -1, 1e-6f);  // faces the origin
  ASSERT_NEAR(front.area, 0.5f, 1e-6f);
  LightLiSample seen = sample_li(front, {0.2f, 0.2f, 0}, {0.3f, 0.6f});
  EXPECT_GT(seen.pdf, 0);
  LightLiSample behind = sample_li(front, {0.2f, 0.2f, 2}, {0.3f, 0.6f});
  EXPECT_EQ(behind.pdf, 0);
  EXPECT_TRUE(is_black(behind.L));
  EXPECT_EQ(emitted_radiance(front, {0, 0, -1}), Rgb(2));
  EXPECT_TRUE(is_black(emitted_radiance(front, {0, 0, 1})));

  Light both = front;
  both.two_sided = true;
  LightLiSample from_back = sample_li(both, {0.2f, 0.2f, 2}, {0.3f, 0.6f});
  EXPECT_GT(from_back.pdf, 0);
  EXPECT_EQ(from_back.L, Rgb(2));
  EXPECT_EQ(emitted_radiance(both, {0, 0, 1}), Rgb(2));
}

TEST(TriangleLight, InThePlaneOrDegenerateGivesNothing) {
  const Light l = make_triangle_light({0, 0, 1}, {0, 1, 1}, {1, 0, 1}, Rgb(1), true, 0);
  EXPECT_EQ(sample_li(l, {3, 3, 1}, {0.5f, 0.5f}).pdf, 0);  // edge-on
  EXPECT_EQ(pdf_li(l, {3, 3, 1}, {0.2f, 0.2f, 1}), 0);
  const Light flat = make_triangle_light({0, 0, 1}, {1, 1, 1}, {2, 2, 1}, Rgb(1), true, 0);
  EXPECT_EQ(flat.area, 0);
  EXPECT_EQ(sample_li(flat, {0, 0, 0}, {0.5f, 0.5f}).pdf, 0);
  EXPECT_EQ(pdf_li(flat, {0, 0, 0}, {1, 1, 1}), 0);
}

TEST(TriangleLight, RefreshFollowsMovedVertices) {
  Light l = make_triangle_light({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, Rgb(1), false, 0);
  EXPECT_NEAR(l.n.z, 1, 1e-6f);
  l.p1 = {2, 0, 0};
  l.p2 = {0, 0, 2};  // now in the y = 0 plane, twice as long each way
  refresh_triangle_light(l);
  EXPECT_NEAR(l.area, 2.0f, 1e-6f);
  EXPECT_NEAR(l.n.y, -1, 1e-6f);
}

TEST(DeltaLights, PointAndDirectional) {
  const Light point = make_point_light({0, 3, 4}, Rgb(10));
  EXPECT_TRUE(point.is_delta());
  LightLiSample s = sample_li(point, {0, 0, 0}, {0.1f, 0.9f});
  EXPECT_EQ(s.pdf, 1);
  EXPECT_NEAR(s.dist, 5, 1e-6f);
  EXPECT_NEAR(s.L.x, 10.0f / 25, 1e-6f);  // intensity over distance squared
  EXPECT_NEAR(s.wi.y, 0.6f, 1e-6f);
  EXPECT_EQ(pdf_li(point, {0, 0, 0}, {0, 3, 4}), 0);  // never hit by a BSDF ray

  const Light sun = make_directional_light({0, 2, 0}, Rgb(3));
  EXPECT_TRUE(sun.is_delta());
  EXPECT_FALSE(sun.has_position());
  LightLiSample d = sample_li(sun, {5, 5, 5}, {0.4f, 0.4f});
  EXPECT_EQ(d.wi, Vec3(0, 1, 0));
  EXPECT_TRUE(std::isinf(d.dist));
  EXPECT_EQ(d.L, Rgb(3));
}

TEST(LightPower, Formulas) {
  const Light tri = make_triangle_light({0, 0, 0}, {2, 0, 0}, {0, 1, 0}, Rgb(1), false, 0);
  EXPECT_NEAR(light_power(tri, 10), kPi * 1.0f, 1e-5f);  // pi A L, A = 1
  Light two = tri;
  two.two_sided = true;
  EXPECT_NEAR(light_power(two, 10), 2 * kPi, 1e-5f);
  EXPECT_NEAR(light_power(make_point_light({0, 0, 0}, Rgb(1)), 10), 4 * kPi, 1e-4f);
  EXPECT_NEAR(light_power(make_directional_light({0, 1, 0}, Rgb(1)), 2), kPi * 4, 1e-4f);
}

}  // namespace
