#include "rll/io/load.h"

#include <fmt/format.h>

#include "rll/core/error.h"
#include "rll/core/memory_budget.h"
#include "rll/core/paths.h"
#include "rll/io/text_scan.h"
#include "rll/scene/builtin.h"

namespace rll {
namespace fs = std::filesystem;

namespace {

// Drops the materials no triangle uses and the textures no remaining material or image light
// uses: an OBJ brings its whole MTL, and a JSON scene may replace some of those materials.
void drop_unused_materials(Scene& scene) {
  std::vector<int64_t> material_id(scene.materials.size(), -1);
  for (uint32_t m : scene.mesh.material)
    if (m < material_id.size()) material_id[m] = 0;
  std::vector<Material> kept;
  for (size_t m = 0; m < scene.materials.size(); ++m)
    if (material_id[m] == 0) {
      material_id[m] = int64_t(kept.size());
      kept.push_back(std::move(scene.materials[m]));
    }
  for (auto& m : scene.mesh.material)
    if (m < material_id.size()) m = uint32_t(material_id[m]);
  std::vector<int> texture_id(scene.textures.size(), -1);
  std::vector<Image> textures;
  for (auto& m : kept)
    for (int* tex : {&m.albedo_texture, &m.roughness_texture, &m.emission_texture}) {
      if (*tex < 0 || *tex >= int(scene.textures.size())) continue;
      int& id = texture_id[size_t(*tex)];
      if (id < 0) {
        id = int(textures.size());
        textures.push_back(std::move(scene.textures[size_t(*tex)]));
      }
      *tex = id;
    }
  for (Light& l : scene.lights)
    if (l.has_image() && l.triangle < scene.textures.size()) {
      int& id = texture_id[l.triangle];
      if (id < 0) {
        id = int(textures.size());
        textures.push_back(std::move(scene.textures[l.triangle]));
      }
      l.triangle = uint32_t(id);
    }
  scene.materials = std::move(kept);
  scene.textures = std::move(textures);
}
}  // namespace

std::string triangle_budget_problem(double triangles, const ReadPolicy& policy) {
  if (triangles > double(policy.max_triangles))
    return fmt::format(
        "the scene would have {:.0f} triangles, more than {} triangles, the most "
        "it may have",
        triangles, policy.max_triangles);
  const double bytes = triangles * kSceneBytesPerTriangle;
  if (bytes > double(memory_budget_bytes()))
    return fmt::format(
        "the scene would have {:.0f} triangles, which need about {} (at {:.0f} bytes each), more "
        "than {}",
        triangles, format_bytes(bytes), kSceneBytesPerTriangle, memory_budget_phrase());
  return "";
}

Scene read_scene(const std::string& spec) {
  Scene scene;
  const std::string prefix = "builtin:";
  if (spec.rfind(prefix, 0) == 0) {
    scene = make_builtin_scene(spec.substr(prefix.size()));
    return scene;
  }
  fs::path path(spec);
  scene.source = spec;
  if (!fs::exists(path)) fail("{}: file not found", spec);
  if (fs::is_directory(path)) fail("{}: is a folder, not a scene file", spec);
  std::string ext = lower_extension(path);
  try {
    if (ext == ".json") load_json_scene(path, scene);
    else if (ext == ".obj") load_obj(path, scene);
    else if (ext == ".ply" || (ext == ".gz" && lower_extension(path.stem()) == ".ply"))
      load_ply(path, scene);  // a .ply.gz is inflated by the PLY reader
    else if (ext == ".gltf" || ext == ".glb") load_gltf(path, scene);
    else if (ext == ".pbrt") load_pbrt(path, scene);
    else
      fail("{}: unknown scene format '{}' (rll reads .json, .obj, .gltf, .glb, .ply, .ply.gz, "
           ".pbrt and builtin:NAME)",
           spec, printable(ext));
  } catch (const Error& e) {
    // The readers quote what they echo from a file with printable(); this catches what they
    // pass on from the libraries (tinyobjloader, tinygltf, nlohmann::json) and file names.
    throw Error(without_control_bytes(e.what()));
  }
  for (auto& w : scene.warnings) w = without_control_bytes(w);
  drop_unused_materials(scene);
  return scene;
}

Scene load_scene(const std::string& spec, const LoadOptions& options) {
  Scene scene = read_scene(spec);
  if (options.width < 0 || options.height < 0) fail("resolution must be positive");
  if (options.width > 0) scene.width = options.width;
  if (options.height > 0) scene.height = options.height;
  // The readers' warnings come before finalize() may fail, and finalize()'s own after it.
  const size_t read_warnings = scene.warnings.size();
  if (options.print_warnings)
    for (const auto& w : scene.warnings) fmt::print(stderr, "rll: warning: {}\n", w);
  scene.finalize();
  if (options.print_warnings)
    for (size_t i = read_warnings; i < scene.warnings.size(); ++i)
      fmt::print(stderr, "rll: warning: {}\n", scene.warnings[i]);
  return scene;
}

}  // namespace rll
