// Scene loading: builtin:NAME, a JSON scene file, or a bare mesh file, chosen by the spec.
#pragma once

#include <filesystem>
#include <string>

#include "rll/scene/scene.h"

namespace rll {

struct LoadOptions {
  int width = 0, height = 0;  // film size override; 0 keeps the scene's
};

// Loads and finalizes a scene; throws rll::Error naming the file (and line where known).
Scene load_scene(const std::string& spec, const LoadOptions& options = {});

// Format readers. Each appends what it reads to `scene` (geometry, materials, textures,
// lights, camera when the format has one) without finalizing it.
void load_json_scene(const std::filesystem::path& path, Scene& scene);
// Wavefront OBJ + MTL through tinyobjloader: Kd, Ks, Ns, Ke, map_Kd (see docs/scene-format.md).
void load_obj(const std::filesystem::path& path, Scene& scene);

}  // namespace rll
