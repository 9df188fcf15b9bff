// All scene triangles, flattened into one indexed mesh (one Embree geometry).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "rll/core/device.h"
#include "rll/core/math.h"

namespace rll {

using Triangle = std::array<uint32_t, 3>;

// The mesh as kernels read it: its arrays, owning nothing (Mesh::view()).
struct MeshView {
  View<const Vec3> positions;
  View<const Vec3> normals;  // empty, or one per position (zero: none)
  View<const Vec2> uvs;      // empty, or one per position
  View<const Triangle> triangles;
  View<const uint32_t> material;  // per triangle
  View<const int32_t> light;      // per triangle: index into the lights, -1 if not emissive

  RLL_HD Vec3 vertex(uint32_t tri, int k) const { return positions[triangles[tri][k]]; }
  // Unnormalised geometric normal (p1-p0)x(p2-p0): length is twice the area.
  RLL_HD Vec3 face_cross(uint32_t tri) const {
    const Triangle& t = triangles[tri];
    return cross(positions[t[1]] - positions[t[0]], positions[t[2]] - positions[t[0]]);
  }
};

struct Mesh {
  std::vector<Vec3> positions;
  // Per-vertex shading normals; a zero vector means "none: use the geometric normal".
  // Either empty or the size of `positions`.
  std::vector<Vec3> normals;
  // Per-vertex texture coordinates; either empty or the size of `positions`.
  std::vector<Vec2> uvs;
  std::vector<Triangle> triangles;
  std::vector<uint32_t> material;  // per triangle
  std::vector<int32_t> light;      // per triangle: index into Scene::lights, -1 if not emissive

  size_t triangle_count() const { return triangles.size(); }
  MeshView view() const {
    return {view_of(positions), view_of(normals),  view_of(uvs),
            view_of(triangles), view_of(material), view_of(light)};
  }
  Vec3 vertex(uint32_t tri, int k) const { return positions[triangles[tri][k]]; }
  // Unnormalised geometric normal (p1-p0)x(p2-p0): length is twice the area.
  Vec3 face_cross(uint32_t tri) const { return view().face_cross(tri); }
  float area(uint32_t tri) const { return 0.5f * length(face_cross(tri)); }

  // Appends another mesh whose material ids are offset by `material_offset`.
  void append(const Mesh& other, uint32_t material_offset);
};

}  // namespace rll
