// Options and output checks shared by the rendering subcommands.
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <set>

#include "commands.h"
#include "rll/core/error.h"
#include "rll/core/file_checks.h"
#include "rll/core/params.h"
#include "rll/lights/light_sampler.h"

namespace rll::cli {
namespace fs = std::filesystem;

std::string lower(std::string s) {
  for (auto& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

namespace {

// The whole of `text` as a decimal integer; false on anything else, an overflow included.
template <typename T>
bool parse_integer(const std::string& text, T& value) {
  const char* end = text.data() + text.size();
  auto [ptr, ec] = std::from_chars(text.data(), end, value);
  return ec == std::errc() && ptr == end && !text.empty();
}

}  // namespace

CLI::Validator integer_in(long long lo, long long hi) {
  return CLI::Validator(
      [lo, hi](std::string& text) -> std::string {
        long long v = 0;
        if (!parse_integer(text, v) || v < lo || v > hi)
          return fmt::format("'{}' is not a whole number in [{}, {}]", shown_text(text), lo, hi);
        return {};
      },
      fmt::format("INT in [{}, {}]", lo, hi));
}

CLI::Validator unsigned_integer() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        uint64_t v = 0;
        if (!parse_integer(text, v))
          return fmt::format("'{}' is not a whole number in [0, {}]", shown_text(text), UINT64_MAX);
        return {};
      },
      "UINT64");
}

CLI::Validator number_in(double lo, double hi, bool positive) {
  return CLI::Validator(
      [lo, hi, positive](std::string& text) -> std::string {
        errno = 0;
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        const bool ok = !text.empty() && end == text.c_str() + text.size() && errno == 0 &&
                        std::isfinite(v) && v <= hi && (positive ? v > lo : v >= lo);
        if (!ok)
          return fmt::format("'{}' is not a finite number in {}{}, {}]", shown_text(text),
                             positive ? "(" : "[", lo, hi);
        return {};
      },
      fmt::format("NUMBER in {}{}, {}]", positive ? "(" : "[", lo, hi));
}

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
      ->capture_default_str()
      ->check(integer_in(1, 10000));
  cmd->add_option("--res", s.resolution,
                  fmt::format("Film resolution WIDTHxHEIGHT, each from 1 to {}, at most {} pixels "
                              "(default: the scene's)",
                              kMaxFilmSide, kMaxFilmPixels));
  cmd->add_option(
         "--points", s.points,
         "Sample points: sobol (Owen-scrambled Sobol', per pixel) or independent (a hash per "
         "pixel, sample and dimension); both reproducible for any --threads")
      ->capture_default_str();
  cmd->add_option("--set", s.set,
                  "Sampler/integrator parameter key=value (repeatable), e.g. rll.alpha=0.1")
      ->take_all();
  cmd->add_option("--filter", s.filter,
                  "none, or psf: path-space filtering (Fermat's psfpt, the paper's teaser): paths "
                  "cut at a vertex share the radiance of the vertices in their cell of a jittered "
                  "spatial hash; biased, far less noisy (docs/psf.md; --set psf.KEY=VALUE, see "
                  "`rll filters --params psf`)")
      ->capture_default_str()
      ->check(CLI::IsMember(filter_names()));
}

void add_wavefront_option(CLI::App* cmd, SessionSettings& s) {
  cmd->add_flag(
      "--wavefront", s.wavefront,
      "Render with the wavefront path tracer (paths advanced a bounce at a time by stages "
      "over queues) instead of the megakernel (one path per call): the same estimator, "
      "the same images within noise");
  add_device_options(cmd, s);
}

void add_device_options(CLI::App* cmd, SessionSettings& s) {
  cmd->add_option("--device", s.device,
                  "cpu, or cuda: the wavefront renderer on the GPU (an NVIDIA GPU of compute "
                  "capability 9.0 or newer; rays traced by rll's own BVH; every sampler but "
                  "ltc). Without a GPU, cuda exits with an error")
      ->capture_default_str()
      ->check(CLI::IsMember({"cpu", "cuda"}));
  cmd->add_option("--tracer", s.tracer,
                  "What the CPU wavefront renderer (--wavefront) traces rays with: embree, or "
                  "bvh (rll's own BVH, the traversal --device cuda runs, to check it on the CPU)")
      ->capture_default_str()
      ->check(CLI::IsMember({"embree", "bvh"}));
}

