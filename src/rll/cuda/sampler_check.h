// What the GPU check of the light samplers' dispatch computes (issue 31): one probe per shading
// context calls prepare_point, sample_light, light_pmf and record_nee (lights/light_dispatch.h)
// over a SamplerView. The CPU
// runs it directly, the GPU through sampler_probe_gpu (sampler_check.cu), over device copies of
// the view's arrays; the two must agree within float rounding (tests/gpu/test_gpu_samplers.cpp).
// Plain C++: host code includes it.
#pragma once

#include <cstdint>
#include <vector>

#include "rll/lights/light_dispatch.h"

namespace rll {

struct SamplerProbe {
  LightContext ctx;
  float u_prepare = 0;  // for prepare_point
  double u = 0;         // for sample_light
  uint32_t light = 0;   // for light_pmf
  float estimate = 0;   // the NeeRecord's estimate, unoccluded and max_rgb for record_nee
};

struct SamplerProbeResult {
  uint32_t cell = kNoCell;  // ctx.cell after prepare_point
  SampledLight sampled;
  float pmf_of_sampled = 0;  // light_pmf of the sampled light
  float pmf_of_light = 0;    // light_pmf of probe.light
};

RLL_HD inline SamplerProbeResult sampler_probe(const SamplerView& s, const SamplerProbe& p) {
  SamplerProbeResult r;
  LightContext ctx = p.ctx;
  prepare_point(s, ctx, p.u_prepare);
  r.cell = ctx.cell;
  r.sampled = sample_light(s, ctx, p.u);
  r.pmf_of_sampled = light_pmf(s, ctx, r.sampled.light);
  r.pmf_of_light = light_pmf(s, ctx, p.light);
  if (r.sampled.pmf > 0) {
    NeeRecord rec;
    rec.estimate = rec.unoccluded = rec.max_rgb = p.estimate;
    record_nee(s, ctx, r.sampled, rec);
  }
  return r;
}

// Runs sampler_probe(s, probes[i]) for every probe on the GPU, the view's arrays (host memory)
// copied to the device first (what the probes write there, cells and rewards, is dropped). Throws
// rll::Error "CUDA: ..." where CUDA fails.
std::vector<SamplerProbeResult> sampler_probe_gpu(const SamplerView& s,
                                                  const std::vector<SamplerProbe>& probes);

}  // namespace rll
