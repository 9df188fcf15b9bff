#include "rll/scene/scene_view.h"

#include "rll/scene/scene.h"

namespace rll {

SceneData::SceneData(const Scene& scene)
    : m_materials(scene.materials.begin(), scene.materials.end()) {
  m_textures.reserve(scene.textures.size());
  for (const Image& t : scene.textures) m_textures.push_back(t.texel_view());
  m_view.mesh = scene.mesh.view();
  m_view.materials = view_of(m_materials);
  m_view.textures = view_of(m_textures);
  m_view.lights = view_of(scene.lights);
}

}  // namespace rll
