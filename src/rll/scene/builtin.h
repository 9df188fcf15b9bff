// Scenes made by rll's own code, addressed as builtin:NAME.
#pragma once

#include <string>
#include <vector>

#include "rll/scene/scene.h"

namespace rll {

struct BuiltinSceneInfo {
  std::string name;
  std::string description;
};

const std::vector<BuiltinSceneInfo>& builtin_scenes();

// Builds the named scene, not yet finalized; throws rll::Error listing the names if unknown.
Scene make_builtin_scene(const std::string& name);

// Analytic value of the furnace scene seen by the camera, for tests: emission Le times the sum
// of albedo^k for k = 0..max_depth.
inline constexpr float kFurnaceEmission = 1.0f;
inline constexpr float kFurnaceAlbedo = 0.5f;

}  // namespace rll
