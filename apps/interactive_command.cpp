// `rll interactive`: the interactive-rate mode for measurement (issue 31, item 7): frames of one
// sample per pixel with one sampler whose learning carries from frame to frame, timed stage by
// stage by the wavefront renderer.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <vector>

#include "commands.h"
#include "rll/core/error.h"
#include "rll/core/image.h"
#include "rll/core/parallel.h"
#include "rll/core/params.h"
#include "rll/core/sysinfo.h"
#include "rll/eval/compare.h"
#include "rll/eval/metrics.h"
#include "rll/eval/reference.h"
#include "rll/lights/light_sampler.h"
#include "rll/session/session.h"

namespace rll::cli {
namespace fs = std::filesystem;

namespace {

struct InteractiveOptions {
  SessionSettings session;
  std::string sampler = "rll";
  int frames = 16;
  int warmup = 1;
  bool warmup_given = false;  // --warmup was on the command line
  uint64_t seed = 1;
  int threads = 0;
  std::string output;
  std::string stats;
  float exposure = 0;
  bool quiet = false;
  // --errors: each frame measured against its own reference (an animated scene's per frame).
  bool errors = false;
  ReferenceRequest reference_request;
  std::string cache_dir;
};

// Median, least and greatest of a set of times (not empty).
struct Spread {
  double median = 0, min = 0, max = 0;
};

Spread spread_of(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return {n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]), v.front(), v.back()};
}

nlohmann::json spread_json(const Spread& s) {
  return {{"median", s.median}, {"min", s.min}, {"max", s.max}};
}

// One frame's times in milliseconds: the total and each stage's.
struct FrameTimes {
  double total_ms = 0;
  std::array<double, kWavefrontStages> stage_ms{};
};

FrameTimes to_ms(const WavefrontTimes& t) {
  FrameTimes f;
  f.total_ms = 1e3 * t.total_seconds;
  for (size_t s = 0; s < kWavefrontStages; ++s) f.stage_ms[s] = 1e3 * t.stage_seconds[s];
  return f;
}

std::string stage_columns(const std::array<double, kWavefrontStages>& ms) {
  std::string line;
  for (size_t s = 0; s < kWavefrontStages; ++s)
    line += fmt::format(" {} {:.2f}", kWavefrontStageNames[s], ms[s]);
  return line;
}

