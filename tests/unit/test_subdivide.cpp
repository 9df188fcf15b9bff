// Loop subdivision: one level of a closed and of an open mesh against positions derived by hand
// from the masks in subdivide.h, the limit step, counts, and refused non-manifold input.
#include <gtest/gtest.h>

#include <cmath>

#include "rll/core/error.h"
#include "rll/scene/subdivide.h"
#include "support/test_support.h"

using namespace rll;
using rll::test::error_of;
using rll::test::expect_mentions;

namespace {

bool near(const Vec3& a, const Vec3& b, float eps = 1e-6f) {
  return length(a - b) <= eps;
}

// The regular tetrahedron a, b, c, d, wound outwards. a + b + c + d = 0, so for every vertex the
// sum of its three neighbours is minus itself.
SubdivisionMesh tetrahedron() {
  SubdivisionMesh m;
  m.positions = {{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}};
  m.triangles = {{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}};
  return m;
}

// The new vertex on the edge between original vertices i and j: the one both (new) vertices i and
// j are connected to; found through the triangles (corner i's triangle is (i, ij, ki)).
uint32_t edge_vertex(const SubdivisionMesh& m, uint32_t i, uint32_t j) {
  for (const auto& t : m.triangles)
    for (int k = 0; k < 3; ++k)
      if (t[size_t(k)] == i) {
        const uint32_t x = t[size_t((k + 1) % 3)], y = t[size_t((k + 2) % 3)];
        for (uint32_t e : {x, y})
          for (const auto& u : m.triangles)
            for (int l = 0; l < 3; ++l)
              if (u[size_t(l)] == j && (u[size_t((l + 1) % 3)] == e || u[size_t((l + 2) % 3)] == e))
                return e;
      }
  ADD_FAILURE() << "no edge vertex between " << i << " and " << j;
  return 0;
}

}  // namespace

TEST(LoopSubdivision, TetrahedronOneLevelByHand) {
  SubdivisionMesh m = tetrahedron();
  loop_subdivide(m, 1, /*push_to_limit=*/false);
  ASSERT_EQ(m.triangles.size(), 16u);
  ASSERT_EQ(m.positions.size(), 10u);  // 4 even + 6 edges
  // Even vertex, valence 3: beta = 3/16, so v' = (1 - 9/16) v + 3/16 (-v) = 4/16 v = v / 4.
  EXPECT_TRUE(near(m.positions[0], Vec3(0.25f, 0.25f, 0.25f)));
  EXPECT_TRUE(near(m.positions[3], Vec3(-0.25f, -0.25f, 0.25f)));
  // Odd vertex on ab: 3/8 (a + b) + 1/8 (c + d) = 3/8 (a + b) - 1/8 (a + b) = (a + b) / 4.
  // a + b = (2, 0, 0): (0.5, 0, 0).
  EXPECT_TRUE(near(m.positions[edge_vertex(m, 0, 1)], Vec3(0.5f, 0, 0)));
  // c + d = (-2, 0, 0): (-0.5, 0, 0).
  EXPECT_TRUE(near(m.positions[edge_vertex(m, 2, 3)], Vec3(-0.5f, 0, 0)));
}

TEST(LoopSubdivision, TetrahedronLimitPositionsAndNormalsByHand) {
  SubdivisionMesh m = tetrahedron();
  loop_subdivide(m, 1);
  ASSERT_EQ(m.positions.size(), 10u);
  ASSERT_EQ(m.normals.size(), 10u);
  // After one level, even vertex a' = a/4 (valence 3): gamma = 1 / (3 + 3 / (8 * 3/16)) = 1/5.
  // Its ring is the three edge vertices (a + b)/4, (a + c)/4, (a + d)/4, summing to
  // (3a + b + c + d)/4 = a/2. Limit: (1 - 3/5) a/4 + 1/5 a/2 = a/10 + a/10 = a/5.
  EXPECT_TRUE(near(m.positions[0], Vec3(0.2f, 0.2f, 0.2f)));
  // Edge vertex m_ab = (a + b)/4 has valence 6: beta = 3/48 = 1/16, gamma = 1 / (6 + 6) = 1/12.
  // Its ring: a/4, b/4, and (a + c)/4, (b + c)/4, (a + d)/4, (b + d)/4, summing to
  // (a + b)/4 + (2a + 2b + 2c + 2d)/4 = (a + b)/4. Limit: 1/2 (a + b)/4 + 1/12 (a + b)/4
  // = 7/48 (a + b) = 7/48 (2, 0, 0) = (7/24, 0, 0).
  EXPECT_TRUE(near(m.positions[edge_vertex(m, 0, 1)], Vec3(7.0f / 24, 0, 0)));
  // By symmetry the limit normal at a's vertex is along a, pointing out.
  EXPECT_TRUE(near(m.normals[0], normalize(Vec3(1, 1, 1)), 1e-5f));
  EXPECT_TRUE(near(m.normals[edge_vertex(m, 0, 1)], Vec3(1, 0, 0), 1e-5f));
}

