#include <fmt/format.h>
#include <fmt/ranges.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "rll/accel/accel.h"
#include "rll/core/error.h"
#include "rll/core/parallel.h"
#include "rll/core/params.h"
#include "rll/core/sysinfo.h"
#include "rll/lights/light_sampler.h"
#include "rll/render/progress.h"
#include "rll/render/session.h"

namespace rll::cli {
namespace fs = std::filesystem;

namespace {

struct RenderOptions {
  SessionSettings session;
  std::string sampler = "rll";
  int spp = 16;
  double time = 0;
  uint64_t seed = 1;
  int threads = 0;
  int pass_spp = 1;
  int max_pass_spp = 8;
  int frames = 1;
  std::string output;
  std::string stats;
  float exposure = 0;
  bool quiet = false;
};

std::string default_output(const std::string& scene) {
  std::string stem =
      scene.rfind("builtin:", 0) == 0 ? scene.substr(8) : fs::path(scene).stem().string();
  return "out/" + stem + ".png";
}

fs::path frame_path(const fs::path& p, int frame, int frames) {
  if (frames <= 1) return p;
  fs::path q = p;
  q.replace_extension(fmt::format(".{:04d}{}", frame, p.extension().string()));
  return q;
}

void run(const RenderOptions& o) {
  install_interrupt_handler();
  ThreadLimit limit(o.threads);
  // Bad flags are reported before the scene (perhaps slow to load) is read; the numbers were
  // checked as they were parsed.
  parse_resolution(o.session.resolution);
  Params::parse(o.session.set);
  fs::path output =
      o.output.empty() ? fs::path(default_output(o.session.scene)) : fs::path(o.output);
  prepare_output(output, "-o", {".exr", ".png"});
  if (!o.stats.empty()) prepare_output(o.stats, "--stats", {".json"});
  const std::vector<fs::path> inputs = scene_inputs(o.session.scene);
  for (int f = 0; f < o.frames && !inputs.empty(); ++f)
    refuse_input(frame_path(output, f, o.frames), "-o", inputs);
  if (!o.stats.empty()) refuse_input(o.stats, "--stats", inputs);

  RenderSession session(o.session);
  Scene& scene = session.scene();
  const IntegratorSettings& is = session.integrator();
  auto sampler = session.make_sampler(o.sampler);
  session.check_params_used();

  RenderSettings rs;
  rs.spp = o.spp;
  rs.time_limit = o.time;
  rs.seed = o.seed;
  rs.pass_spp = o.pass_spp;
  rs.max_pass_spp = o.max_pass_spp;
  const int frames = o.frames;
  nlohmann::json frame_stats = nlohmann::json::array();
  RenderProgress total;
  begin_work();
  for (int f = 0; f < frames && !interrupted(); ++f) {
    session.set_frame(f, sampler.get());
    rs.frame = f;
    Film film(scene.width, scene.height);
    std::string label =
        frames > 1 ? fmt::format("frame {}/{}", f + 1, frames) : std::string("render");
    RenderProgress p = session.render(*sampler, film, rs, label, !o.quiet, interrupt_flag());
    fs::path out = frame_path(output, f, frames);
    write_image(out, film.resolve(), o.exposure);
    if (p.cancelled) fmt::print(stderr, "rll: interrupted after {} spp; ", p.spp_done);
    fmt::print(stderr, "wrote {} ({} spp, {})\n", out.string(), p.spp_done,
               format_duration(p.seconds));
    if (p.nonfinite)
      fmt::print(stderr, "rll: warning: {} non-finite samples were dropped\n", p.nonfinite);
    frame_stats.push_back(
        {{"frame", f}, {"spp", p.spp_done}, {"seconds", p.seconds}, {"output", out.string()}});
    total.seconds += p.seconds;
    total.samples += p.samples;
    total.rays += p.rays;
    total.spp_done = p.spp_done;
    total.cancelled = total.cancelled || p.cancelled;
    total.nonfinite += p.nonfinite;
  }

  if (!o.stats.empty()) {
    nlohmann::json j;
    j["scene"] = o.session.scene;
    j["resolution"] = {scene.width, scene.height};
    j["integrator"] = {{"name", integrator_name(is.type)},
                       {"max_depth", is.max_depth},
                       {"strategy", strategy_name(is.strategy)}};
    j["sampler"] = sampler->describe();
    j["spp"] = total.spp_done;
    j["frames"] = frame_stats;
    j["seconds"] = total.seconds;
    j["samples"] = total.samples;
    j["samples_per_second"] = total.seconds > 0 ? total.samples / total.seconds : 0.0;
    j["rays"] = {{"camera", total.rays.camera},
                 {"bounce", total.rays.bounce},
                 {"shadow", total.rays.shadow},
                 {"total", total.rays.total()}};
    j["rays_per_second"] = total.seconds > 0 ? total.rays.total() / total.seconds : 0.0;
    j["lights"] = scene.lights.size();
    j["triangles"] = scene.mesh.triangle_count();
    j["threads"] = o.threads > 0 ? o.threads : hardware_threads();
    j["seed"] = o.seed;
    j["points"] = point_set_name(session.points());
    j["interrupted"] = total.cancelled;
    j["nonfinite_samples"] = total.nonfinite;
    j["memory"] = {{"peak_rss_bytes", peak_rss_bytes()}};
    write_file_atomic(o.stats, j.dump(2) + "\n");
  }
}

}  // namespace

void add_render_command(CLI::App& app) {
  auto o = std::make_shared<RenderOptions>();
  auto* cmd = app.add_subcommand("render", "Render a scene to an image");
  add_session_options(cmd, o->session);
  cmd->add_option("--sampler", o->sampler,
                  fmt::format("Light sampler: {}", fmt::join(light_sampler_names(), ", ")))
      ->capture_default_str();
  cmd->add_option("--spp", o->spp, "Samples per pixel (an upper limit when --time is given)")
      ->capture_default_str()
      ->check(integer_in(1, kMaxSpp));
  cmd->add_option("--time", o->time,
                  "Time budget in seconds (positive; leave it out for no limit); stops at "
                  "whichever of --spp and --time comes first, but always after at least one "
                  "sample per pixel")
      ->check(number_in(0, kMaxSeconds, true));
  cmd->add_option("--seed", o->seed,
                  "Random seed; the same seed gives the same image with any --threads")
      ->capture_default_str()
      ->check(unsigned_integer());
  cmd->add_option("--threads", o->threads, "Worker threads (0: all cores)")
      ->capture_default_str()
      ->check(integer_in(0, kMaxThreads));
  cmd->add_option("--pass-spp", o->pass_spp,
                  "Samples per pixel of the first passes; passes double every two passes up to "
                  "--max-pass-spp "
                  "(learning samplers adapt between passes)")
      ->capture_default_str()
      ->check(integer_in(1, kMaxPassSpp));
  cmd->add_option("--max-pass-spp", o->max_pass_spp, "Largest pass, in samples per pixel")
      ->capture_default_str()
      ->check(integer_in(1, kMaxSpp));
  cmd->add_option("--frames", o->frames,
                  "Frames to render; animated scenes move between frames, learning persists")
      ->capture_default_str()
      ->check(integer_in(1, kMaxFrames));
  cmd->add_option("-o,--output", o->output,
                  "Output image, .exr (linear) or .png (sRGB), any case; default out/<scene>.png; "
                  "never one of the scene's files");
  cmd->add_option("--stats", o->stats, "Write render statistics to this JSON file");
  cmd->add_option("--exposure", o->exposure, "Exposure in stops for .png output")
      ->capture_default_str()
      ->check(number_in(-kMaxExposure, kMaxExposure));
  cmd->add_flag("--quiet", o->quiet, "No progress bar");
  cmd->callback([o] { run(*o); });
}

}  // namespace rll::cli
