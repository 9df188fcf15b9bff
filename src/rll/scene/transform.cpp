#include "rll/scene/transform.h"

#include <algorithm>
#include <utility>

namespace rll {

float Affine::det() const {
  return a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
         a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
         a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
}

Vec3 Affine::apply_normal(const Vec3& n) const {
  Vec3 c0(a[1][1] * a[2][2] - a[1][2] * a[2][1], a[1][2] * a[2][0] - a[1][0] * a[2][2],
          a[1][0] * a[2][1] - a[1][1] * a[2][0]);
  Vec3 c1(a[0][2] * a[2][1] - a[0][1] * a[2][2], a[0][0] * a[2][2] - a[0][2] * a[2][0],
          a[0][1] * a[2][0] - a[0][0] * a[2][1]);
  Vec3 c2(a[0][1] * a[1][2] - a[0][2] * a[1][1], a[0][2] * a[1][0] - a[0][0] * a[1][2],
          a[0][0] * a[1][1] - a[0][1] * a[1][0]);
  // c0, c1, c2 are the cofactor matrix's rows: r = cof(A) n (cof(A)^T n, as this once was,
  // turned a rotated mesh's normals the other way round).
  Vec3 r(dot(c0, n), dot(c1, n), dot(c2, n));
  return det() < 0 ? -r : r;
}

void Affine::prepend(const float m[3][3]) {
  float r[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r[i][j] = m[i][0] * a[0][j] + m[i][1] * a[1][j] + m[i][2] * a[2][j];
  std::copy(&r[0][0], &r[0][0] + 9, &a[0][0]);
}

Affine inverse(const Affine& x) {
  // The inverse is the transposed cofactor matrix over the determinant.
  const float(&a)[3][3] = x.a;
  const float id = 1 / x.det();
  Affine r;
  r.a[0][0] = (a[1][1] * a[2][2] - a[1][2] * a[2][1]) * id;
  r.a[0][1] = (a[0][2] * a[2][1] - a[0][1] * a[2][2]) * id;
  r.a[0][2] = (a[0][1] * a[1][2] - a[0][2] * a[1][1]) * id;
  r.a[1][0] = (a[1][2] * a[2][0] - a[1][0] * a[2][2]) * id;
  r.a[1][1] = (a[0][0] * a[2][2] - a[0][2] * a[2][0]) * id;
  r.a[1][2] = (a[0][2] * a[1][0] - a[0][0] * a[1][2]) * id;
  r.a[2][0] = (a[1][0] * a[2][1] - a[1][1] * a[2][0]) * id;
  r.a[2][1] = (a[0][1] * a[2][0] - a[0][0] * a[2][1]) * id;
  r.a[2][2] = (a[0][0] * a[1][1] - a[0][1] * a[1][0]) * id;
  r.t = -r.apply_vector(x.t);
  return r;
}

void transform_mesh(Mesh& mesh, const Affine& x, size_t first_triangle, size_t first_vertex) {
  for (size_t i = first_vertex; i < mesh.positions.size(); ++i)
    mesh.positions[i] = x.apply(mesh.positions[i]);
  for (size_t i = first_vertex; i < mesh.normals.size(); ++i)
    mesh.normals[i] = x.apply_normal(mesh.normals[i]);
  if (x.det() < 0)
    for (size_t t = first_triangle; t < mesh.triangles.size(); ++t)
      std::swap(mesh.triangles[t][1], mesh.triangles[t][2]);
}

}  // namespace rll
