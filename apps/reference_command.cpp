// `rll reference`: a high-sample reference image, cached by scene content and settings, that
// `rll compare` reuses.
#include <fmt/format.h>

#include <algorithm>

#include "commands.h"
#include "rll/core/error.h"
#include "rll/core/file_checks.h"
#include "rll/core/image.h"
#include "rll/core/parallel.h"
#include "rll/eval/reference.h"
#include "rll/render/progress.h"

namespace rll::cli {
namespace fs = std::filesystem;

namespace {

struct ReferenceOptions {
  SessionSettings session;
  ReferenceRequest request;
  int threads = 0;
  std::string cache_dir;
  std::string output;
  float exposure = 0;
  bool quiet = false;
};

// Beside an .exr output, its variance: ref.exr -> ref.variance.exr (none for .png).
fs::path variance_path(const fs::path& output) {
  if (lower(output.extension().string()) != ".exr") return {};
  fs::path p = output;
  return p.replace_extension(".variance.exr");
}

void run(const ReferenceOptions& o) {
  install_interrupt_handler();
  ThreadLimit limit(o.threads);
  // The numbers were checked as they were parsed.
  parse_resolution(o.session.resolution);
  if (o.session.filter != "none")
    fail(
        "--filter {}: a reference is the unfiltered estimate the filtered renders are measured "
        "against (their bias included); leave --filter out",
        o.session.filter);
  const std::vector<fs::path> inputs = scene_inputs(o.session.scene);
  const ReferenceCache cache(o.cache_dir.empty() ? default_cache_dir() : fs::path(o.cache_dir));
  if (!o.output.empty()) {
    prepare_output(o.output, "-o", {".exr", ".png"});
    std::vector<std::pair<fs::path, std::string>> outputs = {{o.output, "-o"}};
    if (const fs::path var = variance_path(o.output); !var.empty()) {
      check_output_file(var, "-o (its variance)");
      outputs.emplace_back(var, "-o (its variance)");
    }
    refuse_same_outputs(outputs);
    for (const auto& [path, flag] : outputs) {
      refuse_input(path, flag, inputs);
      // The cache's files are its own: a copy written over an entry would corrupt it for good.
      const fs::path folder = write_target(path).parent_path();
      if (same_file(folder.empty() ? fs::path(".") : folder, cache.dir()))
        fail(
            "{} {} is in the reference cache folder '{}', whose files are the cache's own: "
            "write it elsewhere",
            flag, path.string(), cache.dir().string());
    }
  }

  set_activity(fmt::format("loading scene '{}'", o.session.scene));
  RenderSession session(o.session);
  // A reference renders its two halves in turn and keeps both (image and counts), then their
  // mean and variance: more a pixel than a render.
  session.check_film_memory(3 * 8 + 4 + 2 * (3 * 4 + 4) + 2 * 3 * 4 + 8,
                            "a film, the images and counts of both halves, their mean and its "
                            "variance");
  // An unknown name or parameter fails before rendering.
  make_sampler_for(session, o.request.sampler, "--sampler");
  session.check_params_used();
  set_activity(
      fmt::format("rendering a {}x{} reference", session.scene().width, session.scene().height));
  begin_work();
  ObtainedReference ref = obtain_reference(session, cache, o.request, !o.quiet, interrupt_flag());
  if (!ref.complete) {
    fmt::print(stderr, "rll: interrupted after {} spp; the reference was not cached\n",
               ref.info.spp);
    if (o.output.empty()) return;
    // As `rll render` does: nothing when no sample was taken, nor a .png (which cannot tell a
    // pixel without a sample from a black one) before every pixel had one.
    const bool exr = lower(fs::path(o.output).extension().string()) == ".exr";
    const bool sampled =
        std::any_of(ref.counts.begin(), ref.counts.end(), [](uint32_t n) { return n > 0; });
    if (!sampled || (!exr && ref.info.spp == 0)) {
      fmt::print(stderr, "rll: interrupted {}: {} was not written\n",
                 sampled ? "before every pixel had a sample (0 spp)" : "before the first sample",
                 o.output);
      return;
    }
    set_activity(fmt::format("writing '{}'", o.output));
    // As `rll render` does, an .exr says how many samples each pixel holds.
    if (exr)
      write_exr(o.output, ExrFile{ref.image, {}, ref.counts, {}});
    else
      write_image(o.output, ref.image, o.exposure);
    fmt::print(stderr, "wrote {} (partial: {} spp)\n", o.output, ref.info.spp);
    return;
  }
  if (ref.from_cache)
    fmt::print(stderr, "reference: reused the cached {} ({} spp, sampler {}, seed {})\n",
               ref.info.image.string(), ref.info.spp, ref.info.sampler, ref.info.seed);
  else
    fmt::print(stderr, "reference: rendered {} spp in {}, cached as {}\n", ref.info.spp,
               format_duration(ref.info.seconds), ref.info.image.string());
  if (!o.output.empty()) {
    set_activity(fmt::format("writing '{}'", o.output));
    write_image(o.output, ref.image, o.exposure);
    fmt::print(stderr, "wrote {}\n", o.output);
    if (const fs::path var = variance_path(o.output);
        !var.empty() && ref.variance.pixel_count() > 0) {
      write_image(var, ref.variance);
      fmt::print(stderr, "wrote {} (its per-pixel variance: rll error --reference-variance)\n",
                 var.string());
    }
  }
}

}  // namespace

void add_reference_command(CLI::App& app) {
  auto o = std::make_shared<ReferenceOptions>();
  auto* cmd = app.add_subcommand("reference",
                                 "Render a high-sample reference image, or reuse the cached one: "
                                 "the cache is keyed by the scene's content and the integrator "
                                 "settings, and holds references with at least --spp samples");
  add_session_options(cmd, o->session);
  cmd->add_option("--spp", o->request.spp,
                  "Samples per pixel (a cached reference with at least as many is reused)")
      ->capture_default_str()
      ->check(integer_in(1, kMaxSpp));
  cmd->add_option("--sampler", o->request.sampler, "Light sampler to render it with")
      ->capture_default_str();
  cmd->add_option("--seed", o->request.seed,
                  "Random seed (keep it apart from the seeds of compared renders)")
      ->capture_default_str()
      ->check(unsigned_integer());
  cmd->add_option("--pass-spp", o->request.pass_spp,
                  "Samples per pixel of the first passes; passes double every two passes up to "
                  "--max-pass-spp")
      ->capture_default_str()
      ->check(integer_in(1, kMaxPassSpp));
  cmd->add_option("--max-pass-spp", o->request.max_pass_spp, "Largest pass, in samples per pixel")
      ->capture_default_str()
      ->check(integer_in(1, kMaxSpp));
  cmd->add_option("--threads", o->threads, "Worker threads (0: all cores)")
      ->capture_default_str()
      ->check(integer_in(0, kMaxThreads));
  cmd->add_option("--cache-dir", o->cache_dir,
                  "Reference cache folder (default: $RLL_CACHE_DIR, else out/cache)");
  cmd->add_flag("--force", o->request.force, "Render even when the cache holds a reference");
  cmd->add_option(
      "-o,--output", o->output,
      "Also write the reference here, .exr (linear) or .png (sRGB), any case; beside an "
      ".exr, NAME.variance.exr holds its per-pixel variance (from its two halves)");
  cmd->add_option("--exposure", o->exposure, "Exposure in stops for a .png -o")
      ->capture_default_str()
      ->check(number_in(-kMaxExposure, kMaxExposure));
  cmd->add_flag("--quiet", o->quiet, "No progress bar");
  cmd->callback([o] { run(*o); });
}

}  // namespace rll::cli
