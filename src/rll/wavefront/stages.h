// The stages of the wavefront renderer and where its time went, stage by stage: what both the
// CPU and the GPU versions report.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

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
  // ReSTIR's (render/restir.h): the candidates at the ReSTIR vertex (a bounce's), then over the
  // pixels after the sample's paths: the kept samples' shadow rays, temporal and spatial reuse
  // (with their shadow rays) and the final shading.
  RestirCandidates,
  RestirVisibility,
  RestirTemporal,
  RestirSpatial,
  RestirShade,
  Accumulate,
  EndPass,
  Count
};
inline constexpr size_t kWavefrontStages = size_t(WavefrontStage::Count);
// Their names in --stats files and tables.
inline constexpr std::array<const char*, kWavefrontStages> kWavefrontStageNames = {
    "camera",          "closest_hit",    "emission",     "nee_sample",        "shadow",
    "nee_finish",      "rewards",        "bsdf_sample",  "restir_candidates", "restir_visibility",
    "restir_temporal", "restir_spatial", "restir_shade", "accumulate",        "end_pass"};
// Whether stage s is ReSTIR's (a render without a restir sampler spends nothing there).
inline constexpr bool is_restir_stage(size_t s) {
  return s >= size_t(WavefrontStage::RestirCandidates) && s <= size_t(WavefrontStage::RestirShade);
}

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

// What a render asked of its device in one pass (per frame in `rll interactive`), as --stats
// reports it (`device_work`): the host synchronisations (reads that wait for the device's work),
// the launches (kernels, and fills or copies queued on the device), the allocations of device or
// pinned memory, and the bytes copied to the host and to the device. The CPU's wavefront counts
// the same things of its host backend (its memory is the host's: no bytes are copied), so that a
// CPU test holds the driver to one synchronisation per pass and no allocation after the first.
struct DeviceWork {
  uint64_t syncs = 0, launches = 0, allocations = 0, bytes_to_host = 0, bytes_to_device = 0;

  DeviceWork& operator+=(const DeviceWork& o) {
    syncs += o.syncs;
    launches += o.launches;
    allocations += o.allocations;
    bytes_to_host += o.bytes_to_host;
    bytes_to_device += o.bytes_to_device;
    return *this;
  }
  // What happened between two readings of a counter (`*this` the later).
  DeviceWork since(const DeviceWork& earlier) const {
    return {syncs - earlier.syncs, launches - earlier.launches, allocations - earlier.allocations,
            bytes_to_host - earlier.bytes_to_host, bytes_to_device - earlier.bytes_to_device};
  }
};

}  // namespace rll
