// Every light sampler as data (DESIGN 6): a trivially copyable SamplerView holds a tag and the
// flat views a sampler reads, and each sampler's RLL_HD sample and pmf functions read them;
// lights/light_dispatch.h switches on the tag. Every renderer (the megakernel, the CPU wavefront,
// the GPU's) and every tool reaches every sampler through that switch alone (the samplers'
// classes keep only the host's lifecycle: light_sampler.h), so all run one source. A sampler with
// no device version is the one host-only kind (HostSampler), which a device renderer refuses.
#pragma once

#include <cstdint>

#include "rll/core/device.h"
#include "rll/core/sampling.h"
#include "rll/lights/light_context.h"
#include "rll/lights/rht_view.h"
#include "rll/lighttree/descent.h"

namespace rll {

enum class SamplerKind : uint8_t { None, Uniform, Power, Tree, Rll, Rht, Host };

struct RllView;  // lights/rll_view.h

// A sampler with no device version (ltc, the tests' samplers): its calls as plain functions of the
// sampler object, on the CPU only (LightSampler::set_host_calls makes them from its class).
struct HostSampler {
  const void* self = nullptr;
  void (*prepare)(const void* self, LightContext& ctx, float u) = nullptr;
  SampledLight (*sample)(const void* self, const LightContext& ctx, double u) = nullptr;
  float (*pmf)(const void* self, const LightContext& ctx, uint32_t light) = nullptr;
  void (*record)(const void* self, const LightContext& ctx, const SampledLight& s,
                 const NeeRecord& r) = nullptr;
};

struct SamplerView {
  SamplerKind kind = SamplerKind::None;
  // Whether prepare_point and record_nee do anything: renderers skip them, and their numbers, if
  // not (a frozen learner records nothing).
  bool prepares = false, learns = false;
  uint32_t light_count = 0;  // Uniform
  DistributionView power;    // Power: over the lights by power
  LightTreeView tree;        // Tree
  // Rll: its views, in the memory of the device that runs the dispatch (the sampler's own on the
  // host), held by pointer so that this header need not know them.
  const RllView* rll = nullptr;
  // Rht: draws several candidates a vertex (render/nee_draw.h); its tree is rht.tree.
  RhtView rht;
  const HostSampler* host = nullptr;  // Host
};

// A descent's choice as a sampler's answer (no cluster).
RLL_HD inline SampledLight sampled_light(const TreeSample& t) {
  SampledLight s;
  s.light = t.light;
  s.pmf = t.pmf;
  return s;
}

// P(l) = 1/N.
RLL_HD inline SampledLight uniform_sample(uint32_t count, double u) {
  if (count == 0) return {};
  SampledLight s;
  s.light = std::min(count - 1, uint32_t(u * count));
  s.pmf = 1.0f / count;
  return s;
}
RLL_HD inline float uniform_pmf(uint32_t count, uint32_t light) {
  return light < count ? 1.0f / count : 0.0f;
}

// P(l) proportional to power: the distribution's table.
RLL_HD inline SampledLight power_sample(const DistributionView& d, double u) {
  if (d.empty()) return {};
  SampledLight s;
  s.light = uint32_t(sample_discrete(d, u));
  s.pmf = d.pmf[s.light];
  return s;
}
RLL_HD inline float power_pmf(const DistributionView& d, uint32_t light) {
  return light < d.pmf.size ? d.pmf[light] : 0.0f;
}

// One descent of the light tree from its root.
RLL_HD inline SampledLight tree_sample(const LightTreeView& t, const LightContext& ctx, double u) {
  return sampled_light(tree_descend(t, LightTree::kRoot, ctx.p, ctx.n, u));
}
RLL_HD inline float tree_pmf(const LightTreeView& t, const LightContext& ctx, uint32_t light) {
  return tree_descend_pmf(t, LightTree::kRoot, light, ctx.p, ctx.n);
}

}  // namespace rll
