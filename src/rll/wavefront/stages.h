// The stages of the wavefront renderer and where its time went, stage by stage: what both the
// CPU and the GPU versions report.
#pragma once

#include <array>
#include <cstddef>

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

}  // namespace rll
