// The one next-event contract every renderer runs for every sampler (DESIGN 6): draw_nee yields a
// vertex's light samples, each with its own shadow ray, and finish_nee_draw weighs each after its
// ray. A one-sample sampler yields at most one (resampled from nee.candidates, resample_nee); a
// sampler that draws several candidates a vertex and keeps several (rht: rht_nee, docs/rht.md)
// yields up to nee_draws_per_vertex. The megakernel traces each sample's ray as it comes; the
// wavefront keeps nee_draws_per_vertex sample slots per path slot and traces them in its shadow
// stage.
#pragma once

#include "rll/lights/light_dispatch.h"
#include "rll/render/path_vertex.h"
#include "rll/render/rht_nee.h"

namespace rll {

// The most samples (shadow rays) a vertex draws with sampler s.
RLL_HD inline int nee_draws_per_vertex(const SamplerView& s) {
  return s.kind == SamplerKind::Rht ? s.rht.samples : 1;
}

// Whether the sampler draws its own several candidates (then nee.candidates must stay 1).
RLL_HD inline bool draws_several(const SamplerView& s) {
  return s.kind == SamplerKind::Rht;
}

// Draws the vertex's next-event samples with sampler s, calling emit(const NeeDraw&) for each
// that has a light (pmf > 0), at most nee_draws_per_vertex(s). `rht_memory`: the vertex's
// reservoirs for a sampler that draws several (draws_several), in the path slot's memory (the
// wavefront's); null: on this thread's stack, on the CPU only (a GPU thread's stack holding them
// took the next-event stage over its budgets, tests/unit/kernel_budgets.h).
template <class Emit>
RLL_HD inline void draw_nee(const PathConstants& c, const SamplerView& s, const LightContext& ctx,
                            const Bsdf& bsdf, const Vec3& wo, SampleStream& stream, int depth,
                            RhtReservoirMemory* rht_memory, Emit&& emit) {
  if (s.kind == SamplerKind::Rht) {
#if RLL_DEVICE_CODE
    if (rht_memory) rht_nee(c, s.rht, ctx, bsdf, wo, stream, depth, *rht_memory, emit);
#else
    RhtReservoirMemory own;
    rht_nee(c, s.rht, ctx, bsdf, wo, stream, depth, rht_memory ? *rht_memory : own, emit);
#endif
    return;
  }
  const NeeChoice ch = resample_nee(
      c, ctx, bsdf, wo, stream, depth, [&](double u) { return sample_light(s, ctx, u); },
      [&](const SampledLight& first, double u) { return sample_in_cluster(s, ctx, first, u); },
      [&](const SampledLight& l) { return nee_target(s, l); });
  if (!(ch.light.pmf > 0)) return;
  NeeDraw d;
  d.setup = ch.setup;
  d.light = ch.light;
  // Resampling's ratio (sum w / M) / w_kept, where a candidate was kept.
  if (ch.weight > 0) d.scale = (ch.weight_sum / float(c.nee_candidates)) / ch.weight;
  emit(d);
}

// One sample's contribution after its shadow ray (before the path throughput): nee_finish's
// value, f Le G V m_L / (pmf x pdf of the point), times the draw's scale; the record is the
// sample's with its pmf, for a learning sampler (record_nee). With candidates from one cluster
// (nee.draw=cluster) the record's values carry the scale too: estimate / P(l | cluster) times
// it is resampling's estimate of the cluster's whole visible contribution, unbiased for any
// target (the candidates are i.i.d. within the cluster), which is what the cluster's reward
// estimates (docs/rll.md); unoccluded and max_rgb alike, so that their ratios to it stay the
// sample's own.
RLL_HD inline NeeResult finish_nee_draw(const PathConstants& c, const NeeDraw& d, bool occluded,
                                        const Bsdf& bsdf, const Vec3& wo, const Rgb& beta) {
  NeeResult r =
      nee_finish(d.setup, occluded, bsdf, wo, beta, d.light.pmf, c.strategy == LightStrategy::Mis);
  if (!is_black(r.value)) r.value *= d.scale;
  if (c.nee_cluster) {
    r.record.estimate *= d.scale;
    r.record.unoccluded *= d.scale;
    r.record.max_rgb *= d.scale;
  }
  return r;
}

}  // namespace rll
