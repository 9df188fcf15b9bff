#include "rll/eval/compare.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>

#include "rll/core/error.h"
#include "rll/core/sysinfo.h"
#include "rll/eval/metrics.h"
#include "rll/session/session.h"

namespace rll {

double checkpoint_metric(const Checkpoint& c, const std::string& name) {
  return metric_by_name({c.mse, c.relmse, c.trimmed_relmse, c.mrse}, name);
}

ConvergenceRecorder::ConvergenceRecorder(const Image& reference, const Image* reference_variance,
                                         int per_decade)
    : m_reference(reference),
      m_variance(reference_variance),
      m_step(std::pow(10.0, 1.0 / std::max(1, per_decade))) {}

Checkpoint ConvergenceRecorder::measure(const RenderProgress& p, const Image& image) const {
  const ErrorMetrics m = error_metrics(image, m_reference, m_variance);
  return {p.seconds, p.spp_done, m.relmse, m.mse, m.trimmed_relmse, m.mrse};
}

void ConvergenceRecorder::after_pass(const RenderProgress& p, const Film& film) {
  if (p.seconds < m_next || p.spp_done < 1) return;
  m_checkpoints.push_back(measure(p, film.resolve()));
  m_last_pass = p.passes;
  m_next = p.seconds * m_step;
}

void ConvergenceRecorder::finish(const RenderProgress& p, const Image& image) {
  if (m_last_pass == p.passes && !m_checkpoints.empty()) m_checkpoints.pop_back();
  m_checkpoints.push_back(measure(p, image));
  m_last_pass = p.passes;
}

MeasuredRun measure_run(RenderSession& session, const std::string& name, int repeat,
                        const RenderSettings& settings, int frames, const Image& reference,
                        const Image* reference_variance, const std::string& label,
                        bool show_progress, const std::atomic<bool>* cancel,
                        const std::function<void(const RenderProgress&, const Film&)>& after_pass,
                        const std::vector<Aov>& aovs,
                        const std::vector<FrameReference>& frame_references) {
  if (!frame_references.empty() && frame_references.size() != size_t(frames))
    fail("measure_run: {} frame references for {} frames", frame_references.size(), frames);
  reset_peak_rss();
  MeasuredRun out;
  const auto t0 = std::chrono::steady_clock::now();
  auto sampler = session.make_sampler(name);
  const IntegratorSettings integrator = session.integrator_for(name);
  const double setup_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const Scene& scene = session.scene();
  RenderSettings rs = settings;
  for (int f = 0; f + 1 < frames; ++f) {
    session.set_frame(f, sampler.get());
    Film earlier(scene.width, scene.height);
    RenderSettings rf = rs;
    rf.frame = f;
    rf.follows_frame = f > 0;  // (the filter's temporal reuse blends the last frame's cells)
    rf.precedes_frame = true;
    const RenderProgress pf =
        session.render(*sampler, earlier, rf, fmt::format("{} frame {}", label, f + 1),
                       show_progress, cancel, after_pass, nullptr, &integrator);
    if (pf.cancelled || (cancel && cancel->load())) {
      out.cancelled = true;
      return out;
    }
    if (!frame_references.empty()) {
      const FrameReference& fr = frame_references[size_t(f)];
      ConvergenceRecorder frame_error(*fr.image, fr.variance);
      frame_error.finish(pf, earlier.resolve());
      out.result.frames.push_back({f, frame_error.checkpoints().back()});
    }
  }
  session.set_frame(frames - 1, sampler.get());
  rs.frame = frames - 1;
  rs.follows_frame = frames > 1;
  rs.precedes_frame = false;
  ConvergenceRecorder recorder(reference, reference_variance);
  Film film(scene.width, scene.height);
  if (!aovs.empty()) film.track_camera_vertex();
  const RenderProgress p = session.render(
      *sampler, film, rs, label, show_progress, cancel,
      [&](const RenderProgress& pr, const Film& f) {
        recorder.after_pass(pr, f);
        if (after_pass) after_pass(pr, f);
      },
      nullptr, &integrator);
  if (p.cancelled) {
    out.cancelled = true;
    return out;
  }
  out.image = film.resolve();
  recorder.finish(p, out.image);
  if (!aovs.empty()) out.aovs = resolve_aovs(film, *sampler, aovs);

  RunResult& run = out.result;
  run.sampler = name;
  run.repeat = repeat;
  run.seed = rs.seed;
  run.spp = p.spp_done;
  run.mean_spp = double(p.samples) / (double(scene.width) * double(scene.height));
  run.seconds = p.seconds;
  run.budget = rs.time_limit;
  run.setup_seconds = setup_seconds;
  run.checkpoints = recorder.checkpoints();
  const Checkpoint& last = run.checkpoints.back();
  run.relmse = last.relmse;
  run.mse = last.mse;
  run.trimmed_relmse = last.trimmed_relmse;
  run.mrse = last.mrse;
  run.visible_ratio = p.rays.visible_ratio();
  if (!frame_references.empty()) run.frames.push_back({frames - 1, last});
  run.describe = sampler->describe();
  if (run.describe.is_object() && run.describe.contains("bytes") &&
      run.describe["bytes"].is_number())
    run.sampler_bytes = run.describe["bytes"].get<double>();
  run.peak_rss_bytes = peak_rss_bytes();
  if (p.nonfinite)
    fmt::print(stderr, "rll: warning: {}: {} non-finite samples were dropped\n", name, p.nonfinite);
  out.sampler = std::move(sampler);
  return out;
}

std::optional<double> efficiency(double relmse, double seconds) {
  if (!(relmse > 0) || !(seconds > 0) || !std::isfinite(relmse)) return std::nullopt;
  return 1.0 / (relmse * seconds);
}

Spread spread_of(std::vector<double> values) {
  Spread s;
  s.values = values;
  if (values.empty()) return s;
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  s.median = n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
  s.min = values.front();
  s.max = values.back();
  return s;
}

std::vector<SamplerSummary> summarize(const std::vector<std::string>& samplers,
                                      const std::vector<RunResult>& runs) {
  if (samplers.empty()) fail("no samplers to summarize");
  std::map<std::string, std::map<int, const RunResult*>> by_sampler;
  for (const auto& r : runs) {
    if (std::find(samplers.begin(), samplers.end(), r.sampler) == samplers.end())
      fail("a run of sampler '{}', which is not among those compared", r.sampler);
    if (!by_sampler[r.sampler].emplace(r.repeat, &r).second)
      fail("sampler '{}' has two runs for repeat {}", r.sampler, r.repeat);
  }
  const auto& first = by_sampler[samplers[0]];
  std::vector<SamplerSummary> out;
  for (const auto& name : samplers) {
    const auto& mine = by_sampler[name];
    if (mine.size() != first.size() || mine.empty() ||
        !std::equal(mine.begin(), mine.end(), first.begin(),
                    [](const auto& a, const auto& b) { return a.first == b.first; }))
      fail("sampler '{}' was not run for the same repeats as '{}'", name, samplers[0]);
    SamplerSummary s;
    s.name = name;
    std::vector<double> spp, mean_spp, budget_ratio, seconds, setup, rel, trimmed, mrse_v, mse_v,
        eff, eff_setup, ratio, trimmed_ratio, visible;
    for (const auto& [repeat, run] : mine) {
      s.runs.push_back(run);
      spp.push_back(run->spp);
      mean_spp.push_back(run->mean_spp);
      if (run->budget > 0) budget_ratio.push_back(run->seconds / run->budget);
      seconds.push_back(run->seconds);
      setup.push_back(run->setup_seconds);
      rel.push_back(run->relmse);
      trimmed.push_back(run->trimmed_relmse);
      mrse_v.push_back(run->mrse);
      mse_v.push_back(run->mse);
      visible.push_back(run->visible_ratio);
      if (auto e = efficiency(run->relmse, run->seconds)) eff.push_back(*e);
      if (auto e = efficiency(run->relmse, run->seconds + run->setup_seconds))
        eff_setup.push_back(*e);
      const RunResult& base = *first.at(repeat);
      if (base.relmse > 0) ratio.push_back(run->relmse / base.relmse);
      if (base.trimmed_relmse > 0)
        trimmed_ratio.push_back(run->trimmed_relmse / base.trimmed_relmse);
      if (run->sampler_bytes)
        s.sampler_bytes = std::max(s.sampler_bytes.value_or(0.0), *run->sampler_bytes);
      s.peak_rss_bytes = std::max(s.peak_rss_bytes, run->peak_rss_bytes);
      if (s.describe.is_null()) s.describe = run->describe;
    }
    s.spp = spread_of(spp);
    s.mean_spp = spread_of(mean_spp);
    s.budget_ratio = spread_of(budget_ratio);
    s.seconds = spread_of(seconds);
    s.setup_seconds = spread_of(setup);
    s.relmse = spread_of(rel);
    s.trimmed_relmse = spread_of(trimmed);
    s.mrse = spread_of(mrse_v);
    s.mse = spread_of(mse_v);
    s.efficiency = spread_of(eff);
    s.efficiency_with_setup = spread_of(eff_setup);
    s.relmse_ratio = spread_of(ratio);
    s.trimmed_ratio = spread_of(trimmed_ratio);
    s.visible_ratio = spread_of(visible);
    // Per frame, over the repeats that measured it.
    size_t n_frames = 0;
    for (const RunResult* r : s.runs) n_frames = std::max(n_frames, r->frames.size());
    for (size_t f = 0; f < n_frames; ++f) {
      std::vector<double> fr, ft;
      for (const RunResult* r : s.runs)
        if (f < r->frames.size()) {
          fr.push_back(r->frames[f].error.relmse);
          ft.push_back(r->frames[f].error.trimmed_relmse);
        }
      s.frame_relmse.push_back(spread_of(fr));
      s.frame_trimmed.push_back(spread_of(ft));
    }
    out.push_back(std::move(s));
  }
  return out;
}

namespace {

nlohmann::json spread_json(const Spread& s) {
  if (s.values.empty()) return nullptr;  // undefined in every repeat (e.g. zero error)
  return {{"median", s.median}, {"min", s.min}, {"max", s.max}, {"values", s.values}};
}

std::string sci(double v) {
  return fmt::format("{:.3e}", v);
}

std::string with_range(const Spread& s, std::string (*f)(double)) {
  if (s.values.empty()) return "-";
  if (s.values.size() == 1) return f(s.median);
  return fmt::format("{} [{}, {}]", f(s.median), f(s.min), f(s.max));
}

// Rows of cells as aligned text: the first column left-aligned, the others right-aligned, a rule
// under the header row.
std::string format_rows(const std::vector<std::vector<std::string>>& rows) {
  std::vector<size_t> width(rows[0].size(), 0);
  for (const auto& row : rows)
    for (size_t c = 0; c < row.size(); ++c) width[c] = std::max(width[c], row[c].size());
  std::string out;
  for (size_t r = 0; r < rows.size(); ++r) {
    std::string line;
    for (size_t c = 0; c < rows[r].size(); ++c) {
      // The name left-aligned, numbers right-aligned.
      line += c == 0 ? fmt::format("{:<{}}", rows[r][c], width[c])
                     : fmt::format("  {:>{}}", rows[r][c], width[c]);
    }
    out += line + "\n";
    if (r == 0) out += std::string(line.size(), '-') + "\n";
  }
  return out;
}

}  // namespace

nlohmann::json sampler_summary_json(const SamplerSummary& s) {
  nlohmann::json j;
  j["name"] = s.name;
  j["sampler"] = s.describe;
  j["spp"] = spread_json(s.spp);
  j["mean_spp"] = spread_json(s.mean_spp);
  j["seconds"] = spread_json(s.seconds);
  j["seconds_per_budget"] = spread_json(s.budget_ratio);
  j["setup_seconds"] = spread_json(s.setup_seconds);
  j["relmse"] = spread_json(s.relmse);
  j["trimmed_relmse"] = spread_json(s.trimmed_relmse);
  j["mrse"] = spread_json(s.mrse);
  j["mse"] = spread_json(s.mse);
  j["efficiency"] = spread_json(s.efficiency);
  j["efficiency_with_setup"] = spread_json(s.efficiency_with_setup);
  j["relmse_ratio"] = spread_json(s.relmse_ratio);
  j["trimmed_ratio"] = spread_json(s.trimmed_ratio);
  j["visible_sample_ratio"] = spread_json(s.visible_ratio);
  j["memory"] = {{"sampler_bytes",
                  s.sampler_bytes ? nlohmann::json(*s.sampler_bytes) : nlohmann::json(nullptr)},
                 {"peak_rss_bytes", s.peak_rss_bytes}};
  nlohmann::json runs = nlohmann::json::array();
  for (const RunResult* r : s.runs) {
    nlohmann::json cps = nlohmann::json::array();
    for (const auto& c : r->checkpoints)
      cps.push_back({c.seconds, c.spp, c.relmse, c.trimmed_relmse, c.mrse, c.mse});
    runs.push_back({{"repeat", r->repeat},
                    {"seed", r->seed},
                    {"spp", r->spp},
                    {"mean_spp", r->mean_spp},
                    {"seconds", r->seconds},
                    {"budget", r->budget > 0 ? nlohmann::json(r->budget) : nlohmann::json()},
                    {"setup_seconds", r->setup_seconds},
                    {"relmse", r->relmse},
                    {"trimmed_relmse", r->trimmed_relmse},
                    {"mrse", r->mrse},
                    {"mse", r->mse},
                    {"visible_sample_ratio", r->visible_ratio},
                    {"checkpoints", std::move(cps)}});
    if (!r->frames.empty()) {
      nlohmann::json frames = nlohmann::json::array();
      for (const FrameError& f : r->frames)
        frames.push_back({f.frame, f.error.seconds, f.error.spp, f.error.relmse,
                          f.error.trimmed_relmse, f.error.mrse, f.error.mse});
      runs.back()["frames"] = std::move(frames);
    }
  }
  j["runs"] = std::move(runs);
  if (!s.frame_relmse.empty()) {
    nlohmann::json frames = nlohmann::json::array();
    for (size_t f = 0; f < s.frame_relmse.size(); ++f)
      frames.push_back({{"frame", f},
                        {"relmse", spread_json(s.frame_relmse[f])},
                        {"trimmed_relmse", spread_json(s.frame_trimmed[f])}});
    j["frames"] = std::move(frames);
    j["frame_fields"] = {"frame", "seconds", "spp", "relmse", "trimmed_relmse", "mrse", "mse"};
  }
  j["checkpoint_fields"] = {"seconds", "spp", "relmse", "trimmed_relmse", "mrse", "mse"};
  return j;
}

std::vector<std::string> budget_warnings(const std::vector<SamplerSummary>& summaries) {
  std::vector<std::string> out;
  for (const auto& s : summaries)
    for (const RunResult* r : s.runs)
      if (r->budget > 0 && std::abs(r->seconds / r->budget - 1) > kBudgetTolerance)
        out.push_back(fmt::format(
            "{} (repeat {}) took {:.3f} s of a {:g} s budget ({:+.1f}%, more than {:g}% off): its "
            "equal-time figures compare unequal times",
            s.name, r->repeat + 1, r->seconds, r->budget, 100 * (r->seconds / r->budget - 1),
            100 * kBudgetTolerance));
  return out;
}

std::string format_frame_table(const std::vector<SamplerSummary>& summaries) {
  size_t n_frames = 0;
  for (const auto& s : summaries) n_frames = std::max(n_frames, s.frame_relmse.size());
  if (n_frames == 0) return {};
  std::vector<std::vector<std::string>> rows;
  rows.push_back({"frame"});
  for (const auto& s : summaries) rows[0].push_back(s.name + " relMSE (trimmed)");
  for (size_t f = 0; f < n_frames; ++f) {
    rows.push_back({fmt::format("{}", f + 1)});
    for (const auto& s : summaries)
      rows.back().push_back(
          f < s.frame_relmse.size() && !s.frame_relmse[f].values.empty()
              ? fmt::format("{:.3e} ({:.3e})", s.frame_relmse[f].median, s.frame_trimmed[f].median)
              : std::string("-"));
  }
  return format_rows(rows);
}

std::vector<std::vector<std::string>> table_cells(const std::vector<SamplerSummary>& summaries) {
  std::vector<std::vector<std::string>> rows;
  rows.push_back({"sampler", "spp", "seconds", "setup s", "relMSE median [min, max]",
                  "trimmed relMSE", "MRSE", "ratio", "trimmed ratio", "efficiency",
                  "eff. with setup", "visible"});
  auto median = [](const Spread& s, const char* format) {
    return s.values.empty() ? std::string("-") : fmt::format(fmt::runtime(format), s.median);
  };
  for (const auto& s : summaries) {
    rows.push_back({s.name, median(s.mean_spp, "{:.4g}"), median(s.seconds, "{:.2f}"),
                    median(s.setup_seconds, "{:.2f}"), with_range(s.relmse, sci),
                    median(s.trimmed_relmse, "{:.3e}"), median(s.mrse, "{:.3e}"),
                    median(s.relmse_ratio, "{:.3f}"), median(s.trimmed_ratio, "{:.3f}"),
                    median(s.efficiency, "{:.4g}"), median(s.efficiency_with_setup, "{:.4g}"),
                    median(s.visible_ratio, "{:.3f}")});
  }
  return rows;
}

std::string format_table(const std::vector<SamplerSummary>& summaries) {
  return format_rows(table_cells(summaries));
}

}  // namespace rll
