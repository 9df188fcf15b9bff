// pbrt-v4 scene files, the subset in docs/scene-format.md: transforms, attributes, object
// instances, includes, the perspective camera, film size, triangle/PLY/bilinear meshes and
// tessellated spheres and disks, the materials that map onto rll's, image textures, diffuse
// area lights, distant/point lights and infinite lights (a dome of triangles). pbrt has no
// parser library: this one is hand-written, with line tracking through included files. A
// syntax error is an error naming the file and line; a directive rll does not render is
// skipped with one warning naming it and the line.
#include "rll/io/load.h"
#include "rll/io/pbrt_internal.h"
#include "rll/io/text_scan.h"

namespace rll {
namespace fs = std::filesystem;

void parse_pbrt(std::string_view text, const std::string& name, const fs::path& base_dir,
                Scene& scene, const ReadPolicy& policy) {
  pbrt::PbrtReader(base_dir, scene, policy).read(text, name);
}

void load_pbrt(const fs::path& path, Scene& scene) {
  const std::string file = path.string();
  if (!fs::exists(path)) fail("{}: file not found", file);
  const std::string text = read_text_file(path);
  parse_pbrt(text, file, path.parent_path(), scene);
}

}  // namespace rll
