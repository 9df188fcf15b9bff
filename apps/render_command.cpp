#include <fmt/format.h>
#include <fmt/ranges.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "rll/accel/accel.h"
#include "rll/core/error.h"
#include "rll/core/file_checks.h"
#include "rll/core/parallel.h"
#include "rll/core/params.h"
#include "rll/core/paths.h"
#include "rll/core/sysinfo.h"
#include "rll/lights/light_sampler.h"
#include "rll/lights/sampler_state.h"
#include "rll/render/aov.h"
#include "rll/render/progress.h"
#include "rll/render/share.h"
#include "rll/session/session.h"

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
  std::string task;        // --task I/N, empty: the whole render
  bool spp_given = false;  // --spp was on the command line
  std::string state;       // --rll-state FILE
  std::string state_mode = "update";
  std::string aov;  // --aov NAME[,NAME]: diagnostics as extra EXR channels
};

// What every share of one render has in common (ShareInfo::settings), but the frame.
nlohmann::json share_settings(const RenderOptions& o, const RenderSession& session,
                              uint64_t fingerprint) {
  const Scene& scene = session.scene();
  const IntegratorSettings& is = session.integrator();
  std::vector<std::string> set = o.session.set;
  std::sort(set.begin(), set.end());
  nlohmann::json j = {{"scene_fingerprint", fmt::format("{:016x}", fingerprint)},
                      {"resolution", fmt::format("{}x{}", scene.width, scene.height)},
                      {"integrator", integrator_name(is.type)},
                      {"max_depth", is.max_depth},
                      {"strategy", strategy_name(is.strategy)},
                      {"sampler", o.sampler},
                      {"set", set},
                      {"points", point_set_name(session.points())},
                      {"seed", std::to_string(o.seed)},
                      {"pass_spp", o.pass_spp},
                      {"max_pass_spp", o.max_pass_spp},
                      {"rll_state", o.state.empty() ? "none" : o.state_mode}};
  // (Only where on: the shares of an unfiltered render keep the settings they always had.)
  if (is.psf.on) j["filter"] = filter_json(is.psf);
  return j;
}

std::string default_output(const std::string& scene) {
  std::string stem =
      scene.rfind("builtin:", 0) == 0 ? scene.substr(8) : fs::path(scene).stem().string();
  return "out/" + stem + ".png";
}

fs::path frame_path(const fs::path& p, int frame, int frames) {
  return numbered_path(p, frame, frames);
}

