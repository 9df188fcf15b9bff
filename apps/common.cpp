// Options and output checks shared by the rendering subcommands.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include "commands.h"
#include "rll/core/error.h"

namespace rll::cli {
namespace fs = std::filesystem;

void add_session_options(CLI::App* cmd, SessionSettings& s) {
  cmd->add_option("scene", s.scene,
                  "Scene: a .json, .obj, .gltf, .glb, .ply or .pbrt file, or builtin:NAME (see "
                  "`rll scenes`)")
      ->required();
  cmd->add_option("--integrator", s.integrator,
                  "Light transport: direct (light and BSDF sampling by MIS at the first hit; --set "
                  "direct.strategy=nee for light sampling only) or path")
      ->capture_default_str();
  cmd->add_option("--max-depth", s.max_depth,
                  "Path length limit (path integrator; 1 = direct light)")
      ->capture_default_str();
  cmd->add_option("--res", s.resolution, "Film resolution WIDTHxHEIGHT (default: the scene's)");
  cmd->add_option(
         "--points", s.points,
         "Sample points: sobol (Owen-scrambled Sobol', per pixel) or independent (a hash per "
         "pixel, sample and dimension); both reproducible for any --threads")
      ->capture_default_str();
  cmd->add_option("--set", s.set,
                  "Sampler/integrator parameter key=value (repeatable), e.g. rll.alpha=0.1")
      ->take_all();
}

void prepare_output(const fs::path& p, const char* flag,
                    const std::vector<std::string>& extensions) {
  std::string ext = p.extension().string();
  if (std::find(extensions.begin(), extensions.end(), ext) == extensions.end())
    fail("{} {}: the file must end in {}", flag, p.string(), fmt::join(extensions, " or "));
  std::error_code ec;
  if (p.has_parent_path() && !fs::exists(p.parent_path()) &&
      !fs::create_directories(p.parent_path(), ec))
    fail("{} {}: cannot create folder '{}': {}", flag, p.string(), p.parent_path().string(),
         ec.message());
}

void prepare_output_dir(const fs::path& dir, const char* flag) {
  std::error_code ec;
  if (fs::is_directory(dir, ec)) return;
  if (fs::exists(dir, ec)) fail("{} {}: exists and is not a folder", flag, dir.string());
  if (!fs::create_directories(dir, ec))
    fail("{} {}: cannot create folder: {}", flag, dir.string(), ec.message());
}

}  // namespace rll::cli
