// The pass loop: renders the image in passes of a few samples per pixel over parallel tiles,
// lets a learning sampler adapt between passes, and stops at a sample count, a time budget or
// a cancel request, whichever comes first.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>

#include "rll/core/rng.h"
#include "rll/render/film.h"
#include "rll/render/integrator.h"
#include "rll/render/psf.h"

namespace rll {

// An spp target that is never reached: renders that only a time budget stops.
inline constexpr int kUnlimitedSpp = 1 << 30;

struct RenderSettings {
  int spp = 16;           // samples per pixel to reach (upper limit), or kUnlimitedSpp
  double time_limit = 0;  // seconds; 0 = none
  uint64_t seed = 1;
  // The sample index of the film's first sample: a share of a render split by samples
  // (--task) renders indices [first_sample, first_sample + spp) of each pixel.
  uint64_t first_sample = 0;
  // Pass sizes in samples per pixel: pass_spp for the first two passes, then doubling every
  // two passes up to max_pass_spp (learning samplers adapt fast at first, then the end-of-pass
  // work is spread over more samples).
  int pass_spp = 1;
  int max_pass_spp = 8;
  int tile_size = 16;
  int frame = 0;  // animation frame (enters the random seed)
  // This render is the frame after the last one rendered with the same PsfHistory (an animation's
  // next frame, interactive's next sample of a still scene): path-space filtering's temporal
  // reuse (psf.temporal) blends the cells that render left. False (a first frame, a still
  // render): the render's samples blend nothing, and leave their cells for the next frame.
  bool follows_frame = false;
  // A frame follows this render (an animation's frames but the last, interactive's frames but
  // the last): the session keeps temporal reuse's cells for it (RenderSession::render). Without
  // one and without follows_frame, a render with psf.temporal allocates no second table.
  bool precedes_frame = false;
  PointSet points = PointSet::Sobol;  // the sample points (--points)
};

// Whether a render takes the filter's temporal reuse's second table of cells (psf.temporal): only
// where a frame came before it or comes after it; a still render blends nothing and keeps no
// cells for a next frame. The session's (CPU) and the GPU renderer's one rule.
inline bool psf_temporal_frames(const PsfSettings& psf, const RenderSettings& rs) {
  return psf.on && psf.temporal > 0 && (rs.follows_frame || rs.precedes_frame);
}

struct RenderProgress {
  int passes = 0;
  int spp_done = 0;  // complete samples per pixel (every pixel has at least this many)
  int spp_target = 0;
  double seconds = 0;
  double time_limit = 0;
  uint64_t samples = 0;    // camera samples taken
  uint64_t nonfinite = 0;  // samples that came out NaN/inf and were dropped
  RayCounters rays;
  PsfCounts filter;        // path-space filtering's batches, cells and cut paths (render/psf.h)
  bool cancelled = false;  // stopped by the cancel flag
  bool out_of_time = false;
};

// Whether a pass should stop taking samples: the cancel flag is set or the time budget is spent.
// Once true it stays true for the rest of the render; safe to ask from many threads.
class PassStop {
 public:
  PassStop(const std::atomic<bool>* cancel, double time_limit,
           const std::chrono::steady_clock::time_point& t0)
      : m_cancel(cancel), m_time_limit(time_limit), m_t0(t0) {}
  bool operator()() const;
  bool stopped() const { return m_stop.load(); }
  // Seconds kept back from the time budget for the end of pass that follows a stopped pass, so
  // that the render, that end of pass included, ends at the budget. Set between passes.
  void reserve(double seconds) const { m_reserve.store(seconds, std::memory_order_relaxed); }

 private:
  const std::atomic<bool>* m_cancel;
  double m_time_limit;
  mutable std::atomic<double> m_reserve{0};
  const std::chrono::steady_clock::time_point&
      m_t0;  // moves on while the caller's time is excluded
  mutable std::atomic<bool> m_stop{false};
};

// The samples per pixel of the next pass under a time budget: the pass schedule's `size`, fewer
// where `left` seconds of the budget (its end of pass's expected time taken off) hold fewer at
// the last pass's `seconds_per_spp`; at least 1 (a pass that then runs into the budget is cut
// there). Sized so, a time-budgeted render ends at its budget on a pass boundary instead of
// cutting a large pass part way, which leaves the pixels the cut did not reach a pass's samples
// fewer than the rest (issue 45: equal time that is equal).
int pass_size_for_budget(int size, double left, double seconds_per_spp);

// What one pass of a renderer does: takes samples [first, first + count) of every pixel into the
// film, each as the seeded stream of (frame_seed, pixel, settings.first_sample + sample) gives
// them, checking `stop` often enough to end soon after it turns true (within a pass: every 64
// samples of a tile in the megakernel, every batch of path slots in the wavefront), and adds up
// its rays, dropped non-finite samples and the filter's counts. A stopped pass leaves each pixel
// its first n samples of the pass, n possibly 0; the film counts them. With path-space filtering
// (render/psf.h) a pass is a batch per sample index: each sample of every pixel is traced, then
// its cut paths get their cells' means, before the next sample's (so that a pass's size changes
// no filtered image).
using PassWork = std::function<void(int first, int count, uint64_t frame_seed, const PassStop& stop,
                                    RayCounters& rays, uint64_t& nonfinite, PsfCounts& filter)>;

// The pass loop of every renderer (the megakernel's render() below, the wavefront's): pass sizes,
// the spp and time budgets, cancel, `end_pass` (the sampler's) between passes, `after_pass` and
// progress. A pass stopped by cancel or the time budget still gets its `end_pass` (its rewards
// are learnt; the state after an interrupted render holds all it saw) and `after_pass`, then the
// loop ends. `min_count`, where given, says the film's fewest samples per pixel in place of
// film.min_count(): a renderer whose film lives on a device knows it without copying the film.
RenderProgress run_passes(const Scene& scene, const std::function<void()>& end_pass, Film& film,
                          const RenderSettings& settings, const std::atomic<bool>* cancel,
                          const std::function<void(const RenderProgress&, const Film&)>& after_pass,
                          const PassWork& work, const std::function<uint32_t()>& min_count = {});

// The camera ray of a sample whose stream is at its start (it draws the camera's dimensions).
Ray camera_ray(const Scene& scene, int x, int y, SampleStream& stream);

// Renders into `film` (which may already hold samples of this frame). `after_pass` is called
// after every pass with the film, between passes, and may not touch the sampler; the time it
// takes is excluded from the render's seconds and time budget. `integrator` reads `sampler`
// through its view, which it takes again at the start and after each end of pass.
// With the filter's temporal reuse (psf.temporal > 0), `history` holds its cells from frame to
// frame (without one, no sample blends another's, as in a render that follows no frame).
RenderProgress render(
    const Scene& scene, Integrator& integrator, LightSampler& sampler, Film& film,
    const RenderSettings& settings, const std::atomic<bool>* cancel = nullptr,
    const std::function<void(const RenderProgress&, const Film&)>& after_pass = {},
    PsfHistory* history = nullptr);

}  // namespace rll
