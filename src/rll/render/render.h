// The pass loop: renders the image in passes of a few samples per pixel over parallel tiles,
// lets a learning sampler adapt between passes, and stops at a sample count, a time budget or
// a cancel request, whichever comes first.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>

#include "rll/core/rng.h"
#include "rll/render/film.h"
#include "rll/render/integrator.h"

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
  int frame = 0;                      // animation frame (enters the random seed)
  PointSet points = PointSet::Sobol;  // the sample points (--points)
};

struct RenderProgress {
  int passes = 0;
  int spp_done = 0;  // complete samples per pixel (every pixel has at least this many)
  int spp_target = 0;
  double seconds = 0;
  double time_limit = 0;
  uint64_t samples = 0;    // camera samples taken
  uint64_t nonfinite = 0;  // samples that came out NaN/inf and were dropped
  RayCounters rays;
  bool cancelled = false;  // stopped by the cancel flag
  bool out_of_time = false;
};

// Renders into `film` (which may already hold samples of this frame). `after_pass` is called
// after every pass with the film, between passes, and may not touch the sampler; the time it
// takes is excluded from the render's seconds and time budget.
RenderProgress render(
    const Scene& scene, const Integrator& integrator, LightSampler& sampler, Film& film,
    const RenderSettings& settings, const std::atomic<bool>* cancel = nullptr,
    const std::function<void(const RenderProgress&, const Film&)>& after_pass = {});

}  // namespace rll