void run(const RenderOptions& o) {
  install_interrupt_handler();
  ThreadLimit limit(o.threads);
  // Bad flags are reported before the scene (perhaps slow to load) is read; the numbers were
  // checked as they were parsed.
  parse_resolution(o.session.resolution);
  Params::parse(o.session.set);
  const RenderTask task = o.task.empty() ? RenderTask{} : parse_task(o.task, "--task");
  if (!o.task.empty()) {
    if (!o.spp_given)
      fail(
          "--task {}: give the samples per pixel of each share with --spp (the shares of a render "
          "must all hold the same number)",
          o.task);
    if (o.time > 0)
      fail("--task {}: a share renders a fixed range of samples; --time cannot be used with it",
           o.task);
    if ((long long)o.spp * task.count > kMaxSpp)
      fail("--task {} with --spp {}: the whole render would have more than {} spp", o.task, o.spp,
           kMaxSpp);
  }
  fs::path output =
      o.output.empty() ? fs::path(default_output(o.session.scene)) : fs::path(o.output);
  if (!o.task.empty() && lower(output.extension().string()) != ".exr")
    fail("--task {}: the output must be an .exr, which keeps what a merge needs (got -o {})",
         o.task, output.string());
  prepare_output(output, "-o", {".exr", ".png"});
  const std::vector<Aov> aovs = o.aov.empty() ? std::vector<Aov>() : parse_aovs(o.aov, "--aov");
  if (!aovs.empty() && lower(output.extension().string()) != ".exr")
    fail("--aov: the diagnostics are extra channels of an .exr output (got -o {})",
         output.string());
  if (!aovs.empty() && (o.session.wavefront || o.session.device != "cpu"))
    fail(
        "--aov: the diagnostics are measured by the megakernel; leave out --wavefront and "
        "--device");
  for (int f = 1; f < o.frames; ++f) check_output_file(frame_path(output, f, o.frames), "-o");
  const bool load_state = !o.state.empty() && o.state_mode != "save";
  const bool save_state = !o.state.empty() && o.state_mode != "load";
  if (!o.state.empty()) {
    std::error_code ec;
    if (load_state) check_input_file(o.state, "--rll-state");
    if (o.state_mode == "load" && !fs::exists(o.state, ec))
      fail("--rll-state {}: not found (--rll-state-mode load reads a state and never writes one)",
           o.state);
    if (save_state)
      prepare_output(o.state, "--rll-state", {lower(fs::path(o.state).extension().string())});
  }
  if (!o.stats.empty()) prepare_output(o.stats, "--stats", {".json"});
  // Every output is a file of its own, and none is a file the render reads.
  std::vector<std::pair<fs::path, std::string>> outputs;
  for (int f = 0; f < o.frames; ++f) outputs.emplace_back(frame_path(output, f, o.frames), "-o");
  if (!o.stats.empty()) outputs.emplace_back(o.stats, "--stats");
  if (save_state) outputs.emplace_back(o.state, "--rll-state");
  refuse_same_outputs(outputs, size_t(o.frames));  // frame names differ from one another
  std::vector<fs::path> inputs = scene_inputs(o.session.scene);
  if (load_state && !save_state) inputs.emplace_back(o.state);
  for (const auto& [path, flag] : outputs) refuse_input(path, flag, inputs);

  set_activity(fmt::format("loading scene '{}'", o.session.scene));
  RenderSession session(o.session);
  Scene& scene = session.scene();
  // The per-pixel diagnostics of --aov are kept beside the film: checked with it.
  if (!aovs.empty())
    session.check_film_memory(
        kRenderBytesPerPixel + kCameraVertexBytesPerPixel + 4.0 * double(aovs.size()),
        fmt::format("{}, and the --aov diagnostics", kRenderPixelText));
  set_activity(fmt::format("making sampler '{}'", o.sampler));
  auto sampler = make_sampler_for(session, o.sampler, "--sampler");
  const IntegratorSettings integrator = session.integrator_for(o.sampler);
  session.check_params_used();
  if (!o.state.empty()) check_sampler_has_state(*sampler, "--rll-state");
  // Shares and states belong to the scene as loaded, before an animation moves its lights.
  const bool exr_output = lower(output.extension().string()) == ".exr";
  const uint64_t fingerprint = exr_output || !o.state.empty() ? scene.fingerprint() : 0;
  nlohmann::json settings;
  if (exr_output) settings = share_settings(o, session, fingerprint);
  bool state_loaded = false;
  if (load_state && fs::exists(o.state)) {
    load_sampler_state(o.state, *sampler, fingerprint);
    state_loaded = true;
    if (!o.quiet)
      fmt::print(stderr, "rll: {} starts from the state learnt in {}\n", sampler->name(), o.state);
  }

  RenderSettings rs;
  rs.spp = o.spp;
  rs.time_limit = o.time;
  rs.seed = o.seed;
  rs.first_sample = uint64_t(task.index) * uint64_t(o.spp);
  rs.pass_spp = o.pass_spp;
  rs.max_pass_spp = o.max_pass_spp;
  const int frames = o.frames;
  nlohmann::json frame_stats = nlohmann::json::array();
  RenderProgress total;
  begin_work();
  for (int f = 0; f < frames && !interrupted(); ++f) {
    session.set_frame(f, sampler.get());
    rs.frame = f;
    rs.follows_frame = f > 0;  // (the filter's temporal reuse blends the last frame's cells)
    rs.precedes_frame = f + 1 < frames;
    std::string label =
        frames > 1 ? fmt::format("frame {}/{}", f + 1, frames) : std::string("render");
    set_activity(fmt::format("rendering {}x{} ({}{})", scene.width, scene.height, label,
                             o.aov.empty() ? "" : ", with --aov " + o.aov));
    Film film(scene.width, scene.height);
    if (!aovs.empty()) film.track_camera_vertex();
    RenderProgress p = session.render(*sampler, film, rs, label, !o.quiet, interrupt_flag(), {},
                                      nullptr, &integrator);
    fs::path out = frame_path(output, f, frames);
    total.seconds += p.seconds;
    total.samples += p.samples;
    total.rays += p.rays;
    total.spp_done = p.spp_done;
    total.cancelled = total.cancelled || p.cancelled;
    total.nonfinite += p.nonfinite;
    total.filter += p.filter;
    // Interrupted before any sample, or (a .png, which cannot tell a pixel without a sample from
    // a black one) before every pixel had one: nothing worth writing, and writing a huge film
    // would take long after the user asked to stop. An .exr keeps each pixel's sample count.
    if (p.cancelled && (p.samples == 0 || (!exr_output && p.spp_done == 0))) {
      fmt::print(
          stderr, "rll: interrupted {}: {} was not written{}\n",
          p.samples == 0 ? "before the first sample" : "before every pixel had a sample (0 spp)",
          out.string(),
          p.samples == 0 ? "" : " (an .exr output keeps the pixels that have samples)");
      frame_stats.push_back(
          {{"frame", f}, {"spp", 0}, {"seconds", p.seconds}, {"output", nullptr}});
      break;
    }
    set_activity(fmt::format("writing '{}' ({}x{})", out.string(), scene.width, scene.height));
    if (exr_output) {
      ShareInfo share;
      share.settings = settings;
      share.settings["frame"] = f;
      share.tasks = task.count;
      share.task_spp = o.task.empty() ? p.spp_done : o.spp;
      share.held = {task.index};
      share.scene = o.session.scene;
      share.commit = build_commit();
      ExrFile file = share_file(film, share);
      if (!aovs.empty()) file.channels = resolve_aovs(film, *sampler, aovs);
      write_exr(out, file);
    } else {
      write_image(out, film.resolve(), o.exposure);
    }
    if (p.cancelled) fmt::print(stderr, "rll: interrupted after {} spp; ", p.spp_done);
    fmt::print(stderr, "wrote {} ({} spp, {})\n", out.string(), p.spp_done,
               format_duration(p.seconds));
    if (p.nonfinite)
      fmt::print(stderr, "rll: warning: {} non-finite samples were dropped\n", p.nonfinite);
    frame_stats.push_back(
        {{"frame", f}, {"spp", p.spp_done}, {"seconds", p.seconds}, {"output", out.string()}});
  }

  if (save_state) {
    save_sampler_state(o.state, *sampler, fingerprint);
    if (!o.quiet)
      fmt::print(stderr, "rll: saved {}'s learnt state to {}\n", sampler->name(), o.state);
  }

  if (!o.stats.empty()) {
    nlohmann::json j = session_stats(session);
    j["sampler"] = sampler->describe();
    j["spp"] = total.spp_done;
    j["frames"] = frame_stats;
    j["seconds"] = total.seconds;
    j["samples"] = total.samples;
    j["samples_per_second"] = total.seconds > 0 ? total.samples / total.seconds : 0.0;
    j["rays"] = {{"camera", total.rays.camera},
                 {"bounce", total.rays.bounce},
                 {"shadow", total.rays.shadow},
                 {"shadow_visible", total.rays.shadow_visible},
                 {"total", total.rays.total()}};
    j["visible_sample_ratio"] = total.rays.visible_ratio();
    j["rays_per_second"] = total.seconds > 0 ? total.rays.total() / total.seconds : 0.0;
    j["lights"] = scene.lights.size();
    j["triangles"] = scene.mesh.triangle_count();
    j["threads"] = o.threads > 0 ? o.threads : hardware_threads();
    j["seed"] = o.seed;
    j["task"] = {{"index", task.index}, {"count", task.count}, {"first_sample", rs.first_sample}};
    j["rll_state"] = {{"file", o.state}, {"mode", o.state_mode}, {"loaded", state_loaded}};
    j["interrupted"] = total.cancelled;
    j["nonfinite_samples"] = total.nonfinite;
    j["filter"] =
        filter_json(integrator.psf, &total.filter, total.samples, session.psf_history_bytes());
    j["memory"] = {{"peak_rss_bytes", peak_rss_bytes()}};
    write_file_atomic(o.stats, j.dump(2) + "\n");
  }
}

}  // namespace

