// The hot data of a Scene as kernels read it (DESIGN 6): flat views of the mesh, materials,
// textures and lights, owning nothing, trivially copyable, so that the same RLL_HD functions
// read them on the CPU and, pointing into device memory, on the GPU.
#pragma once

#include <vector>

#include "rll/core/device.h"
#include "rll/core/image.h"
#include "rll/scene/light.h"
#include "rll/scene/material.h"
#include "rll/scene/mesh.h"

namespace rll {

struct Scene;

struct SceneView {
  MeshView mesh;
  View<const MaterialData> materials;
  View<const TexelView> textures;  // Material::albedo_texture and roughness_texture index these
  View<const Light> lights;
};

// Bilinear lookup with repeat wrapping, v pointing up the image.
RLL_HD inline Rgb sample_texture(const TexelView& tex, Vec2 uv) {
  if (tex.width == 0) return Rgb(1);
  float x = (uv.x - std::floor(uv.x)) * tex.width - 0.5f;
  float y = (1 - (uv.y - std::floor(uv.y))) * tex.height - 0.5f;
  int x0 = int(std::floor(x)), y0 = int(std::floor(y));
  float fx = x - x0, fy = y - y0;
  auto texel = [&](int i, int j) {
    i %= tex.width;
    j %= tex.height;
    if (i < 0) i += tex.width;
    if (j < 0) j += tex.height;
    return tex.at(i, j);
  };
  return (texel(x0, y0) * (1 - fx) + texel(x0 + 1, y0) * fx) * (1 - fy) +
         (texel(x0, y0 + 1) * (1 - fx) + texel(x0 + 1, y0 + 1) * fx) * fy;
}

// The radiance material m emits at texture coordinates uv: its emission, times its emission
// texture there.
RLL_HD inline Rgb emission_at(const SceneView& scene, const MaterialData& m, Vec2 uv) {
  if (m.emission_texture < 0) return m.emission;
  return m.emission * sample_texture(scene.textures[m.emission_texture], uv);
}

// The texture coordinates of point y on mesh triangle `tri` (its barycentrics, clamped to the
// triangle, applied to the vertices' uvs; without uvs, the barycentrics themselves, as
// make_surface_hit reads them).
RLL_HD inline Vec2 triangle_uv(const MeshView& m, uint32_t tri, const Vec3& y) {
  const Triangle& t = m.triangles[tri];
  const Vec3 p0 = m.positions[t[0]], e1 = m.positions[t[1]] - p0, e2 = m.positions[t[2]] - p0,
             d = y - p0;
  const float d00 = dot(e1, e1), d01 = dot(e1, e2), d11 = dot(e2, e2), d20 = dot(d, e1),
              d21 = dot(d, e2), den = d00 * d11 - d01 * d01;
  float b1 = 0, b2 = 0;
  if (den > 0) {
    b1 = clamp((d11 * d20 - d01 * d21) / den, 0.0f, 1.0f);
    b2 = clamp((d00 * d21 - d01 * d20) / den, 0.0f, 1.0f - b1);
  }
  if (m.uvs.empty()) return Vec2{b1, b2};
  const float b0 = 1 - b1 - b2;
  const Vec2 &a = m.uvs[t[0]], &b = m.uvs[t[1]], &c = m.uvs[t[2]];
  return Vec2{a.x * b0 + b.x * b1 + c.x * b2, a.y * b0 + b.y * b1 + c.y * b2};
}

// A light sample as every renderer draws it: image lights read their image from the scene's
// textures, and a textured triangle light emits its material's emission texture at the point.
RLL_HD inline LightLiSample sample_li(const SceneView& scene, const Light& light, const Vec3& p,
                                      Vec2 u) {
  LightLiSample s =
      sample_li(light, p, u, light.has_image() ? &scene.textures[light.triangle] : nullptr);
  if (light.textured && s.pdf > 0)
    s.L = emission_at(scene, scene.materials[scene.mesh.material[light.triangle]],
                      triangle_uv(scene.mesh, light.triangle, s.point));
  return s;
}

// A SceneView of a Scene, and the two small arrays it needs that the Scene holds in another form:
// the materials without their names, one texel view per texture. Holds pointers into the Scene,
// which must outlive it and keep its arrays where they are while it is used (a render: after
// animate() or reorder_lights(), build another).
class SceneData {
 public:
  explicit SceneData(const Scene& scene);
  SceneData(const SceneData&) = delete;
  SceneData& operator=(const SceneData&) = delete;
  const SceneView& view() const { return m_view; }

 private:
  std::vector<MaterialData> m_materials;
  std::vector<TexelView> m_textures;
  SceneView m_view;
};

}  // namespace rll
