// The CPU's door from the wavefront stages to a light sampler: prepare, sample, pmf and record. A
// sampler with a device version (sampler_view(): uniform, power, tree, rll, fermat) is reached
// through the tag-dispatched RLL_HD functions of lights/light_dispatch.h, the functions a GPU
// kernel runs (ViewSampler, wavefront/kernels.h); one without (ltc, oracle) through its class, on
// the CPU only. Copied by value into every stage.
#pragma once

#include "rll/lights/light_dispatch.h"
#include "rll/lights/light_sampler.h"

namespace rll {

struct HostLightSampler {
  LightSampler* sampler = nullptr;
  SamplerView view;
  // Whether prepare() and record() do anything: the stages skip them, and their numbers, if not.
  bool prepares = false, learns = false;

  // The sampler as it stands (again after each end_pass: its tables may have moved).
  static HostLightSampler of(LightSampler& s) {
    return {&s, s.sampler_view(), s.prepares(), s.learns()};
  }
  // Whether the calls go through the device functions (else through the class).
  bool dispatched() const { return view.kind != SamplerKind::None; }
  void prepare(LightContext& ctx, float u) const {
    if (dispatched())
      prepare_point(view, ctx, u);
    else
      sampler->prepare(ctx, u);
  }
  SampledLight sample(const LightContext& ctx, double u) const {
    return dispatched() ? sample_light(view, ctx, u) : sampler->sample(ctx, u);
  }
  float pmf(const LightContext& ctx, uint32_t light) const {
    return dispatched() ? light_pmf(view, ctx, light) : sampler->pmf(ctx, light);
  }
  float target(const SampledLight& l) const { return nee_target(view, l); }
  // Safe from many threads at once; only for a sampler that learns().
  void record(const LightContext& ctx, const SampledLight& s, const NeeRecord& r) const {
    if (dispatched())
      record_nee(view, ctx, s, r);
    else
      sampler->record(ctx, s, r);
  }
};

}  // namespace rll
