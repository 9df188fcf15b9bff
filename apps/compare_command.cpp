// `rll compare`: renders a scene with several light samplers under one budget (equal time or
// equal spp), interleaving their runs, and measures each against a reference: summary.json,
// report.html, convergence.png, every image as .exr, and a table on stdout.
#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <fstream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "rll/core/error.h"
#include "rll/core/file_checks.h"
#include "rll/core/parallel.h"
#include "rll/core/paths.h"
#include "rll/core/sysinfo.h"
#include "rll/eval/cell_chart.h"
#include "rll/eval/compare.h"
#include "rll/eval/metrics.h"
#include "rll/eval/plot.h"
#include "rll/eval/raster.h"
#include "rll/eval/reference.h"
#include "rll/eval/report.h"
#include "rll/lights/light_sampler.h"
#include "rll/lights/oracle_sampler.h"
#include "rll/render/aov.h"
#include "rll/render/progress.h"

namespace rll::cli {
namespace fs = std::filesystem;

namespace {

struct CompareOptions {
  SessionSettings session;
  std::string samplers;
  double time = 0;
  int spp = 0;
  int repeats = 1;
  int frames = 1;
  bool every_frame = false;  // --every-frame: each frame measured against its own reference
  int pass_spp = 1;
  int max_pass_spp = 8;
  uint64_t seed = 1;
  int threads = 0;
  std::string reference;
  ReferenceRequest reference_request;
  std::string cache_dir;
  std::string out;
  float exposure = 0;
  std::string plot_metric = "relmse";
  std::string aov;  // --aov NAME[,NAME]: the first repeat's diagnostics, shown in the report
  bool quiet = false;
};

// A reference whose noise cannot be subtracted should have many more samples than the runs: its
// own noise adds to every sampler's measured error alike and squeezes the ratios towards 1.
constexpr double kReferenceSppFactor = 8;

std::vector<std::string> parse_sampler_list(const std::string& list) {
  std::vector<std::string> names;
  size_t start = 0;
  while (start <= list.size()) {
    size_t end = list.find(',', start);
    if (end == std::string::npos) end = list.size();
    std::string name = list.substr(start, end - start);
    name.erase(0, name.find_first_not_of(" \t"));
    name.erase(name.find_last_not_of(" \t") + 1);
    if (name.empty()) fail("--samplers '{}': empty sampler name", list);
    if (std::find(names.begin(), names.end(), name) != names.end())
      fail("--samplers '{}': '{}' is listed twice", list, name);
    names.push_back(name);
    start = end + 1;
  }
  return names;
}

// A sampler name as part of a file name.
std::string file_stem(const std::string& name) {
  std::string s = name;
  for (char& c : s)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_' && c != '.') c = '_';
  return s;
}

std::string image_name(const std::string& sampler, int repeat) {
  return repeat == 0 ? file_stem(sampler) + ".exr"
                     : fmt::format("{}.repeat{}.exr", file_stem(sampler), repeat + 1);
}

std::string budget_text(const CompareOptions& o) {
  return o.time > 0 ? fmt::format("equal time, {} s per run", o.time)
                    : fmt::format("equal samples, {} spp per run", o.spp);
}

bool reference_shares_a_run_seed(const CompareOptions& o, uint64_t s) {
  return reference_shares_a_seed(s, o.seed, o.repeats);
}

// Checks every flag that can be checked before the scene (perhaps slow to load) is read.
std::vector<std::string> check_flags(const CompareOptions& o) {
  parse_resolution(o.session.resolution);
  Params::parse(o.session.set);
  std::vector<std::string> samplers = parse_sampler_list(o.samplers);
  if ((o.time > 0) == (o.spp > 0))
    fail("give exactly one budget: --time SECONDS or --spp N (positive)");
  if (o.repeats < 1) fail("--repeats must be at least 1");
  if (o.frames < 1) fail("--frames must be at least 1");
  if (o.every_frame && !o.reference.empty())
    fail(
        "--every-frame measures each frame against its own reference, from the cache; "
        "--reference gives one image: leave one of them out");
  if (o.pass_spp < 1) fail("--pass-spp must be at least 1");
  if (o.max_pass_spp < 1) fail("--max-pass-spp must be at least 1");
  if (o.reference.empty() && o.reference_request.spp < 1)
    fail("--reference-spp must be at least 1");
  if (o.reference.empty() && reference_shares_a_run_seed(o, o.reference_request.seed))
    fail(
        "--reference-seed {} (and {}, its second half) overlaps the seeds of the runs (--seed {} "
        "with {} repeats): the reference would share their noise",
        o.reference_request.seed, o.reference_request.seed + 1, o.seed, o.repeats);
  metric_label(o.plot_metric);  // throws for an unknown name
  if (!o.aov.empty()) {
    parse_aovs(o.aov, "--aov");
    if (o.session.wavefront || o.session.device != "cpu")
      fail(
          "--aov: the diagnostics are measured by the megakernel; leave out --wavefront and "
          "--device");
  }
  if (o.out.empty()) fail("--out DIR is required");
  return samplers;
}

// Unknown sampler names and --set keys fail before any rendering. Samplers read their keys when
// made, so with --set each is made once here (a cost only then: an oracle's may be high).
void check_samplers(const CompareOptions& o, const RenderSession& session,
                    std::vector<std::string> needed) {
  const auto& known = light_sampler_names();
  auto check = [&](const std::string& name, const char* flag) {
    if (std::find(known.begin(), known.end(), name) == known.end() || !o.session.set.empty())
      make_sampler_for(session, name, flag);  // lists the valid names for an unknown one
  };
  for (const auto& name : needed) check(name, "--samplers");
  if (o.reference.empty()) check(o.reference_request.sampler, "--reference-sampler");
  session.check_params_used();
}

struct ChosenReference {
  Image image;
  Image variance;       // per pixel and channel; empty when unknown
  nlohmann::json json;  // for summary.json
  std::string caption;
};

// --reference, or the cache's reference, or a new one rendered into the cache.
// `frame`: the frame the session was moved to, for an animated scene (-1: a static one).
ChosenReference choose_reference(const CompareOptions& o, const RenderSession& session, int frame) {
  ChosenReference ref;
  const Scene& scene = session.scene();
  if (!o.reference.empty()) {
    ref.image = read_measured_image(o.reference, MeasuredRole::reference);
    if (ref.image.width() != scene.width || ref.image.height() != scene.height)
      fail("--reference {}: the image is {}x{} but the scene renders at {}x{}", o.reference,
           ref.image.width(), ref.image.height(), scene.width, scene.height);
    ref.json = {{"source", "file"}, {"path", o.reference}};
    ref.caption = o.reference;
    return ref;
  }
  ReferenceCache cache(o.cache_dir.empty() ? default_cache_dir() : fs::path(o.cache_dir));
  ReferenceRequest request = o.reference_request;
  request.pass_spp = o.pass_spp;
  request.max_pass_spp = o.max_pass_spp;
  request.seed_allowed = [&](uint64_t s) { return !reference_shares_a_run_seed(o, s); };
  request.frame = frame;
  ObtainedReference got = obtain_reference(session, cache, request, !o.quiet, interrupt_flag());
  if (!got.complete)
    throw Interrupted("interrupted while rendering the reference; nothing was written");
  fmt::print(stderr, "reference: {} {} ({} spp, sampler {})\n",
             got.from_cache ? "reused" : "rendered and cached", got.info.image.string(),
             got.info.spp, got.info.sampler);
  ref.image = std::move(got.image);
  check_measured_pixels(ref.image, got.info.image.string(), MeasuredRole::reference);
  ref.variance = std::move(got.variance);
  ref.json = reference_json(got.from_cache, got.info, ref.image, ref.variance);
  ref.caption = fmt::format("{} spp, {}", got.info.spp, got.info.sampler);
  if (ref.variance.pixel_count()) {
    const double noise = ref.json["noise_relmse"].get<double>();
    ref.caption += fmt::format(", its noise {:.2e} (relMSE) subtracted from every error", noise);
  } else {
    ref.caption += ", made without halves: its noise is not subtracted";
  }
  return ref;
}

std::string interrupted_text(const CompareOptions& o, const std::string& name) {
  return fmt::format(
      "interrupted during the run of '{}'; {} holds the reference and the images of the runs "
      "that finished, but no summary or report",
      name, o.out);
}

// One render of one sampler, fresh (a learning sampler starts cold every run), with relMSE
// checkpoints; the image is returned in `image`, and the sampler in `kept` and the --aov
// diagnostics in `aovs` when they are given.
RunResult run_once(const CompareOptions& o, RenderSession& session, const std::string& name,
                   int repeat, const ChosenReference& reference,
                   const std::vector<FrameReference>& frame_references, Image& image,
                   std::unique_ptr<LightSampler>* kept = nullptr,
                   std::vector<std::pair<std::string, std::vector<float>>>* aovs = nullptr) {
  RenderSettings rs;
  rs.spp = o.time > 0 ? kUnlimitedSpp : o.spp;
  rs.time_limit = o.time;
  rs.seed = o.seed + uint64_t(repeat);
  rs.pass_spp = o.pass_spp;
  rs.max_pass_spp = o.max_pass_spp;
  const std::string label =
      o.repeats > 1 ? fmt::format("{} ({}/{})", name, repeat + 1, o.repeats) : name;
  MeasuredRun m = measure_run(
      session, name, repeat, rs, o.frames, reference.image,
      reference.variance.pixel_count() ? &reference.variance : nullptr, label, !o.quiet,
      interrupt_flag(), {},
      aovs && !o.aov.empty() ? parse_aovs(o.aov, "--aov") : std::vector<Aov>(), frame_references);
  if (m.cancelled || interrupted()) throw Interrupted(interrupted_text(o, name));
  image = std::move(m.image);
  if (kept) *kept = std::move(m.sampler);
  if (aovs) *aovs = std::move(m.aovs);
  const RunResult& run = m.result;
  if (!o.quiet)
    fmt::print(stderr, "{}: {:.4g} spp in {}, relMSE {:.4e}\n", label, run.mean_spp,
               format_duration(run.seconds), run.relmse);
  return run;
}

// A plot of each sampler's runs, one curve per repeat: `points(run, metric)` gives a run's
// (x, metric) points.
template <typename Points>
LogLogPlot runs_plot(const std::vector<SamplerSummary>& summaries, const std::string& title,
                     const std::string& x_label, const std::string& metric, const Points& points) {
  LogLogPlot plot;
  plot.title = title;
  plot.x_label = x_label;
  plot.y_label = metric_label(metric);
  for (size_t i = 0; i < summaries.size(); ++i) {
    PlotSeries series{summaries[i].name, series_colour(i), {}};
    for (const RunResult* r : summaries[i].runs) series.curves.push_back(points(*r, metric));
    plot.series.push_back(std::move(series));
  }
  return plot;
}

LogLogPlot convergence_plot(const Scene& scene, const std::vector<SamplerSummary>& summaries,
                            const std::string& metric) {
  return runs_plot(summaries,
                   fmt::format("{} against render time ({})", metric_label(metric), scene.source),
                   "render time (s)", metric, [](const RunResult& r, const std::string& m) {
                     std::vector<std::pair<double, double>> curve;
                     for (const auto& c : r.checkpoints)
                       curve.emplace_back(c.seconds, checkpoint_metric(c, m));
                     return curve;
                   });
}

// --every-frame's plot: each sampler's error against the frame.
LogLogPlot frame_plot(const Scene& scene, const std::vector<SamplerSummary>& summaries,
                      const std::string& metric) {
  return runs_plot(summaries,
                   fmt::format("{} of each frame against its own reference ({})",
                               metric_label(metric), scene.source),
                   "frame", metric, [](const RunResult& r, const std::string& m) {
                     std::vector<std::pair<double, double>> curve;
                     for (const FrameError& f : r.frames)
                       curve.emplace_back(double(f.frame + 1), checkpoint_metric(f.error, m));
                     return curve;
                   });
}

std::string integrator_text(const IntegratorSettings& is) {
  return fmt::format(
      "{} (max depth {}, {}){}", integrator_name(is.type), is.max_depth, strategy_name(is.strategy),
      is.psf.on
          ? fmt::format(", path-space filtered (--filter psf: {})", filter_json(is.psf).dump())
          : "");
}

// Every file that compare writes into --out (a new file written there must be listed here: a
// later compare into the same folder removes exactly these).
std::vector<std::string> output_files(const CompareOptions& o,
                                      const std::vector<std::string>& samplers) {
  std::vector<std::string> files = {"reference.exr", "reference.variance.exr"};
  for (const auto& name : samplers) {
    for (int r = 0; r < o.repeats; ++r) files.push_back(image_name(name, r));
    files.push_back(file_stem(name) + ".error.exr");
  }
  for (const char* f : {"side-by-side.png", "convergence.png", "report.html", "summary.json"})
    files.push_back(f);
  return files;
}

// Refuses outputs that are inputs, removes the files an earlier compare listed in the folder's
// summary.json (its samplers' images would otherwise sit beside the new report; nothing else is
// ever removed), then lists this compare's files there, so that an interrupted one is cleared
// as well.
void prepare_folder(const CompareOptions& o, const std::vector<std::string>& samplers) {
  const fs::path out(o.out);
  std::vector<fs::path> inputs = scene_inputs(o.session.scene);
  if (!o.reference.empty()) inputs.push_back(o.reference);
  const std::vector<std::string> files = output_files(o, samplers);
  for (const auto& f : files) {
    check_output_file(out / f, "--out");
    refuse_input(out / f, "--out", inputs);
  }
  std::error_code ec;
  if (fs::is_regular_file(out / "summary.json", ec)) {
    std::ifstream in(out / "summary.json");
    const nlohmann::json old = nlohmann::json::parse(in, nullptr, false);
    if (old.is_object() && old.contains("outputs") && old["outputs"].is_array())
      for (const auto& f : old["outputs"]) {
        if (!f.is_string()) continue;
        const std::string name = f.get<std::string>();
        const fs::path p = out / name;
        const std::string ext = fs::path(name).extension().string();
        const bool ours = fs::path(name).filename() == name && name[0] != '.' &&
                          (ext == ".exr" || ext == ".png" || ext == ".html" || ext == ".json");
        bool is_input = false;
        for (const auto& in : inputs) is_input = is_input || same_file(p, in);
        if (ours && !is_input && fs::is_regular_file(p, ec)) fs::remove(p, ec);
      }
  }
  write_file_atomic(out / "summary.json",
                    nlohmann::json{{"complete", false}, {"outputs", files}}.dump(2) + "\n");
}

void run(const CompareOptions& o) {
  install_interrupt_handler();
  ThreadLimit limit(o.threads);
  const std::vector<std::string> samplers = check_flags(o);
  prepare_output_dir(o.out, "--out");
  const fs::path out(o.out);
  scene_inputs(o.session.scene);  // refuses a scene, or a file it names, that is no file
  set_activity(fmt::format("loading scene '{}'", o.session.scene));
  RenderSession session(o.session);
  const Scene& scene = session.scene();
  // Per pixel, a run's film and image, the reference and its variance, and for each sampler its
  // first image, its error map and its tile of the side-by-side figure (with --aov, its
  // diagnostics too): the whole of it is checked before the first film is allocated.
  // (--every-frame keeps every frame's reference and variance.)
  session.check_film_memory(
      kRenderBytesPerPixel + 2 * 3 * 4 * (o.every_frame ? o.frames : 1) +
          double(samplers.size()) *
              (3 * 4 + 4 + 4 + (o.aov.empty() ? 0 : kCameraVertexBytesPerPixel)),
      "a run's film and image, the reference and its variance, and each sampler's image, error "
      "map and figure");
  set_activity("making the samplers");
  check_samplers(o, session, samplers);

  // Only now, when every check has passed, may an earlier compare's files go.
  prepare_folder(o, samplers);
  set_activity(
      fmt::format("comparing {} samplers at {}x{}", samplers.size(), scene.width, scene.height));
  begin_work();
  // The measured frame's reference (the last frame's), and with --every-frame every frame's, each
  // with the scene moved to its frame (a moved light changes the scene's cache key).
  std::vector<ChosenReference> frame_refs;
  for (int f = o.every_frame ? 0 : o.frames - 1; f < o.frames; ++f) {
    session.set_frame(f, nullptr);
    if (o.every_frame) fmt::print(stderr, "frame {} of {}: ", f + 1, o.frames);
    frame_refs.push_back(choose_reference(o, session, scene.animate ? f : -1));
  }
  const ChosenReference& ref = frame_refs.back();
  std::vector<FrameReference> frame_references;
  if (o.every_frame)
    for (const ChosenReference& r : frame_refs)
      frame_references.push_back({&r.image, r.variance.pixel_count() ? &r.variance : nullptr});
  write_image(out / "reference.exr", ref.image);
  // The reference's per-pixel variance, so that the errors can be recomputed from the files.
  if (ref.variance.pixel_count()) write_image(out / "reference.variance.exr", ref.variance);

  // Repeat by repeat, every sampler once, starting one further along each repeat so that no
  // sampler always runs first (on a cold cache) or last (on a machine warmed by the others).
  std::vector<RunResult> runs;
  std::map<std::string, Image> first_images;  // repeat 0's, shown in the report
  std::map<std::string, std::vector<std::pair<std::string, std::vector<float>>>> first_aovs;
  // Repeat 0's learning samplers (rll, fermat) and oracle, for the report's cell chart.
  std::map<std::string, std::unique_ptr<LightSampler>> charted;
  const OracleLightSampler* oracle = nullptr;
  nlohmann::json order = nlohmann::json::array();
  const int n = int(samplers.size());
  for (int r = 0; r < o.repeats; ++r) {
    order.push_back(nlohmann::json::array());
    for (int k = 0; k < n; ++k) {
      const std::string& name = samplers[size_t((k + r) % n)];
      order.back().push_back(name);
      Image image;
      std::unique_ptr<LightSampler> sampler;
      std::vector<std::pair<std::string, std::vector<float>>> aovs;
      runs.push_back(run_once(o, session, name, r, ref, frame_references, image,
                              r == 0 ? &sampler : nullptr, r == 0 ? &aovs : nullptr));
      if (!aovs.empty()) first_aovs.emplace(name, std::move(aovs));
      if (sampler && sampler->learnt_cells().oracle) oracle = sampler->learnt_cells().oracle;
      if (sampler && sampler->learnt_cells().rll) charted.emplace(name, std::move(sampler));
      write_image(out / image_name(name, r), image);
      if (r == 0) first_images.emplace(name, std::move(image));
    }
  }
  const std::vector<SamplerSummary> summaries = summarize(samplers, runs);

  std::vector<std::string> warnings;
  if (ref.json.contains("noise_relmse")) {
    // Subtracted, the reference's noise leaves the errors unbiased; where it is larger than a
    // sampler's own error, that error is a small difference of large numbers.
    double least = std::numeric_limits<double>::infinity();
    for (const auto& s : summaries) least = std::min(least, s.relmse.median);
    const double noise = ref.json["noise_relmse"].get<double>();
    if (noise > least)
      warnings.push_back(fmt::format(
          "The reference's own noise (relMSE {:.2e}, subtracted) exceeds the smallest measured "
          "error ({:.2e}): those errors are uncertain; use a larger --reference-spp.",
          noise, least));
  } else if (ref.json.contains("spp")) {
    double most = 0;
    for (const auto& s : summaries) most = std::max(most, s.spp.max);
    if (ref.json["spp"].get<double>() < kReferenceSppFactor * most)
      warnings.push_back(fmt::format(
          "The reference has {} spp, fewer than {}x the {} spp of the longest run: its noise "
          "inflates every error alike and pulls the ratios towards 1 (use --reference-spp).",
          ref.json["spp"].get<int>(), kReferenceSppFactor, most));
  }
  if (!figures_built())
    warnings.push_back(
        "this rll was built without librsvg and pango (-DRLL_FIGURES=OFF): side-by-side.png and "
        "convergence.png are not written; report.html has every figure");
  for (const auto& w : warnings) fmt::print(stderr, "rll: warning: {}\n", w);

  std::map<std::string, std::vector<float>> errors;
  for (const auto& name : samplers) {
    errors[name] = relative_error_map(first_images.at(name), ref.image);
    write_image(out / (file_stem(name) + ".error.exr"),
                grey_image(errors[name], scene.width, scene.height));
  }
  std::vector<const Image*> row;
  std::vector<std::string> captions;
  for (const auto& s : summaries) {
    const RunResult& first = *s.runs.front();
    row.push_back(&first_images.at(s.name));
    captions.push_back(fmt::format("{}\nrelMSE {:.3e}, trimmed {:.3e}\n{} spp, {}, visible {:.3f}",
                                   s.name, first.relmse, first.trimmed_relmse, first.spp,
                                   format_duration(first.seconds), first.visible_ratio));
  }
  row.push_back(&ref.image);
  captions.push_back("reference\n" + ref.caption);
  if (figures_built())
    write_file_atomic(out / "side-by-side.png", side_by_side_png(row, captions, o.exposure));
  LogLogPlot plot = convergence_plot(scene, summaries, o.plot_metric);
  if (figures_built()) write_file_atomic(out / "convergence.png", plot_png(plot));

  Report report;
  report.title = fmt::format("rll compare: {}", scene.source);
  report.facts = {
      {"scene", fmt::format("{} ({}x{}, {} lights)", scene.source, scene.width, scene.height,
                            scene.lights.size())},
      {"integrator", integrator_text(session.integrator())},
      {"budget", budget_text(o)},
      {"repeats", o.repeats == 1 ? fmt::format("1 (seed {})", o.seed)
                                 : fmt::format("{} (seeds {}..{}), runs interleaved", o.repeats,
                                               o.seed, o.seed + o.repeats - 1)},
      {"threads", fmt::format("{}", o.threads > 0 ? o.threads : hardware_threads())},
      {"machine", machine_description()},
      {"commit", build_commit()},
      {"reference", ref.caption},
      {"metrics",
       fmt::format(
           "means over pixels and channels: relMSE of (x - ref)^2 / (ref^2 + 0.01); trimmed relMSE "
           "the same without the worst 0.1% of pixels; MRSE of (x - ref)^2 / (ref + 0.01)^2; MSE "
           "of (x - ref)^2; {}. Efficiency = 1 / (relMSE x seconds), with setup: x (seconds + "
           "setup); ratios are to the first sampler's, per repeat",
           ref.variance.pixel_count()
               ? "each with the reference's own variance, estimated from its two halves, "
                 "subtracted from every squared difference"
               : "the reference's noise is NOT subtracted (it has no halves)")}};
  report.warnings = warnings;
  report.reference = &ref.image;
  report.reference_caption = ref.caption;
  for (size_t i = 0; i < summaries.size(); ++i) {
    const auto& s = summaries[i];
    const RunResult& first = *s.runs.front();
    report.entries.push_back(
        {s.name,
         fmt::format("relMSE {:.3e}, {} spp, {}, visible-sample ratio {:.3f}", first.relmse,
                     first.spp, format_duration(first.seconds), first.visible_ratio),
         series_colour(i), &first_images.at(s.name), &errors.at(s.name),
         fmt::format("repeat 1 of {}, seed {}", o.repeats, o.seed),
         first_aovs.contains(s.name) ? &first_aovs.at(s.name) : nullptr});
    report.samplers.push_back({s.name,
                               s.describe.is_object() && s.describe.contains("parameters")
                                   ? s.describe["parameters"].dump(2)
                                   : std::string("(no parameters)"),
                               s.setup_seconds.median, s.seconds.median});
  }
  report.table = table_cells(summaries);
  report.exposure = o.exposure;
  report.plot_svg = plot_svg(plot);
  if (o.every_frame) report.frame_plot_svg = plot_svg(frame_plot(scene, summaries, o.plot_metric));
  for (const auto& name : samplers) {
    const auto it = charted.find(name);
    if (it == charted.end()) continue;
    // The oracle's cells are charted as its bars beside a learner's, not as a chart of their own.
    const LearntCells& cells = it->second->learnt_cells();
    if (cells.rll && !cells.oracle)
      report.cell_charts.push_back(
          cell_chart(scene, session.accel(), session.integrator(), *cells.rll, name, oracle));
  }
  write_file_atomic(out / "report.html", report_html(report));

  nlohmann::json j = session_stats(session);
  j["lights"] = scene.lights.size();
  j["budget"] = o.time > 0 ? nlohmann::json{{"time", o.time}} : nlohmann::json{{"spp", o.spp}};
  j["frames"] = o.frames;
  if (o.every_frame) {
    // Every frame's reference, frame 0 first (the last is "reference").
    j["frame_references"] = nlohmann::json::array();
    for (const ChosenReference& r : frame_refs) j["frame_references"].push_back(r.json);
  }
  j["repeats"] = o.repeats;
  j["seed"] = o.seed;
  j["pass_spp"] = {{"first", o.pass_spp}, {"max", o.max_pass_spp}};
  j["threads"] = o.threads > 0 ? o.threads : hardware_threads();
  j["set"] = o.session.set;
  if (!o.aov.empty()) j["aov"] = o.aov;  // the first repeat's diagnostics, in report.html
  j["reference"] = ref.json;
  j["reference"]["image"] = "reference.exr";
  if (ref.variance.pixel_count()) j["reference"]["variance_image"] = "reference.variance.exr";
  j["metric_notes"] =
      ref.variance.pixel_count()
          ? "errors have the reference's own variance (reference.variance.exr, from its two "
            "halves) subtracted from every squared difference"
          : "errors include the reference's own noise (it has no halves)";
  j["order"] = order;
  j["warnings"] = warnings;
  j["samplers"] = nlohmann::json::array();
  for (const auto& s : summaries) {
    nlohmann::json sj = sampler_summary_json(s);
    sj["image"] = image_name(s.name, 0);
    sj["error_image"] = file_stem(s.name) + ".error.exr";
    j["samplers"].push_back(std::move(sj));
  }
  j["files"] = {{"report", "report.html"}};
  if (figures_built()) {
    j["files"]["convergence"] = "convergence.png";
    j["files"]["side_by_side"] = "side-by-side.png";
  }
  j["outputs"] = output_files(o, samplers);
  write_file_atomic(out / "summary.json", j.dump(2) + "\n");

  fmt::print("{}", format_table(summaries));
  if (o.every_frame)
    fmt::print("\nrelMSE of each frame (median over repeats):\n{}", format_frame_table(summaries));
  for (const auto& w : budget_warnings(summaries)) fmt::print(stderr, "rll: warning: {}\n", w);
  fmt::print("report: {}\n", (out / "report.html").string());
}

}  // namespace

void add_compare_command(CLI::App& app) {
  auto o = std::make_shared<CompareOptions>();
  auto* cmd =
      app.add_subcommand("compare",
                         "Render a scene with several light samplers under the same budget and "
                         "measure them against a reference (writes summary.json, report.html, "
                         "convergence.png, side-by-side.png and every image as .exr into --out)");
  add_session_options(cmd, o->session);
  add_wavefront_option(cmd, o->session);
  std::string all;
  for (const auto& n : light_sampler_names()) all += (all.empty() ? "" : ",") + n;
  o->samplers = all;
  cmd->add_option("--samplers", o->samplers,
                  "Comma-separated light samplers; ratios are to the first")
      ->capture_default_str();
  auto* time = cmd->add_option("--time", o->time,
                               "Equal time: seconds per run (positive; every run takes at least "
                               "one sample per pixel; the last passes are sized from the "
                               "measured rate to end at the budget, and a run more than 3% off "
                               "it is warned about)");
  auto* spp = cmd->add_option("--spp", o->spp, "Equal samples: samples per pixel per run");
  time->excludes(spp);
  cmd->add_option(
         "--frames", o->frames,
         "Frames per run (animated scenes): each frame gets the budget, learning carries over, "
         "the last frame is measured (every frame with --every-frame)")
      ->capture_default_str();
  cmd->add_flag("--every-frame", o->every_frame,
                "Measure every frame of a run against that frame's own reference (each taken from "
                "the cache or rendered into it, as the last frame's): summary.json's per-run and "
                "per-sampler `frames`, a table of relMSE per frame and a plot of error against "
                "frame in report.html");
  cmd->add_option("--repeats", o->repeats, "Runs per sampler; reported as median and range")
      ->capture_default_str();
  cmd->add_option("--pass-spp", o->pass_spp,
                  "Samples per pixel of the first passes; passes double every two passes up to "
                  "--max-pass-spp (learning samplers adapt between passes)")
      ->capture_default_str();
  cmd->add_option("--max-pass-spp", o->max_pass_spp, "Largest pass, in samples per pixel")
      ->capture_default_str();
  cmd->add_option("--seed", o->seed, "Seed of the first repeat; repeat r uses seed + r")
      ->capture_default_str();
  cmd->add_option("--threads", o->threads, "Worker threads (0: all cores)")->capture_default_str();
  auto* ref =
      cmd->add_option("--reference", o->reference, "Reference image (.exr) instead of the cache");
  cmd->add_option("--reference-spp", o->reference_request.spp,
                  "Samples per pixel of the reference: a cached one with at least as many is "
                  "reused, otherwise one is rendered and cached")
      ->capture_default_str()
      ->excludes(ref);
  cmd->add_option("--reference-sampler", o->reference_request.sampler,
                  "Light sampler that renders the reference")
      ->capture_default_str()
      ->excludes(ref);
  cmd->add_option("--reference-seed", o->reference_request.seed, "Seed of the reference render")
      ->capture_default_str()
      ->excludes(ref);
  cmd->add_option("--cache-dir", o->cache_dir,
                  "Reference cache folder (default: $RLL_CACHE_DIR, else out/cache)");
  cmd->add_option("--out", o->out,
                  "Output folder; the files an earlier compare wrote there (listed in its "
                  "summary.json) are removed first, nothing else")
      ->required();
  cmd->add_option("--exposure", o->exposure, "Initial exposure of the report's images, in stops")
      ->capture_default_str();
  cmd->add_option("--plot-metric", o->plot_metric,
                  "Metric of the convergence plot: relmse, trimmed_relmse, mrse or mse")
      ->capture_default_str();
  std::string aov_help =
      "Per-pixel diagnostics of the first repeat's run of every sampler, measured at the camera "
      "vertex as `rll render --aov` measures them and shown in report.html beside the error maps "
      "(flippable with the reference like them; the image is the same to the bit, that run's time "
      "includes the measuring: leave --aov out when timing); a comma-separated list of:";
  for (const auto& a : aov_list()) aov_help += fmt::format(" {} ({});", a.name, a.meaning);
  cmd->add_option("--aov", o->aov, aov_help);
  cmd->add_flag("--quiet", o->quiet, "No progress output");
  // Numbers are checked as every command checks them (commands.h).
  time->check(number_in(0, kMaxSeconds, true));
  spp->check(integer_in(1, kMaxSpp));
  cmd->get_option("--frames")->check(integer_in(1, kMaxFrames));
  cmd->get_option("--repeats")->check(integer_in(1, 10000));
  cmd->get_option("--pass-spp")->check(integer_in(1, kMaxPassSpp));
  cmd->get_option("--max-pass-spp")->check(integer_in(1, kMaxSpp));
  cmd->get_option("--seed")->check(unsigned_integer());
  cmd->get_option("--threads")->check(integer_in(0, kMaxThreads));
  cmd->get_option("--reference-spp")->check(integer_in(1, kMaxSpp));
  cmd->get_option("--reference-seed")->check(unsigned_integer());
  cmd->get_option("--exposure")->check(number_in(-kMaxExposure, kMaxExposure));
  cmd->callback([o] { run(*o); });
}

}  // namespace rll::cli
