// The measuring side of `rll compare`: relMSE checkpoints while a render runs, per-run results,
// their median and spread over repeats, summary.json and the printed table.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "rll/core/image.h"
#include "rll/lights/light_sampler.h"
#include "rll/render/aov.h"
#include "rll/render/film.h"
#include "rll/render/render.h"

namespace rll {

struct Checkpoint {
  double seconds = 0;  // render time so far, metric time excluded
  int spp = 0;
  double relmse = 0, mse = 0, trimmed_relmse = 0, mrse = 0;
};
// The checkpoint's metric by its name in kMetricNames (metrics.h).
double checkpoint_metric(const Checkpoint& c, const std::string& name);

// Takes checkpoints of the error of a film against a reference at render times spaced
// logarithmically (a fixed number per decade), for the convergence curve. With
// `reference_variance`, the reference's noise is subtracted (error_metrics in metrics.h).
class ConvergenceRecorder {
 public:
  ConvergenceRecorder(const Image& reference, const Image* reference_variance = nullptr,
                      int per_decade = 6);
  // To be called after every pass (render()'s after_pass): takes a checkpoint when due.
  void after_pass(const RenderProgress& progress, const Film& film);
  // The final state, always recorded (replaces a checkpoint taken at the same pass).
  void finish(const RenderProgress& progress, const Image& image);
  const std::vector<Checkpoint>& checkpoints() const { return m_checkpoints; }

