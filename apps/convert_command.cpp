// `rll convert IN OUT`: reads any scene rll reads and writes it as JSON + OBJ (or glTF, pbrt),
// so that a scene made elsewhere can be inspected and edited.
#include <fmt/format.h>

#include <filesystem>

#include "commands.h"
#include "rll/core/error.h"
#include "rll/scene/load.h"
#include "rll/scene/save.h"

namespace rll::cli {
namespace fs = std::filesystem;

namespace {

void convert(const std::string& in, const std::string& out) {
  const fs::path target(out);
  std::string ext = target.extension().string();
  for (auto& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (ext != ".json" && ext != ".gltf" && ext != ".pbrt")
    fail("{}: rll writes .json (with .obj and .mtl beside it), .gltf and .pbrt", out);
  if (target.has_parent_path() && !fs::is_directory(target.parent_path()))
    fail("{}: folder '{}' does not exist", out, target.parent_path().string());
  Scene scene = read_scene(in);
  for (const auto& w : scene.warnings) fmt::print(stderr, "rll: warning: {}\n", w);
  std::vector<std::string> lost;
  if (ext == ".json")
    save_json_scene(scene, target);
  else if (ext == ".gltf")
    lost = save_gltf_scene(scene, target);
  else
    lost = save_pbrt_scene(scene, target);
  for (const auto& w : lost) fmt::print(stderr, "rll: warning: {}: {}\n", out, w);
}

}  // namespace

void add_convert_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "convert",
      "Convert a scene (.json .obj .gltf .glb .ply .pbrt) to .json + .obj, .gltf or .pbrt");
  auto in = std::make_shared<std::string>(), out = std::make_shared<std::string>();
  cmd->add_option("input", *in, "scene to read")->required();
  cmd->add_option("output", *out, "file to write; its extension chooses the format")->required();
  cmd->callback([in, out] { convert(*in, *out); });
}

}  // namespace rll::cli
