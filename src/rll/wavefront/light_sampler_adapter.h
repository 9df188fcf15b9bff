// The one door through which the wavefront renderer reaches a light sampler: prepare, sample,
// pmf, record and end_pass. A sampler with a device version (sampler_view(): uniform, power,
// tree, rll, fermat) is reached through the tag-dispatched RLL_HD functions of
// lights/light_dispatch.h, the functions a GPU kernel runs; one without (ltc, oracle) through its
// class, on the CPU only.
#pragma once

#include "rll/lights/light_dispatch.h"
#include "rll/lights/light_sampler.h"

namespace rll {

class WavefrontLightSampler {
 public:
  explicit WavefrontLightSampler(LightSampler& sampler)
      : m_sampler(sampler),
        m_view(sampler.sampler_view()),
        m_prepares(sampler.prepares()),
        m_learns(sampler.learns()) {}
  // Whether prepare() and record() do anything: the stages skip them, and their numbers, if not.
  bool prepares() const { return m_prepares; }
  bool learns() const { return m_learns; }
  // Whether the calls go through the device functions (else through the class).
  bool dispatched() const { return m_view.kind != SamplerKind::None; }
  void prepare(LightContext& ctx, float u) const {
    if (dispatched())
      prepare_point(m_view, ctx, u);
    else
      m_sampler.prepare(ctx, u);
  }
  SampledLight sample(const LightContext& ctx, double u) const {
    return dispatched() ? sample_light(m_view, ctx, u) : m_sampler.sample(ctx, u);
  }
  float pmf(const LightContext& ctx, uint32_t light) const {
    return dispatched() ? light_pmf(m_view, ctx, light) : m_sampler.pmf(ctx, light);
  }
  // Safe from many threads at once; only for a sampler that learns().
  void record(const LightContext& ctx, const SampledLight& s, const NeeRecord& r) const {
    if (dispatched())
      record_nee(m_view, ctx, s, r);
    else
      m_sampler.record(ctx, s, r);
  }
  // Between passes, when no stage runs. The view is taken again: the end of a pass may move
  // what it points to (a sampler's tables are its own to rebuild).
  void end_pass() {
    m_sampler.end_pass();
    m_view = m_sampler.sampler_view();
    m_learns = m_sampler.learns();
  }

 private:
  LightSampler& m_sampler;
  SamplerView m_view;
  bool m_prepares, m_learns;
};

}  // namespace rll