 private:
  Checkpoint measure(const RenderProgress& p, const Image& image) const;
  const Image& m_reference;
  const Image* m_variance;
  double m_step;  // ratio between successive checkpoint times
  double m_next = 0;
  int m_last_pass = -1;
  std::vector<Checkpoint> m_checkpoints;
};

// The error of one frame of a run against that frame's own reference (compare --every-frame):
// the frame's final state, as a Checkpoint, and its frame number (0 first).
struct FrameError {
  int frame = 0;
  Checkpoint error;
};

// One render of one sampler.
struct RunResult {
  std::string sampler;
  int repeat = 0;
  uint64_t seed = 0;
  int spp = 0;               // complete samples per pixel (every pixel has at least this many)
  double mean_spp = 0;       // samples per pixel taken, on average (a pass cut at a budget counts)
  double seconds = 0;        // rendering, learning included
  double budget = 0;         // the time budget in seconds, 0 for none
  double setup_seconds = 0;  // making the sampler (e.g. an oracle's estimates), not in `seconds`
  // Errors of the final image (metrics.h), the reference's noise subtracted when it is known.
  double relmse = 0, mse = 0, trimmed_relmse = 0, mrse = 0;
  // The share of light samples whose shadow ray reached the light (RayCounters::visible_ratio).
  double visible_ratio = 0;
  std::optional<double> sampler_bytes;  // the sampler's describe()["bytes"], when it reports one
  size_t peak_rss_bytes = 0;            // of the whole process, after this run
  nlohmann::json describe;              // the sampler's describe()
  std::vector<Checkpoint> checkpoints;
  // Every frame's error against its own reference, in frame order (the last is the run's own
  // final error); empty unless the run measured every frame.
  std::vector<FrameError> frames;
};

class RenderSession;

// The references of the frames of an animated run, frame 0 first, each with its variance or
// null (compare --every-frame): measure_run measures every frame against its own.
struct FrameReference {
  const Image* image = nullptr;
  const Image* variance = nullptr;
};

// One measured run of `rll compare` (and rll.compare in Python): a fresh sampler `name` (its
// making timed as setup), the frames before `frames - 1` rendered with the same budget so that a
// learning sampler carries what it learnt, then the last frame rendered with relMSE checkpoints
// against `reference` (its noise subtracted with `reference_variance`). Cancelled (`cancelled`
// set, no result) when `cancel` is raised during any frame. With `aovs`, the last frame's film
// keeps its camera vertices and `aovs` of the result holds those diagnostics (render/aov.h), as
// `rll render --aov` measures them: the image is the same to the bit, the time includes the
// measuring. With `frame_references` (one per frame, the last being `reference`), every frame's
// error against its own reference goes to RunResult::frames (the measuring is not timed).
struct MeasuredRun {
  RunResult result;
  Image image;
  std::unique_ptr<LightSampler> sampler;  // as the run left it (what it learnt)
  std::vector<std::pair<std::string, std::vector<float>>> aovs;  // resolve_aovs' channels
  bool cancelled = false;
};
MeasuredRun measure_run(
    RenderSession& session, const std::string& name, int repeat, const RenderSettings& settings,
    int frames, const Image& reference, const Image* reference_variance, const std::string& label,
    bool show_progress, const std::atomic<bool>* cancel,
    const std::function<void(const RenderProgress&, const Film&)>& after_pass = {},
    const std::vector<Aov>& aovs = {}, const std::vector<FrameReference>& frame_references = {});

// 1 / (relMSE x seconds); nullopt where undefined (zero error or zero time).
std::optional<double> efficiency(double relmse, double seconds);

// Median and range of one quantity over repeats.
struct Spread {
  double median = 0, min = 0, max = 0;
  std::vector<double> values;  // in repeat order
};
// Median (mean of the middle two for an even count), min and max; all 0 for no values.
Spread spread_of(std::vector<double> values);

struct SamplerSummary {
  std::string name;
  Spread spp, mean_spp, seconds, setup_seconds, relmse, trimmed_relmse, mrse, mse;
  // Seconds over the time budget, per run (empty without a budget): equal time is as equal as
  // these are close to 1.
  Spread budget_ratio;
  // 1 / (relMSE x seconds), over the render's seconds alone and over render and setup together
  // (an oracle's precomputation can take far longer than its render).
  Spread efficiency, efficiency_with_setup;
  // Per repeat, relMSE (trimmed relMSE) over the first sampler's in the same repeat: ratios taken
  // within one repeat cancel machine noise that hits all samplers of that repeat alike.
  Spread relmse_ratio, trimmed_ratio;
  Spread visible_ratio;  // RunResult::visible_ratio
  // Per frame (RunResult::frames, where the runs measured every frame): relMSE and trimmed
  // relMSE over repeats.
  std::vector<Spread> frame_relmse, frame_trimmed;
  std::optional<double> sampler_bytes;  // largest over repeats
  size_t peak_rss_bytes = 0;            // largest over repeats
  nlohmann::json describe;
  std::vector<const RunResult*> runs;  // in repeat order, pointing into the results given
};

// Groups runs by sampler (in `samplers` order) and reduces them over repeats. Every sampler
// must have the same repeats; throws rll::Error otherwise.
std::vector<SamplerSummary> summarize(const std::vector<std::string>& samplers,
                                      const std::vector<RunResult>& runs);

// How far a run's seconds may be from its time budget before compare warns that the times it
// compares are not equal (issue 45's goal: every run within 3% of the budget).
inline constexpr double kBudgetTolerance = 0.03;
// A warning for each run whose seconds are off its time budget by more than kBudgetTolerance
// (none without a budget).
std::vector<std::string> budget_warnings(const std::vector<SamplerSummary>& summaries);

// The per-sampler part of summary.json.
nlohmann::json sampler_summary_json(const SamplerSummary& s);

// The table printed at the end of a compare: sampler, spp (the mean samples per pixel taken),
// seconds, setup seconds, relMSE median [min-max], trimmed relMSE, MRSE, both ratios to the first
// sampler, efficiency without and with setup time, the visible-sample ratio.
std::string format_table(const std::vector<SamplerSummary>& summaries);
// The per-frame table of a compare that measured every frame: one row per frame, one column per
// sampler holding its median relMSE (and trimmed relMSE); empty where no run measured frames.
std::string format_frame_table(const std::vector<SamplerSummary>& summaries);
// The same table as rows of cells (header first), for the HTML report.
std::vector<std::vector<std::string>> table_cells(const std::vector<SamplerSummary>& summaries);

}  // namespace rll