void add_render_command(CLI::App& app) {
  auto o = std::make_shared<RenderOptions>();
  auto* cmd = app.add_subcommand("render", "Render a scene to an image");
  add_session_options(cmd, o->session);
  add_wavefront_option(cmd, o->session);
  cmd->add_option("--sampler", o->sampler,
                  fmt::format("Light sampler: {}", fmt::join(sampler_names(), ", ")))
      ->capture_default_str();
  cmd->add_option("--spp", o->spp, "Samples per pixel (an upper limit when --time is given)")
      ->capture_default_str()
      ->check(integer_in(1, kMaxSpp))
      ->each([o](const std::string&) { o->spp_given = true; });
  cmd->add_option("--time", o->time,
                  "Time budget in seconds (positive; leave it out for no limit); stops at "
                  "whichever of --spp and --time comes first, but always after at least one "
                  "sample per pixel; the last passes are sized from the measured rate to end "
                  "at the budget")
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
                  fmt::format("Frames to render, at most {} (a file each: NAME.0000.EXT, ...); "
                              "animated scenes move between frames, learning persists",
                              kMaxFrames))
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
  cmd->add_option("--task", o->task,
                  "Render share I of N (I counted from 0) of a render split by samples: sample "
                  "indices [I*S, (I+1)*S) of each pixel, S the --spp of each share, to an .exr "
                  "that `rll merge` combines with the other shares into the N*S-spp render "
                  "(docs/cluster.md)");
  cmd->add_option("--rll-state", o->state,
                  "Learnt sampler state (rll, fermat): loaded at the start if the file exists, "
                  "saved at the end (see --rll-state-mode); refused if it was learnt on another "
                  "scene, resolution, sampler or parameters");
  cmd->add_option("--rll-state-mode", o->state_mode,
                  "update: load if it exists, save at the end; load: it must exist, never "
                  "written (the shares of a farm); save: start cold, write at the end")
      ->capture_default_str()
      ->check(CLI::IsMember({"update", "load", "save"}));
  std::string aov_help =
      "Per-pixel diagnostics at the camera vertex (the first surface a path hits), written as "
      "extra channels aov.NAME of the .exr output; a comma-separated list of:";
  for (const auto& a : aov_list()) aov_help += fmt::format(" {} ({});", a.name, a.meaning);
  cmd->add_option("--aov", o->aov, aov_help);
  cmd->callback([o] { run(*o); });
}

}  // namespace rll::cli
