// Affine transforms of scene geometry (p -> A p + t), shared by the scene file readers.
#pragma once

#include <cmath>
#include <cstddef>
#include <limits>

#include "rll/core/math.h"
#include "rll/scene/mesh.h"

namespace rll {

// A double as a float, out-of-range values becoming infinite (a plain conversion of those is
// undefined behaviour): the readers then reject them as non-finite.
inline float to_float(double d) {
  constexpr double kMax = std::numeric_limits<float>::max();
  if (std::abs(d) <= kMax || std::isnan(d)) return float(d);
  return d > 0 ? std::numeric_limits<float>::infinity() : -std::numeric_limits<float>::infinity();
}

struct Affine {
  float a[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  Vec3 t;

  Vec3 apply(const Vec3& p) const { return apply_vector(p) + t; }
  Vec3 apply_vector(const Vec3& v) const {
    return Vec3(a[0][0] * v.x + a[0][1] * v.y + a[0][2] * v.z,
                a[1][0] * v.x + a[1][1] * v.y + a[1][2] * v.z,
                a[2][0] * v.x + a[2][1] * v.y + a[2][2] * v.z);
  }
  float det() const;
  // Normals transform with the inverse transpose; the cofactor matrix is that times det(A), and
  // the scale does not matter since shading normalizes.
  Vec3 apply_normal(const Vec3& n) const;
  // this = m * this
  void prepend(const float m[3][3]);
};

// The inverse transform (the caller checks that det() is not 0).
Affine inverse(const Affine& x);

// Transforms the triangles from `first_triangle` and the vertices from `first_vertex` on (a shape
// just added). A mirroring transform turns the winding around; it is flipped back so that front
// faces (and one-sided emitters) keep facing the way the transformed normals do.
void transform_mesh(Mesh& mesh, const Affine& x, size_t first_triangle, size_t first_vertex);

}  // namespace rll