void run(InteractiveOptions o) {
  install_interrupt_handler();
  ThreadLimit limit(o.threads);
  // Bad flags are reported before the scene (perhaps slow to load) is read.
  parse_resolution(o.session.resolution);
  Params::parse(o.session.set);
  if (!o.warmup_given) o.warmup = std::min(o.warmup, o.frames - 1);  // a single frame is measured
  if (o.warmup >= o.frames)
    fail("--warmup {}: must be less than --frames {} (the summary needs a measured frame)",
         o.warmup, o.frames);
  std::vector<std::pair<fs::path, std::string>> outputs;
  if (!o.output.empty()) {
    prepare_output(o.output, "-o", {".exr", ".png"});
    outputs.emplace_back(o.output, "-o");
  }
  if (!o.stats.empty()) {
    prepare_output(o.stats, "--stats", {".json"});
    outputs.emplace_back(o.stats, "--stats");
  }
  refuse_same_outputs(outputs);
  const std::vector<fs::path> inputs = scene_inputs(o.session.scene);
  for (const auto& [path, flag] : outputs) refuse_input(path, flag, inputs);

  SessionSettings settings = o.session;
  settings.wavefront = true;  // the renderer with stages to time
  set_activity(fmt::format("loading scene '{}'", o.session.scene));
  RenderSession session(settings);
  const Scene& scene = session.scene();
  const IntegratorSettings& is = session.integrator();
  auto sampler = make_sampler_for(session, o.sampler, "--sampler");
  session.check_params_used();
  const bool animated = bool(scene.animate);
  // --errors: the references, before the first frame (a static scene's one; an animated
  // scene's one per frame, each with the scene moved to it). The seeds of the frames' renders
  // are the run's `seed`: a reference never shares them.
  std::vector<ObtainedReference> references;
  if (o.errors) {
    session.check_film_memory(kRenderBytesPerPixel + 2 * 3 * 4 * (animated ? o.frames : 1),
                              "the film, and each reference and its variance");
    ReferenceCache cache(o.cache_dir.empty() ? default_cache_dir() : fs::path(o.cache_dir));
    ReferenceRequest request = o.reference_request;
    request.seed_allowed = [&](uint64_t s) { return !reference_shares_a_seed(s, o.seed, 1); };
    if (reference_shares_a_seed(request.seed, o.seed, 1))
      fail(
          "--reference-seed {} (its halves use seeds {} and {}) shares --seed {}: the reference "
          "would share the frames' noise",
          request.seed, request.seed, request.seed + 1, o.seed);
    for (int f = 0; f < (animated ? o.frames : 1); ++f) {
      session.set_frame(f, nullptr);
      request.frame = animated ? f : -1;
      set_activity(fmt::format("the reference of frame {}", f + 1));
      ObtainedReference got = obtain_reference(session, cache, request, !o.quiet, interrupt_flag());
      if (!got.complete) throw Interrupted("interrupted while rendering a reference");
      if (!o.quiet)
        fmt::print(stderr, "reference{}: {} {} ({} spp, sampler {})\n",
                   animated ? fmt::format(" of frame {}", f + 1) : std::string(),
                   got.from_cache ? "reused" : "rendered and cached", got.info.image.string(),
                   got.info.spp, got.info.sampler);
      references.push_back(std::move(got));
    }
  }
  // A static scene's frames accumulate in one film, which stays on the GPU between them (read
  // back once, for -o); an animated scene's film is new each frame.
  session.keep_film_on_device(!animated);

  RenderSettings rs;
  rs.spp = 1;
  rs.seed = o.seed;
  rs.pass_spp = rs.max_pass_spp = 1;
  // A static scene's frames are further samples of one image (sample f of each pixel in frame
  // f); an animated scene's frames are images of their own (the frame enters the seed).
  Film film(scene.width, scene.height);
  std::vector<FrameTimes> frames;
  nlohmann::json frame_stats = nlohmann::json::array();
  if (!o.quiet)
    fmt::print("rll interactive: {} {}x{}, {} {} depth {}, sampler {}, {}, {} frames\n",
               o.session.scene, scene.width, scene.height, integrator_name(is.type),
               strategy_name(is.strategy), is.max_depth,
               o.sampler.rfind("restir", 0) == 0 ? o.sampler : sampler->name(),  // (its source's)
               session.gpu() ? "GPU wavefront on " + session.gpu()->device_name()
                             : std::string("CPU wavefront"),
               o.frames);
  set_activity(fmt::format("rendering {}x{} frames", scene.width, scene.height));
  begin_work();
  bool cancelled = false;
  PsfCounts filter;                     // path-space filtering's, over the frames
  std::vector<double> relmse, trimmed;  // --errors: per frame
  uint64_t samples = 0;
  for (int f = 0; f < o.frames && !interrupted(); ++f) {
    session.set_frame(f, sampler.get());
    if (animated) {
      rs.frame = f;
      film = Film(scene.width, scene.height);
    } else {
      rs.spp = f + 1;  // the film holds samples 0 to f - 1: this frame takes sample f
    }
    rs.follows_frame = f > 0;  // (the filter's temporal reuse blends the last frame's cells)
    rs.precedes_frame = f + 1 < o.frames;
    WavefrontTimes times;
    // One pass of 1 spp: the sampler's end_pass after it carries the frame's learning on.
    const RenderProgress p =
        session.render(*sampler, film, rs, "frame", false, interrupt_flag(), {}, &times);
    if (p.cancelled) {
      cancelled = true;
      break;
    }
    filter += p.filter;
    samples += p.samples;
    const FrameTimes ft = to_ms(times);
    frames.push_back(ft);
    // --errors: the frame's image (an animated scene's frame, a static scene's frames so far)
    // against its reference; read and measured after the frame's timed render.
    Checkpoint error;
    if (o.errors) {
      const ObtainedReference& ref = references[animated ? size_t(f) : 0];
      session.read_film(film);
      ConvergenceRecorder recorder(ref.image, ref.variance.pixel_count() ? &ref.variance : nullptr);
      recorder.finish(p, film.resolve());
      error = recorder.checkpoints().back();
      relmse.push_back(error.relmse);
      trimmed.push_back(error.trimmed_relmse);
    }
    nlohmann::json stages;
    for (size_t s = 0; s < kWavefrontStages; ++s) stages[kWavefrontStageNames[s]] = ft.stage_ms[s];
    frame_stats.push_back(
        {{"frame", f},
         {"ms_total", ft.total_ms},
         {"ms_stages", stages},
         {"samples", p.samples},
         {"rays",
          {{"camera", p.rays.camera}, {"bounce", p.rays.bounce}, {"shadow", p.rays.shadow}}}});
    if (o.errors) {
      frame_stats.back()["relmse"] = error.relmse;
      frame_stats.back()["trimmed_relmse"] = error.trimmed_relmse;
      frame_stats.back()["mrse"] = error.mrse;
    }
    if (!o.quiet) {
      fmt::print("frame {} {:.2f} ms:{}{}\n", f, ft.total_ms, stage_columns(ft.stage_ms),
                 o.errors ? fmt::format(" relmse {:.4e} trimmed {:.4e}", error.relmse,
                                        error.trimmed_relmse)
                          : std::string());
      std::fflush(stdout);  // a line as each frame ends, also into a pipe
    }
  }

  // The summary over the frames after the warm-up (an interrupted run: those it has).
  nlohmann::json summary;
  const int measured = int(frames.size()) - o.warmup;
  if (measured > 0) {
    auto over = [&](auto&& value) {
      std::vector<double> v;
      for (size_t f = size_t(o.warmup); f < frames.size(); ++f) v.push_back(value(frames[f]));
      return spread_of(v);
    };
    const Spread total = over([](const FrameTimes& t) { return t.total_ms; });
    summary["ms_total"] = spread_json(total);
    std::array<double, kWavefrontStages> medians{};
    for (size_t s = 0; s < kWavefrontStages; ++s) {
      const Spread sp = over([s](const FrameTimes& t) { return t.stage_ms[s]; });
      summary["ms_stages"][kWavefrontStageNames[s]] = spread_json(sp);
      medians[s] = sp.median;
    }
    if (!o.quiet) {
      fmt::print("median of {} frames after {} warm-up: {:.2f} ms (min {:.2f}, max {:.2f})\n",
                 measured, o.warmup, total.median, total.min, total.max);
      fmt::print("median ms per stage:{}\n", stage_columns(medians));
    }
  }

  // An animated scene's film holds the interrupted frame alone, a part of it: no image of it.
  if (!o.output.empty() && cancelled && animated)
    fmt::print(stderr, "rll: the frame being rendered was interrupted: {} was not written\n",
               o.output);
  else if (!o.output.empty() && !frames.empty()) {
    set_activity(fmt::format("writing '{}'", o.output));
    session.read_film(film);
    write_image(o.output, film.resolve(), o.exposure);
    fmt::print(stderr, "wrote {} ({})\n", o.output,
               animated ? "the last frame" : fmt::format("{} frames accumulated", frames.size()));
  }
  if (!o.stats.empty()) {
    nlohmann::json j = session_stats(session);
    j["sampler"] = sampler->describe();
    j["filter"] = filter_json(is.psf, &filter, samples, session.psf_history_bytes());
    j["device"] = o.session.device;
    if (session.gpu()) {
      j["gpu"] = session.gpu()->device_name();
      j["memory"]["gpu_bytes"] = session.gpu()->device_bytes();
    }
    j["animated"] = animated;
    j["spp_per_frame"] = 1;
    j["frames_requested"] = o.frames;
    j["warmup"] = o.warmup;
    j["stages"] = kWavefrontStageNames;
    j["frames"] = frame_stats;
    j["summary"] = summary;
    if (o.errors) {
      j["summary"]["relmse"] = relmse;  // per frame, frame 0 first (the warm-up's too)
      j["summary"]["trimmed_relmse"] = trimmed;
      j["references"] = nlohmann::json::array();
      for (const ObtainedReference& r : references)
        j["references"].push_back(reference_json(r.from_cache, r.info, r.image, r.variance));
    }
    j["threads"] = o.threads > 0 ? o.threads : hardware_threads();
    j["seed"] = o.seed;
    j["interrupted"] = cancelled || interrupted();
    j["memory"]["peak_rss_bytes"] = peak_rss_bytes();
    write_file_atomic(o.stats, j.dump(2) + "\n");
  }
  if (cancelled || interrupted())
    fmt::print(stderr, "rll: interrupted after {} frames\n", frames.size());
}

}  // namespace

