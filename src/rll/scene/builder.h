// Helpers that add primitives (quads, boxes, spheres) to a scene; used by the built-in scenes
// and by tests that generate their own scenes.
#pragma once

#include "rll/scene/scene.h"

namespace rll {

class SceneBuilder {
 public:
  explicit SceneBuilder(Scene& scene) : m_scene(scene) {}
  Scene& scene() { return m_scene; }
  uint32_t material(const Material& m);
  uint32_t diffuse(const Rgb& albedo, const std::string& name = "");
  uint32_t emitter(const Rgb& radiance, bool two_sided = false, const std::string& name = "");
  // Quad p, p+e1, p+e1+e2, p+e2 as two triangles; front face (and emission) along e1 x e2.
  void quad(const Vec3& p, const Vec3& e1, const Vec3& e2, uint32_t material);
  void triangle(const Vec3& a, const Vec3& b, const Vec3& c, uint32_t material);
  // Axis-aligned box; faces point outwards, or inwards when `inward` (a room). Faces can be
  // skipped with a mask: bit 0 -x, 1 +x, 2 -y, 3 +y, 4 -z, 5 +z.
  void box(const Vec3& lo, const Vec3& hi, uint32_t material, bool inward = false, unsigned skip = 0);
  // A wall in the plane axis=`axis` at `offset`, spanning [lo,hi] in the other two axes, with
  // rectangular holes (each given as lo/hi in the same two axes); normal along +axis or -axis.
  struct Hole {
    float u0, v0, u1, v1;
  };
  void wall_with_holes(int axis, float offset, float u0, float v0, float u1, float v1,
                       const std::vector<Hole>& holes, bool normal_positive, uint32_t material);
  // Icosphere (subdivided icosahedron) with outward or inward faces, with smooth shading
  // normals or flat facets.
  void sphere(const Vec3& center, float radius, int subdivisions, uint32_t material, bool inward = false,
              bool smooth = true);

 private:
  uint32_t vertex(const Vec3& p, const Vec3& n = Vec3(0));
  Scene& m_scene;
};

}  // namespace rll