nlohmann::json session_stats(const RenderSession& session) {
  const IntegratorSettings& is = session.integrator();
  nlohmann::json j = {{"scene", session.settings().scene},
                      {"resolution", {session.scene().width, session.scene().height}},
                      {"integrator",
                       {{"name", integrator_name(is.type)},
                        {"max_depth", is.max_depth},
                        {"strategy", strategy_name(is.strategy)}}},
                      {"renderer", session.renderer_name()},
                      {"points", point_set_name(session.points())},
                      {"filter", filter_json(is.psf)}};
  // The wavefront's path slots and what its device did, pass by pass (frame by frame in
  // interactive): docs/gpu.md.
  if (const auto made = session.restir_made(); !made.empty()) {
    // ReSTIR (docs/restir.md): each restir spec's settings, and the memory its renders took.
    nlohmann::json samplers = nlohmann::json::object();
    for (const auto& [spec, settings] : made) {
      nlohmann::json s = nlohmann::json::object();
      params_json(restir_params(), settings, s);
      samplers[spec] = s;
    }
    j["restir"] = {{"samplers", samplers},
                   {"bytes", session.restir_bytes()},
                   {"bytes_per_pixel", kRestirBytesPerPixel}};
  }
  if (session.settings().wavefront || session.gpu() || session.restir_bytes() > 0) {
    const WavefrontWork& w = session.wavefront_work();
    j["path_slots"] = {
        {"count", w.path_slots}, {"bytes", w.slot_bytes}, {"budget_bytes", w.budget_bytes}};
    nlohmann::json passes = nlohmann::json::array();
    for (const DeviceWork& d : w.passes)
      passes.push_back({{"syncs", d.syncs},
                        {"launches", d.launches},
                        {"allocations", d.allocations},
                        {"bytes_to_host", d.bytes_to_host},
                        {"bytes_to_device", d.bytes_to_device}});
    j["device_work"] = passes;
  }
  return j;
}

namespace {

// Formats whose text names other files that a scene reads.
bool names_files(const std::string& ext) {
  return ext == ".json" || ext == ".obj" || ext == ".mtl" || ext == ".gltf" || ext == ".pbrt";
}

bool is_file_reference(const std::string& token) {
  static const std::set<std::string> kExtensions = {
      ".json", ".obj", ".mtl", ".gltf", ".glb", ".bin", ".ply", ".pbrt", ".exr",  ".png", ".jpg",
      ".jpeg", ".hdr", ".tga", ".bmp",  ".pfm", ".ppm", ".pgm", ".tif",  ".tiff", ".gz"};
  return kExtensions.count(lower(fs::path(token).extension().string())) > 0;
}

// Candidate file names in one line: quoted strings whole, and words.
void add_candidates(const std::string& line, std::vector<std::string>& out) {
  for (size_t q = line.find('"'); q != std::string::npos;) {
    size_t e = line.find('"', q + 1);
    if (e == std::string::npos) break;
    out.push_back(line.substr(q + 1, e - q - 1));
    q = line.find('"', e + 1);
  }
  std::string word;
  for (char c : line + " ") {
    if (std::isspace(static_cast<unsigned char>(c)) || c == '"' || c == ',' || c == '[' ||
        c == ']' || c == '{' || c == '}') {
      if (!word.empty()) out.push_back(word);
      word.clear();
    } else {
      word += c;
    }
  }
}

}  // namespace

