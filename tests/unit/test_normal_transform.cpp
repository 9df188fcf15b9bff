// Shading normals under a shape's transform (issue 42, found proving the killeroo gap): normals
// move with the inverse transpose of the transform, so that they stay perpendicular to the
// transformed surface. Affine::apply_normal once applied the transposed cofactor matrix, which
// turned a rotated mesh's normals the other way round (killeroo-simple's loopsubdiv under
// `Rotate -60` rendered dark, patchy killeroos); every reader that places meshes with
// transform_mesh (pbrt, glTF) shares it.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "rll/io/load.h"
#include "rll/scene/transform.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;

namespace {

bool near(const Vec3& a, const Vec3& b, float eps = 1e-5f) {
  return length(a - b) <= eps;
}

// A general transform: a rotation, a non-uniform scale and a shear, mirrored when `mirror`.
Affine general(bool mirror) {
  Affine x;
  const float m[3][3] = {{0.8f, -1.1f, 0.3f}, {0.9f, 0.7f, -0.2f}, {0.1f, 0.4f, 1.6f}};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) x.a[i][j] = m[i][j] * (mirror && j == 0 ? -1.0f : 1.0f);
  x.t = Vec3(3, -2, 5);
  return x;
}

}  // namespace

TEST(NormalTransform, RotatesWithTheSurface) {
  // Rotate 60 degrees about z: the normal +x turns to (cos 60, sin 60, 0), as a vector does.
  Affine r;
  const float c = std::cos(kPi / 3), s = std::sin(kPi / 3);
  const float m[3][3] = {{c, -s, 0}, {s, c, 0}, {0, 0, 1}};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r.a[i][j] = m[i][j];
  EXPECT_TRUE(near(normalize(r.apply_normal(Vec3(1, 0, 0))), Vec3(c, s, 0)));
  EXPECT_TRUE(near(normalize(r.apply_normal(Vec3(0, 1, 0))), r.apply_vector(Vec3(0, 1, 0))));
}

TEST(NormalTransform, StaysPerpendicularAndOnTheFrontUnderAnyTransform) {
  for (const bool mirror : {false, true}) {
    Mesh mesh;
    mesh.positions = {Vec3(0, 0, 0), Vec3(1, 0.2f, 0.1f), Vec3(0.3f, 1, -0.4f)};
    mesh.triangles = {{0, 1, 2}};
    const Vec3 n = normalize(mesh.face_cross(0));
    mesh.normals = {n, n, n};
    transform_mesh(mesh, general(mirror), 0, 0);
    const Vec3 e1 = mesh.positions[1] - mesh.positions[0],
               e2 = mesh.positions[2] - mesh.positions[0];
    const Vec3 face = normalize(mesh.face_cross(0));  // with the winding as transform_mesh left it
    for (const Vec3& v : mesh.normals) {
      const Vec3 nn = normalize(v);
      EXPECT_NEAR(dot(nn, normalize(e1)), 0, 1e-5f) << "mirror " << mirror;
      EXPECT_NEAR(dot(nn, normalize(e2)), 0, 1e-5f) << "mirror " << mirror;
      EXPECT_TRUE(near(nn, face)) << "mirror " << mirror;
    }
  }
}

// The pbrt reader: a mesh's "normal N" and a loopsubdiv's limit normals turn with the shape.
TEST(NormalTransform, PbrtShapesUnderRotateKeepTheirNormalsOnTheSurface) {
  TempDir dir;
  const std::string camera = "Scale -1 1 1\nLookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"\n";
  Scene s;
  load_pbrt(dir.write("n.pbrt",
                      camera + "WorldBegin\nRotate 60 0 0 1\n"
                               "Shape \"trianglemesh\" \"point3 P\" [0 0 0  0 1 0  0 0 1] "
                               "\"normal N\" [1 0 0  1 0 0  1 0 0] \"integer indices\" [0 1 2]\n"),
            s);
  ASSERT_EQ(s.mesh.normals.size(), 3u);
  const Vec3 expected(std::cos(kPi / 3), std::sin(kPi / 3), 0);
  for (const Vec3& n : s.mesh.normals) EXPECT_TRUE(near(normalize(n), expected, 1e-5f));

  // A variant: the regular tetrahedron's limit normal at (1, 1, 1) is along (1, 1, 1); under
  // Rotate 90 about x it is along (1, -1, 1), the direction of its moved vertex.
  Scene t;
  load_pbrt(dir.write("t.pbrt", camera + "WorldBegin\nRotate 90 1 0 0\n"
                                         "Shape \"loopsubdiv\" \"integer levels\" 1 "
                                         "\"point3 P\" [ 1 1 1  1 -1 -1  -1 1 -1  -1 -1 1 ] "
                                         "\"integer indices\" [ 0 1 2  0 3 1  0 2 3  1 3 2 ]\n"),
            t);
  ASSERT_EQ(t.mesh.normals.size(), t.mesh.positions.size());
  EXPECT_TRUE(near(t.mesh.positions[0], Vec3(0.2f, -0.2f, 0.2f), 1e-5f));
  EXPECT_TRUE(near(normalize(t.mesh.normals[0]), normalize(Vec3(1, -1, 1)), 1e-5f));
}
