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

// An environment image for the sky: the radiance seen along world direction d is
// SkyDome::radiance * lookup(d).
struct EnvironmentMap {
  enum class Mapping : uint8_t {
    EqualArea,  // pbrt-v4's equal-area octahedral square (Clarberg), +z at the square's centre
    Equirect,   // latitude-longitude: u = phi / 2pi from +x towards +y, v = theta / pi from +z
  };
  Image image;  // row 0 at the top
  Mapping mapping = Mapping::EqualArea;
  // From world directions to the map's frame (a rotation, possibly with a mirror).
  float world_to_map[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  // Bilinear lookup of the image along a world direction (need not be normalized).
  Rgb lookup(const Vec3& world_direction) const;
};

// The inverse of equal_area_sphere_to_square (light.h): pbrt-v4's equal-area octahedral map from
// [0, 1]^2 to unit directions.
Vec3 equal_area_square_to_sphere(Vec2 p);

// A sky as a dome of emissive triangles over the upper hemisphere around `up`, or the whole
// sphere.
struct SkyDome {
  int triangles = 2048;  // over the whole dome (for a full sphere: even, half on each side)
  Rgb radiance{1.0f};
  // A sphere of triangles, as an infinite light is, rather than a hemisphere.
  bool full_sphere = false;
  // With a map, each triangle emits the map's mean over the solid angle it covers (times
  // `radiance`), and so is a light of its own colour; without, every triangle emits `radiance`.
  std::shared_ptr<const EnvironmentMap> map;
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
  // What the loaders skipped or approximated (an unsupported pbrt directive, a glTF spot light):
  // load_scene prints each as "rll: warning: ..." and keeps them here.
  std::vector<std::string> warnings;

  // Filled by finalize():
  Bounds3 bounds;      // all geometry except the sky dome
  float radius = 1;    // radius of the bounding sphere of `bounds`
  size_t sky_first_triangle = 0, sky_triangle_count = 0;
  // True if mesh triangle t belongs to the sky dome.
  bool is_sky_triangle(size_t t) const {
    return t >= sky_first_triangle && t < sky_first_triangle + sky_triangle_count;
  }
  // True once finalize() has split the large textured emitters into pieces (textured_emitters.h),
  // so that a second finalize does not split them again.
  bool textured_emitters_split = false;

  // Animated scenes move lights between frames: called with the frame index, it updates the
  // mesh and the lights in place (triangle lights keep their ids).
  std::function<void(Scene&, int)> animate;
  int frame_count = 1;

  // Validates the scene (finite vertices, valid indices, at least one light, film size), adds
  // the sky dome, creates one light per emissive triangle and fits a camera if none was given.
  // The light tree is not the scene's: whoever renders builds and holds it (build_light_tree,
  // rll/lighttree/; the render session does). Throws rll::Error naming `source`.
  void finalize();

  // A hash of everything in the finalized scene that the expected image depends on (mesh
  // positions, normals, uvs, triangles, per-triangle materials and lights, materials but not
  // their names, textures, lights, camera, sky, film size), whatever file or path it was read
  // from: the key of cached references, and what render shares and learnt states are tied to.
  uint64_t fingerprint() const;

  // Light id of a mesh triangle, or -1.
  int32_t light_of_triangle(uint32_t tri) const { return mesh.light[tri]; }
  // Reorders lights: new_lights[i] = lights[order[i]]; triangle->light ids follow.
  void reorder_lights(const std::vector<uint32_t>& order);
  // Re-reads triangle light geometry and emission from the mesh and materials (after
  // animate()); the light tree's owner then refits it (LightTree::refit).
  void refresh_lights_from_mesh();
};

// Adds the triangles of a sky dome (around `center` with `radius`) to `scene` with an emissive
// material. Exposed for tests; finalize() calls it when scene.sky is set.
void add_sky_dome(Scene& scene, const SkyDome& sky, const Vec3& center, float radius);

}  // namespace rll
