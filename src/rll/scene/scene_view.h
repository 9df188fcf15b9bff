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

// A light sample as every renderer draws it: image lights read their image from the scene's
// textures.
RLL_HD inline LightLiSample sample_li(const SceneView& scene, const Light& light, const Vec3& p,
                                      Vec2 u) {
  return sample_li(light, p, u, light.has_image() ? &scene.textures[light.triangle] : nullptr);
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
