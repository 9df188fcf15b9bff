// A renderable scene: one flattened triangle mesh, materials, textures, lights, camera, film.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "rll/core/image.h"
#include "rll/scene/camera.h"
#include "rll/scene/light.h"
#include "rll/scene/material.h"
#include "rll/scene/mesh.h"

namespace rll {

class LightTree;

// A sky as a dome of emissive triangles over the upper hemisphere around `up`.
struct SkyDome {
  int triangles = 2048;
  Rgb radiance{1.0f};
  Vec3 up{0, 1, 0};
  // Dome radius in units of the scene's bounding radius; > 2 so that shadow rays towards a
  // directional light, which stop at the bounding sphere, never reach it.
  float radius_scale = 50;
};

struct Scene {
  std::string source;  // the file or builtin:NAME it came from, for messages
  Mesh mesh;
  std::vector<Material> materials;
  std::vector<Image> textures;
  // Point and directional lights as given; emissive triangles are appended by finalize().
  std::vector<Light> lights;
  Camera camera;
  int width = 640, height = 480;
  bool has_camera = false;  // false: finalize() fits one to the bounds
  std::optional<SkyDome> sky;

  // Filled by finalize():
  Bounds3 bounds;      // all geometry except the sky dome
  float radius = 1;    // radius of the bounding sphere of `bounds`
  size_t sky_first_triangle = 0, sky_triangle_count = 0;
  // The reference light tree over `lights`, which finalize() reorders into tree order.
  std::shared_ptr<LightTree> light_tree;

  // Animated scenes move lights between frames: called with the frame index, it updates the
  // mesh and the lights in place (triangle lights keep their ids).
  std::function<void(Scene&, int)> animate;
  int frame_count = 1;

  // Validates the scene (finite vertices, valid indices, at least one light, film size), adds
  // the sky dome, creates one light per emissive triangle, fits a camera if none was given and
  // builds the light tree (reordering the lights). Throws rll::Error naming `source`.
  void finalize();

  // Light id of a mesh triangle, or -1.
  int32_t light_of_triangle(uint32_t tri) const { return mesh.light[tri]; }
  // Reorders lights: new_lights[i] = lights[order[i]]; triangle->light ids follow.
  void reorder_lights(const std::vector<uint32_t>& order);
  // Re-reads triangle light geometry and emission from the mesh and materials (after
  // animate()) and refits the light tree.
  void refresh_lights_from_mesh();
};

// Adds the triangles of a sky dome (around `center` with `radius`) to `scene` with an emissive
// material. Exposed for tests; finalize() calls it when scene.sky is set.
void add_sky_dome(Scene& scene, const SkyDome& sky, const Vec3& center, float radius);

}  // namespace rll
