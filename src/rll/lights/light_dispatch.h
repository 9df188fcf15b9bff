// The light samplers' dispatch (DESIGN 6): RLL_HD sample_light and light_pmf switch on a
// SamplerView's tag, not on a virtual call, so that every renderer (the megakernel, the CPU
// wavefront, the GPU's) chooses lights with the same functions that the samplers' classes run.
// The Host kind (a sampler with no device version) is compiled for the host only.
#pragma once

#include "rll/lights/rll_view.h"
#include "rll/lights/sampler_view.h"

namespace rll {

// A light for the shading point ctx and its probability; SampledLight{} (pmf 0) for None, and for
// Rht, which draws several per vertex: renderers draw every sampler through draw_nee
// (render/nee_draw.h), which runs rht's own draw.
RLL_HD inline SampledLight sample_light(const SamplerView& s, const LightContext& ctx, double u) {
  switch (s.kind) {
    case SamplerKind::Uniform:
      return uniform_sample(s.light_count, u);
    case SamplerKind::Power:
      return power_sample(s.power, u);
    case SamplerKind::Tree:
      return tree_sample(s.tree, ctx, u);
    case SamplerKind::Rll:
      return rll_sample(*s.rll, ctx, u);
    case SamplerKind::Rht:
      break;
    case SamplerKind::Host:
#if !RLL_DEVICE_CODE
      return s.host->sample(s.host->self, ctx, u);
#endif
    case SamplerKind::None:
      break;
  }
  return {};
}

// Whether the sampler draws a cluster first and can draw more lights from it
// (sample_in_cluster): rll (and the oracle, which samples with rll's view).
RLL_HD inline bool draws_clusters(const SamplerView& s) {
  return s.kind == SamplerKind::Rll && rll_cluster_draws(*s.rll);
}

// Another light from the cluster that `first` (a draw of sample_light at ctx) came from, with
// its full pmf: resampled NEE's candidates from one cluster (nee.draw=cluster). Only where
// draws_clusters(s); nothing otherwise.
RLL_HD inline SampledLight sample_in_cluster(const SamplerView& s, const LightContext& ctx,
                                             const SampledLight& first, double u) {
  return s.kind == SamplerKind::Rll ? rll_sample_in_cluster(*s.rll, ctx, first, u) : SampledLight{};
}

// The probability that sample_light(s, ctx, .) returns `light`.
RLL_HD inline float light_pmf(const SamplerView& s, const LightContext& ctx, uint32_t light) {
  switch (s.kind) {
    case SamplerKind::Uniform:
      return uniform_pmf(s.light_count, light);
    case SamplerKind::Power:
      return power_pmf(s.power, light);
    case SamplerKind::Tree:
      return tree_pmf(s.tree, ctx, light);
    case SamplerKind::Rll:
      return rll_pmf(*s.rll, ctx, light);
    case SamplerKind::Rht:  // the probability that a draw yields the light (its MIS density)
      return rht_pmf(s.rht, ctx.p, ctx.n, light);
    case SamplerKind::Host:
#if !RLL_DEVICE_CODE
      return s.host->pmf(s.host->self, ctx, light);
#endif
    case SamplerKind::None:
      break;
  }
  return 0;
}

// Resampled NEE's learnt factor of a drawn light's target (nee.target=learnt, docs/nee.md): rll's
// learnt visibility of the light's cluster in the cell, from its record (ClusterDraw::target); 1
// for a sampler that learns none.
RLL_HD inline float nee_target(const SamplerView& s, const SampledLight& sampled) {
  return s.kind == SamplerKind::Rll ? cluster_draw(sampled).target : 1.0f;
}

// Once per shading point before sample_light / light_pmf: a learning sampler finds the point's
// cell (ctx.cell). u is a fresh uniform number for its stochastic choices.
RLL_HD inline void prepare_point(const SamplerView& s, LightContext& ctx, float u) {
  if (s.kind == SamplerKind::Rll) rll_prepare(*s.rll, ctx, u);
#if !RLL_DEVICE_CODE
  if (s.kind == SamplerKind::Host) s.host->prepare(s.host->self, ctx, u);
#endif
}

// One call per next-event sample, zeros included (see NeeRecord): a learning sampler's reward.
// Thread-safe. Only where s.learns (a frozen rll's view would still record).
RLL_HD inline void record_nee(const SamplerView& s, const LightContext& ctx,
                              const SampledLight& sampled, const NeeRecord& r) {
  if (s.kind == SamplerKind::Rll) rll_record(*s.rll, ctx, sampled, r);
#if !RLL_DEVICE_CODE
  if (s.kind == SamplerKind::Host) s.host->record(s.host->self, ctx, sampled, r);
#endif
}

}  // namespace rll