void add_interactive_command(CLI::App& app) {
  auto o = std::make_shared<InteractiveOptions>();
  o->session.resolution = "1920x1080";
  auto* cmd = app.add_subcommand(
      "interactive",
      "Interactive-rate measurement: frames of 1 spp with learning carried from frame to frame, "
      "timed per stage (the CPU wavefront renderer, or with --device cuda the GPU's, its "
      "stages timed by CUDA events)");
  add_session_options(cmd, o->session);
  add_device_options(cmd, o->session);
  cmd->get_option("--res")->description(
      fmt::format("Film resolution WIDTHxHEIGHT, each from 1 to {}, at most {} pixels",
                  kMaxFilmSide, kMaxFilmPixels));
  cmd->get_option("--res")->capture_default_str();
  cmd->add_option("--sampler", o->sampler,
                  fmt::format("Light sampler, one for all frames (what it learns in a frame is "
                              "used by the next): {}",
                              fmt::join(sampler_names(), ", ")))
      ->capture_default_str();
  cmd->add_option("--frames", o->frames,
                  fmt::format("Frames to render, 1 spp each, at most {}; an animated scene "
                              "(builtin:cornell-boxes-dynamic) moves to frame f in frame f, a "
                              "static one accumulates them",
                              kMaxFrames))
      ->capture_default_str()
      ->check(integer_in(1, kMaxFrames));
  cmd->add_option("--warmup", o->warmup,
                  "Frames left out of the summary's median, min and max (less than --frames; "
                  "by default 1, or 0 with --frames 1)")
      ->capture_default_str()
      ->check(integer_in(0, kMaxFrames - 1))
      ->each([o](const std::string&) { o->warmup_given = true; });
  cmd->add_option("--seed", o->seed,
                  "Random seed; the same seed gives the same images with any --threads")
      ->capture_default_str()
      ->check(unsigned_integer());
  cmd->add_option("--threads", o->threads, "Worker threads (0: all cores)")
      ->capture_default_str()
      ->check(integer_in(0, kMaxThreads));
  cmd->add_option("-o,--output", o->output,
                  "Write the last frame (animated scene) or all frames accumulated (static "
                  "scene): .exr (linear) or .png (sRGB); none by default");
  cmd->add_option("--stats", o->stats,
                  "Write the per-frame and per-stage times (ms) and their summary to this JSON "
                  "file");
  cmd->add_option("--exposure", o->exposure, "Exposure in stops for .png output")
      ->capture_default_str()
      ->check(number_in(-kMaxExposure, kMaxExposure));
  cmd->add_flag("--quiet", o->quiet, "No per-frame lines and summary on stdout");
  auto* errors = cmd->add_flag(
      "--errors", o->errors,
      "Measure each frame against its own reference (an animated scene's per frame, a "
      "static scene's frames so far against its one), taken from the reference cache "
      "or rendered into it before the first frame: relMSE and trimmed relMSE on each "
      "frame's line and in --stats (the reading and measuring are not timed)");
  cmd->add_option("--reference-spp", o->reference_request.spp,
                  "With --errors: samples per pixel of the references")
      ->capture_default_str()
      ->check(integer_in(1, kMaxSpp))
      ->needs(errors);
  cmd->add_option("--reference-sampler", o->reference_request.sampler,
                  "With --errors: the light sampler that renders the references")
      ->capture_default_str()
      ->needs(errors);
  cmd->add_option("--reference-seed", o->reference_request.seed,
                  "With --errors: seed of the references")
      ->capture_default_str()
      ->check(unsigned_integer())
      ->needs(errors);
  cmd->add_option("--cache-dir", o->cache_dir,
                  "With --errors: reference cache folder (default: $RLL_CACHE_DIR, else "
                  "out/cache)")
      ->needs(errors);
  cmd->callback([o] { run(*o); });
}

}  // namespace rll::cli
