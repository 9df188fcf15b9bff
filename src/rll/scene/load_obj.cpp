#include "rll/core/error.h"
#include "rll/scene/load.h"

namespace rll {
void load_obj(const std::filesystem::path& path, Scene& scene) {
  fail("{}: OBJ files are not supported yet", path.string());
}
}  // namespace rll
