// The sky dome: exactly the requested number of triangles, all facing the centre, tiling the
// upper hemisphere once (total solid angle 2 pi, every upward direction hits one triangle).
#include <gtest/gtest.h>

#include <numeric>

#include "rll/core/error.h"
#include "rll/core/rng.h"
#include "rll/core/sampling.h"
#include "rll/scene/builder.h"
#include "support/light_cases.h"

using namespace rll;
using namespace rll::test;

namespace {

struct Dome {
  Scene scene;
  Vec3 center{1, 2, 3};
  float radius = 100;
  Vec3 up;
};

Dome make_dome(int triangles, Vec3 up = {0, 1, 0}) {
  Dome d;
  d.up = normalize(up);
  d.scene.source = "test";
  SkyDome sky;
  sky.triangles = triangles;
  sky.up = up;
  add_sky_dome(d.scene, sky, d.center, d.radius);
  return d;
}

std::vector<int> triangle_counts() {
  std::vector<int> counts;
  for (int n = 4; n <= 300; ++n) counts.push_back(n);
  for (int n = 301; n <= 5000; n += 37) counts.push_back(n);
  for (int n : {1000, 2047, 2048, 2049, 4096, 4999, 5000}) counts.push_back(n);
  return counts;
}

TEST(SkyDome, ExactTriangleCountFacingInwardsCoveringTheHemisphere) {
  for (int n : triangle_counts()) {
    SCOPED_TRACE(testing::Message() << n << " triangles");
    Dome d = make_dome(n);
    const Mesh& m = d.scene.mesh;
    ASSERT_EQ(m.triangle_count(), size_t(n));
    ASSERT_EQ(d.scene.sky_triangle_count, size_t(n));
    ASSERT_EQ(d.scene.sky_first_triangle, 0u);
    double total = 0, smallest = kInf, largest = 0;
    for (uint32_t t = 0; t < m.triangle_count(); ++t) {
      const Vec3 a = m.vertex(t, 0), b = m.vertex(t, 1), c = m.vertex(t, 2);
      const Vec3 mid = (a + b + c) / 3.0f;
      ASSERT_GT(m.area(t), 0) << "triangle " << t << " is degenerate";
      ASSERT_GT(dot(m.face_cross(t), d.center - mid), 0) << "triangle " << t << " faces outwards";
      for (const Vec3& v : {a, b, c}) {
        ASSERT_NEAR(length(v - d.center), d.radius, 1e-4f * d.radius);
        ASSERT_GE(dot(v - d.center, d.up), -1e-4f * d.radius) << "a vertex below the horizon";
      }
      double omega = reference_solid_angle(d.center, a, b, c);
      total += omega;
      smallest = std::min(smallest, omega);
      largest = std::max(largest, omega);
    }
    ASSERT_NEAR(total, 2 * M_PI, 1e-4) << "the dome does not tile the hemisphere once";
    // Similar solid angles keep the sky's lights comparable in power (the ratio is 4.8 at 2048
    // triangles and at most 6.4 up to 5000).
    if (n >= 64) {
      ASSERT_LT(largest / smallest, 8.0) << "triangle sizes are far apart";
    }
  }
}

// Coverage without overlap: every upward ray from the centre meets exactly one triangle, a
// downward one none.
TEST(SkyDome, EveryUpwardDirectionHitsOneTriangle) {
  for (int n : {4, 5, 17, 2048}) {
    SCOPED_TRACE(testing::Message() << n << " triangles");
    Dome d = make_dome(n, Vec3(0.3f, 1, -0.2f));
    const Mesh& m = d.scene.mesh;
    Pcg32 rng{uint64_t(n)};
    Frame f(d.up);
    for (int k = 0; k < 400; ++k) {
      Vec3 w = f.to_world(sample_uniform_sphere({rng.next_float(), rng.next_float()}));
      if (std::abs(dot(w, d.up)) < 1e-3f) continue;  // too close to the horizon edge
      int hits = 0;
      for (uint32_t t = 0; t < m.triangle_count(); ++t) {
        // Does the ray from the centre along w pass through triangle t (all three edge planes)?
        const Vec3 a = m.vertex(t, 0) - d.center, b = m.vertex(t, 1) - d.center,
                   c = m.vertex(t, 2) - d.center;
        float s0 = dot(w, cross(a, b)), s1 = dot(w, cross(b, c)), s2 = dot(w, cross(c, a));
        if ((s0 >= 0 && s1 >= 0 && s2 >= 0) || (s0 <= 0 && s1 <= 0 && s2 <= 0))
          if (dot(w, a + b + c) > 0) ++hits;
      }
      ASSERT_EQ(hits, dot(w, d.up) > 0 ? 1 : 0) << "direction " << k;
    }
  }
}

TEST(SkyDome, BadParametersAreErrors) {
  Scene s;
  s.source = "sky.json";
  SkyDome sky;
  sky.triangles = 3;
  EXPECT_THROW(add_sky_dome(s, sky, Vec3(0), 10), Error);
  sky.triangles = 100;
  sky.radius_scale = 2;
  EXPECT_THROW(add_sky_dome(s, sky, Vec3(0), 10), Error);
}

TEST(SkyDome, FinalizeMakesOneLightPerSkyTriangle) {
  Scene s;
  s.source = "test";
  SceneBuilder b(s);
  b.quad(Vec3(-1, 0, -1), Vec3(0, 0, 2), Vec3(2, 0, 0), b.diffuse(Rgb(0.5f)));
  SkyDome sky;
  sky.triangles = 2048;
  sky.radiance = Rgb(0.5f, 1, 2);
  s.sky = sky;
  s.finalize();
  EXPECT_EQ(s.sky_triangle_count, 2048u);
  EXPECT_EQ(s.lights.size(), 2048u);
  for (const Light& l : s.lights) {
    EXPECT_EQ(l.radiance, sky.radiance);
    EXPECT_GE(l.triangle, s.sky_first_triangle);
    // The dome is far outside the scene's bounds: > 2 bounding radii from its centre.
    EXPECT_GT(length(l.centroid() - s.bounds.center()), 2 * s.radius);
  }
  // finalize() is idempotent: a second call adds no second dome and keeps the dome out of the
  // scene's bounds.
  const size_t triangles = s.mesh.triangle_count();
  const Bounds3 bounds = s.bounds;
  const float radius = s.radius;
  s.finalize();
  EXPECT_EQ(s.mesh.triangle_count(), triangles);
  EXPECT_EQ(s.lights.size(), 2048u);
  EXPECT_EQ(s.bounds.lo, bounds.lo);
  EXPECT_EQ(s.bounds.hi, bounds.hi);
  EXPECT_EQ(s.radius, radius);
}

}  // namespace
