#include "rll/scene/load.h"

#include "rll/core/error.h"
#include "rll/scene/builtin.h"

namespace rll {
namespace fs = std::filesystem;

namespace {
std::string lower_extension(const fs::path& p) {
  std::string e = p.extension().string();
  for (auto& c : e) c = char(std::tolower(static_cast<unsigned char>(c)));
  return e;
}
}  // namespace

Scene load_scene(const std::string& spec, const LoadOptions& options) {
  Scene scene;
  const std::string prefix = "builtin:";
  if (spec.rfind(prefix, 0) == 0) {
    scene = make_builtin_scene(spec.substr(prefix.size()));
  } else {
    fs::path path(spec);
    scene.source = spec;
    if (!fs::exists(path)) fail("{}: file not found", spec);
    if (fs::is_directory(path)) fail("{}: is a folder, not a scene file", spec);
    std::string ext = lower_extension(path);
    if (ext == ".json") load_json_scene(path, scene);
    else if (ext == ".obj") load_obj(path, scene);
    else fail("{}: unknown scene format '{}' (rll reads .json, .obj and builtin:NAME)", spec, ext);
  }
  if (options.width < 0 || options.height < 0) fail("resolution must be positive");
  if (options.width > 0) scene.width = options.width;
  if (options.height > 0) scene.height = options.height;
  scene.finalize();
  return scene;
}

}  // namespace rll