TEST(LoopSubdivision, OpenMeshUsesTheBoundaryRules) {
  // One triangle: every vertex and edge is on the boundary.
  SubdivisionMesh tri;
  tri.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  tri.triangles = {{0, 1, 2}};
  SubdivisionMesh one = tri;
  loop_subdivide(one, 1, false);
  ASSERT_EQ(one.triangles.size(), 4u);
  // Boundary even: 3/4 v + 1/8 (the two boundary neighbours).
  // a: 3/4 (0,0,0) + 1/8 ((1,0,0) + (0,1,0)) = (1/8, 1/8, 0)
  EXPECT_TRUE(near(one.positions[0], Vec3(0.125f, 0.125f, 0)));
  // b: 3/4 (1,0,0) + 1/8 ((0,0,0) + (0,1,0)) = (3/4, 1/8, 0)
  EXPECT_TRUE(near(one.positions[1], Vec3(0.75f, 0.125f, 0)));
  // Boundary odd: the midpoint.
  EXPECT_TRUE(near(one.positions[edge_vertex(one, 0, 1)], Vec3(0.5f, 0, 0)));
  EXPECT_TRUE(near(one.positions[edge_vertex(one, 1, 2)], Vec3(0.5f, 0.5f, 0)));
  // The limit of a boundary vertex: 3/5 v + 1/5 (its boundary neighbours).
  // a' = (1/8, 1/8, 0) between m_ab = (1/2, 0, 0) and m_ca = (0, 1/2, 0):
  // 3/5 (1/8, 1/8) + 1/5 (1/2, 1/2) = (3/40 + 4/40) = (0.175, 0.175, 0).
  // m_ab = (1/2, 0, 0) between a' = (1/8, 1/8, 0) and b' = (3/4, 1/8, 0):
  // 3/5 (1/2, 0) + 1/5 (7/8, 1/4) = (0.3 + 0.175, 0.05) = (0.475, 0.05, 0).
  SubdivisionMesh lim = tri;
  loop_subdivide(lim, 1);
  EXPECT_TRUE(near(lim.positions[0], Vec3(0.175f, 0.175f, 0)));
  EXPECT_TRUE(near(lim.positions[edge_vertex(lim, 0, 1)], Vec3(0.475f, 0.05f, 0)));
  for (const Vec3& n : lim.normals) EXPECT_TRUE(near(n, Vec3(0, 0, 1), 1e-5f));

  // A square of two triangles with two opposite corners raised: the diagonal is an interior
  // edge (3/8, 3/8, 1/8, 1/8), the corners are boundary vertices (which ignore the diagonal).
  SubdivisionMesh sq;
  sq.positions = {{0, 0, 0}, {1, 0, 1}, {1, 1, 0}, {0, 1, 1}};
  sq.triangles = {{0, 1, 2}, {0, 2, 3}};
  loop_subdivide(sq, 1, false);
  ASSERT_EQ(sq.triangles.size(), 8u);
  ASSERT_EQ(sq.positions.size(), 9u);  // 4 + 5 edges
  // Diagonal 0-2: 3/8 ((0,0,0) + (1,1,0)) + 1/8 ((1,0,1) + (0,1,1)) = (1/2, 1/2, 1/4);
  // its midpoint would have z = 0.
  EXPECT_TRUE(near(sq.positions[edge_vertex(sq, 0, 2)], Vec3(0.5f, 0.5f, 0.25f)));
  // Corner 0: 3/4 (0,0,0) + 1/8 ((1,0,1) + (0,1,1)) = (1/8, 1/8, 1/4).
  EXPECT_TRUE(near(sq.positions[0], Vec3(0.125f, 0.125f, 0.25f)));
  // Boundary edge 0-1: the midpoint (1/2, 0, 1/2).
  EXPECT_TRUE(near(sq.positions[edge_vertex(sq, 0, 1)], Vec3(0.5f, 0, 0.5f)));
}

TEST(LoopSubdivision, CountsGrowByFourPerLevel) {
  for (int levels = 0; levels <= 3; ++levels) {
    SubdivisionMesh m = tetrahedron();
    loop_subdivide(m, levels);
    EXPECT_EQ(m.triangles.size(), size_t(4) << (2 * levels));
    // A closed genus-0 mesh: V = F/2 + 2.
    EXPECT_EQ(m.positions.size(), m.triangles.size() / 2 + 2);
    EXPECT_EQ(m.normals.size(), m.positions.size());
  }
  // Level 3 of a tetrahedron approaches a sphere-like blob: every vertex keeps its winding's
  // side, the normals pointing away from the centre.
  SubdivisionMesh m = tetrahedron();
  loop_subdivide(m, 3);
  for (size_t i = 0; i < m.positions.size(); ++i) EXPECT_GT(dot(m.normals[i], m.positions[i]), 0);
}

TEST(LoopSubdivision, NonManifoldInputIsRefused) {
  // Three triangles on one edge.
  SubdivisionMesh fin;
  fin.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  fin.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  expect_mentions(error_of([&] { loop_subdivide(fin, 1); }), {"edge (0, 1)", "not a manifold"});
  // Two fans meeting at one vertex (a bow tie).
  SubdivisionMesh bow;
  bow.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0}, {-1, -1, 0}};
  bow.triangles = {{0, 1, 2}, {0, 3, 4}};
  expect_mentions(error_of([&] { loop_subdivide(bow, 1); }), {"vertex 0", "not a manifold"});
  // Inconsistent winding.
  SubdivisionMesh flip;
  flip.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}};
  flip.triangles = {{0, 1, 2}, {0, 1, 3}};
  expect_mentions(error_of([&] { loop_subdivide(flip, 1); }), {"edge (0, 1)", "oriented"});
  SubdivisionMesh bad;
  bad.positions = {{0, 0, 0}, {1, 0, 0}};
  bad.triangles = {{0, 1, 5}};
  expect_mentions(error_of([&] { loop_subdivide(bad, 1); }), {"vertex 5"});
}
