// The wavefront path tracer: paths in flight as structure-of-arrays state in a fixed budget of
// slots, advanced one bounce at a time by stages (camera rays, closest hit, emission and MIS,
// next-event set-up, shadow rays, its finish, rewards, BSDF sampling, accumulation), each a
// host_parallel_for over its own queue. It calls the megakernel's per-vertex functions
// (render/path_vertex.h) in the megakernel's order, so a path's radiance is the same to the bit.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>

#include "rll/accel/accel.h"
#include "rll/lights/light_sampler.h"
#include "rll/render/film.h"
#include "rll/render/integrator.h"
#include "rll/render/render.h"
#include "rll/scene/scene.h"

namespace rll {

// The stages of the wavefront renderer, in the order a bounce runs them; end_pass is the
// sampler's work between passes (learning), which the pass loop runs.
enum class WavefrontStage {
  Camera,
  ClosestHit,
  Emission,
  NeeSample,
  Shadow,
  NeeFinish,
  Rewards,
  BsdfSample,
  Accumulate,
  EndPass,
  Count
};
inline constexpr size_t kWavefrontStages = size_t(WavefrontStage::Count);
// Their names in --stats files and tables.
inline constexpr std::array<const char*, kWavefrontStages> kWavefrontStageNames = {
    "camera",     "closest_hit", "emission",    "nee_sample", "shadow",
    "nee_finish", "rewards",     "bsdf_sample", "accumulate", "end_pass"};

// Where the time of a render went, stage by stage, summed over its batches and bounces. On the
// CPU each stage's loop is timed by the wall clock; a device version records the same stages
// with events around its launches, so that the two compare stage for stage.
struct WavefrontTimes {
  std::array<double, kWavefrontStages> stage_seconds{};
  // The whole render_wavefront call: the stages, the set-up (views, slot memory), the loops
  // between them and the caller's after_pass.
  double total_seconds = 0;

  double& operator[](WavefrontStage s) { return stage_seconds[size_t(s)]; }
  double stages_sum() const;
};

struct WavefrontSettings {
  // Paths in flight at once: the state of each slot takes under 1 KB, allocated once per render.
  uint32_t path_slots = 1u << 15;
  // When set, the times of the render are added to it (the clock is read only then).
  WavefrontTimes* times = nullptr;
};

// As render() (render/render.h), with the wavefront renderer: the same pass loop, the same
// samples of each pixel in the same order, so the film is the same to the bit whatever the thread
// count (for a sampler that learns nothing within a pass, the same as render()'s).
RenderProgress render_wavefront(
    const Scene& scene, const Accel& accel, LightSampler& sampler,
    const IntegratorSettings& integrator, Film& film, const RenderSettings& settings,
    const std::atomic<bool>* cancel = nullptr,
    const std::function<void(const RenderProgress&, const Film&)>& after_pass = {},
    const WavefrontSettings& wavefront = {});

}  // namespace rll
