// `rll convert IN OUT`: reads any scene rll reads and writes it as JSON + OBJ (or glTF, pbrt),
// so that a scene made elsewhere can be inspected and edited.
#include <fmt/format.h>

#include <algorithm>
#include <filesystem>

#include "commands.h"
#include "rll/core/error.h"
#include "rll/core/file_checks.h"
#include "rll/core/paths.h"
#include "rll/io/load.h"
#include "rll/io/save.h"

namespace rll::cli {
namespace fs = std::filesystem;

namespace {

// Whether `name` is a file that the writer for `ext` puts beside <stem><ext> (see save.h).
bool is_side_file(const std::string& name, const std::string& stem, const std::string& ext) {
  if (name.compare(0, stem.size(), stem) != 0) return false;
  const std::string rest = name.substr(stem.size());
  auto numbered = [&](const std::string& prefix, const std::string& suffix) {
    if (rest.size() <= prefix.size() + suffix.size() || rest.compare(0, prefix.size(), prefix) ||
        rest.compare(rest.size() - suffix.size(), suffix.size(), suffix))
      return false;
    const std::string digits =
        rest.substr(prefix.size(), rest.size() - prefix.size() - suffix.size());
    return std::all_of(digits.begin(), digits.end(), [](char c) { return std::isdigit(c); });
  };
  if (ext == ".json")
    return rest == ".obj" || rest == ".mtl" || numbered("_tex", ".exr") ||
           numbered("_light", ".exr");
  if (ext == ".gltf") return numbered("_tex", ".png");
  return rest == "_sky.exr" || numbered("_tex", ".exr") || numbered("_mesh", ".ply") ||
         numbered("_light", ".exr");
}

void convert(const std::string& in, const std::string& out) {
  install_interrupt_handler();
  const fs::path target(out);
  const std::string ext = lower_extension(target);
  if (ext != ".json" && ext != ".gltf" && ext != ".pbrt")
    fail("{}: rll writes .json (with .obj and .mtl beside it), .gltf and .pbrt", out);
  if (target.has_parent_path() && !fs::is_directory(target.parent_path()))
    fail("{}: folder '{}' does not exist", out, target.parent_path().string());
  // The output and the files written beside it must not replace what is being converted.
  const std::vector<fs::path> inputs = scene_inputs(in);
  refuse_input(target, "convert", inputs);
  const fs::path dir = target.parent_path().empty() ? fs::path(".") : target.parent_path();
  for (const auto& input : inputs) {
    const fs::path folder = input.parent_path().empty() ? fs::path(".") : input.parent_path();
    if (is_side_file(input.filename().string(), target.stem().string(), ext) &&
        same_file(folder, dir))
      fail(
          "convert {}: would write over the input file '{}', which the {} output writes "
          "beside it (choose another output name or folder)",
          out, input.string(), ext);
  }
  prepare_output(target, "convert", {".json", ".gltf", ".pbrt"});
  // The files a .json output always writes beside it (the others depend on the scene and are
  // checked as they are written).
  if (ext == ".json")
    for (const char* side : {".obj", ".mtl"})
      check_output_file(fs::path(target).replace_extension(side), "convert");
  set_activity(fmt::format("reading scene '{}'", in));
  Scene scene = read_scene(in);
  for (const auto& w : scene.warnings) fmt::print(stderr, "rll: warning: {}\n", w);
  std::vector<std::string> lost;
  set_activity(fmt::format("writing '{}' and the files beside it", out));
  // The writers replace the files of an earlier conversion all together or not at all
  // (WriteBatch): a signal now lets them finish rather than end the program between two renames.
  begin_work();
  if (ext == ".json")
    save_json_scene(scene, target);
  else if (ext == ".gltf")
    lost = save_gltf_scene(scene, target);
  else
    lost = save_pbrt_scene(scene, target);
  for (const auto& w : lost) fmt::print(stderr, "rll: warning: {}: {}\n", out, w);
  if (interrupted())
    throw Interrupted(fmt::format("interrupted while writing; {} and its files are complete", out));
}

}  // namespace

void add_convert_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "convert",
      "Convert a scene (.json .obj .gltf .glb .ply .pbrt) to .json + .obj, .gltf or .pbrt");
  auto in = std::make_shared<std::string>(), out = std::make_shared<std::string>();
  cmd->add_option("input", *in, "scene to read")->required();
  cmd->add_option(
         "output", *out,
         "file to write; its extension chooses the format; neither it nor the files written "
         "beside it may be one of the input's files")
      ->required();
  cmd->callback([in, out] { convert(*in, *out); });
}

}  // namespace rll::cli