std::vector<fs::path> scene_inputs(const std::string& spec) {
  std::vector<fs::path> inputs;
  if (spec.rfind("builtin:", 0) == 0) return inputs;
  std::error_code ec;
  check_input_file(spec, "scene");
  if (!fs::is_regular_file(spec, ec)) return inputs;  // the loader reports a missing scene
  const fs::path root_dir = fs::path(spec).parent_path();
  std::set<fs::path> seen;
  std::vector<fs::path> todo = {fs::path(spec)};
  // A scene's files are few; the bound keeps a pathological one from taking long.
  constexpr size_t kMaxFiles = 10000;
  constexpr std::streamoff kMaxScanBytes = std::streamoff(64) << 20;
  while (!todo.empty() && inputs.size() < kMaxFiles) {
    const fs::path file = todo.back();
    todo.pop_back();
    const fs::path canonical = fs::weakly_canonical(file, ec);
    if (ec || !seen.insert(canonical).second) continue;
    inputs.push_back(file);
    const std::string ext = lower(file.extension().string());
    if (!names_files(ext)) continue;
    std::ifstream in(file, std::ios::binary);
    std::string line;
    std::vector<std::string> candidates;
    while (std::getline(in, line) && in.tellg() < kMaxScanBytes) {
      // OBJ names other files only in mtllib lines; the vertex lines are most of a large one.
      if (ext == ".obj" && line.rfind("mtllib", 0) != 0) continue;
      candidates.clear();
      add_candidates(line, candidates);
      for (const auto& c : candidates) {
        if (!is_file_reference(c)) continue;
        // Relative names resolve against the naming file's folder (pbrt: the first file's).
        for (const fs::path& base : {file.parent_path(), root_dir}) {
          const fs::path p = fs::path(c).is_absolute() ? fs::path(c) : base / c;
          // A FIFO or a device named as a mesh or a texture would hang the reader or never end.
          if (fs::exists(p, ec) && !fs::is_directory(p, ec))
            check_input_file(p, fmt::format("{}: file", file.string()));
          if (fs::is_regular_file(p, ec)) {
            todo.push_back(p);
            break;
          }
        }
      }
    }
  }
  return inputs;
}

void refuse_input(const fs::path& out, const std::string& flag,
                  const std::vector<fs::path>& inputs) {
  // The file a write changes is the target of `out`'s links; a hard link of an input is the
  // same file too (refused rather than reasoned about).
  const fs::path target = write_target(out);
  for (const auto& in : inputs)
    if (same_file(target, in))
      fail("{} {} is the input file '{}': refusing to write over it (choose another output)", flag,
           out.string(), in.string());
}

std::unique_ptr<LightSampler> make_sampler_for(const RenderSession& session,
                                               const std::string& spec, const char* flag) {
  try {
    return session.make_sampler(spec);
  } catch (const Error& e) {
    fail("{}: {}", flag, e.what());
  }
}

void refuse_same_outputs(const std::vector<std::pair<fs::path, std::string>>& outputs,
                         size_t distinct) {
  for (size_t j = std::max<size_t>(distinct, 1); j < outputs.size(); ++j)
    for (size_t i = 0; i < j; ++i)
      if (same_file(write_target(outputs[i].first), write_target(outputs[j].first)))
        fail("{} {} and {} {} are the same file: give each output its own", outputs[i].second,
             outputs[i].first.string(), outputs[j].second, outputs[j].first.string());
}

void prepare_output(const fs::path& p, const char* flag,
                    const std::vector<std::string>& extensions) {
  const std::string ext = lower(p.extension().string());
  if (std::find(extensions.begin(), extensions.end(), ext) == extensions.end())
    fail("{} {}: the file must end in {}", flag, p.string(), fmt::join(extensions, " or "));
  std::error_code ec;
  // Devices, pipes, folders and read-only files are refused; a link is written through, so its
  // target's folder is the one written in (and never created through the link: check_output_file
  // refuses a link into a missing folder).
  check_output_file(p, flag);
  const fs::path target = write_target(p);
  if (target.has_parent_path() && !fs::exists(target.parent_path(), ec))
    create_output_folder(target.parent_path(), fmt::format("{} {}", flag, p.string()));
  if (target.has_parent_path() && !fs::is_directory(target.parent_path(), ec))
    fail("{} {}: '{}' is not a folder", flag, p.string(), target.parent_path().string());
  check_folder_writable(target.parent_path(), fmt::format("{} {}", flag, p.string()));
}

void prepare_output_dir(const fs::path& dir, const char* flag) {
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
    fail("{} {}: exists and is not a folder", flag, dir.string());
  create_output_folder(dir, fmt::format("{} {}", flag, dir.string()));
  check_folder_writable(dir, fmt::format("{} {}", flag, dir.string()));
}

}  // namespace rll::cli
