// scene/interaction.h's pieces of a path vertex that the renderers (render/path_vertex.h) and the
// oracle's discovery and estimates share: the footprint's widening and a next-event sample's
// shadow ray.
#include <gtest/gtest.h>

#include <cmath>

#include "rll/scene/interaction.h"
#include "rll/scene/light.h"

using namespace rll;

TEST(VertexPieces, FootprintWidensByTheSegmentOverItsDensity) {
  const Vec3 up(0, 0, 1);
  // R + t / sqrt(p |cos|): 1 + 2 / sqrt(4 * 1) = 2, head on.
  EXPECT_EQ(widen_footprint(1.0f, 2.0f, 4.0f, Vec3(0, 0, -1), up), 2.0f);
  // At 60 degrees |cos| = 1/2, either side of the surface.
  EXPECT_FLOAT_EQ(widen_footprint(0.0f, 1.0f, 2.0f, Vec3(0, std::sqrt(0.75f), 0.5f), up), 1.0f);
  EXPECT_FLOAT_EQ(widen_footprint(0.0f, 1.0f, 2.0f, Vec3(0, std::sqrt(0.75f), -0.5f), up), 1.0f);
  // Grazing: |cos| is taken as at least 1e-2, so 2 / sqrt(4 * 1e-2) = 10.
  EXPECT_FLOAT_EQ(widen_footprint(1.0f, 2.0f, 4.0f, Vec3(1, 0, 0), up), 11.0f);
}

TEST(VertexPieces, ShadowRayEndsBeforeTheLightOrPastTheScene) {
  const Vec3 p(0, 0, 0), ng(0, 0, 1);
  // A triangle light above: the ray is aimed at its point from off the surface, and stops short
  // of the light, which it must not hit.
  const Light tri =
      make_triangle_light(Vec3(-1, -1, 2), Vec3(1, -1, 2), Vec3(0, 1, 2), Rgb(1), false, 0);
  LightLiSample ls;
  ls.point = Vec3(0, 0, 2);
  ls.wi = Vec3(0, 0, 1);
  ls.dist = 2;
  Ray r = shadow_ray_to_light(p, ng, tri, ls, Vec3(0), 100.0f);
  EXPECT_GT(r.o.z, 0.0f);  // pushed off the surface, toward the light
  EXPECT_NEAR(r.d.z, 1.0f, 1e-6f);
  EXPECT_LT(r.o.z + r.tmax, 2.0f);
  EXPECT_GT(r.o.z + r.tmax, 1.99f);
  // A directional light: along wi, to past the scene's bounding sphere (centre 3 away, radius 5).
  const Light sun = make_directional_light(Vec3(0, 0, 1), Rgb(1));
  ls.dist = kInf;
  ls.point = Vec3(0);
  r = shadow_ray_to_light(p, ng, sun, ls, Vec3(3, 0, 0), 5.0f);
  EXPECT_EQ(r.d, Vec3(0, 0, 1));
  EXPECT_FLOAT_EQ(r.tmax, 3.0f + 1.01f * 5.0f);
  EXPECT_GT(r.o.z, 0.0f);
}
