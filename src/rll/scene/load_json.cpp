#include "rll/core/error.h"
#include "rll/scene/load.h"

namespace rll {
void load_json_scene(const std::filesystem::path& path, Scene& scene) {
  fail("{}: JSON scenes are not supported yet", path.string());
}
}  // namespace rll
