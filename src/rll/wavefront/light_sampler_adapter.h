// The one door through which the wavefront renderer reaches a light sampler: prepare, sample,
// pmf, record and end_pass. On the CPU it wraps today's LightSampler; the tag-dispatched RLL_HD
// sampler functions (lights/) will replace what is behind it without touching the stages.
#pragma once

#include "rll/lights/light_sampler.h"

namespace rll {

class WavefrontLightSampler {
 public:
  explicit WavefrontLightSampler(LightSampler& sampler)
      : m_sampler(sampler), m_prepares(sampler.prepares()), m_learns(sampler.learns()) {}
  // Whether prepare() and record() do anything: the stages skip them, and their numbers, if not.
  bool prepares() const { return m_prepares; }
  bool learns() const { return m_learns; }
  void prepare(LightContext& ctx, float u) const { m_sampler.prepare(ctx, u); }
  SampledLight sample(const LightContext& ctx, double u) const { return m_sampler.sample(ctx, u); }
  float pmf(const LightContext& ctx, uint32_t light) const { return m_sampler.pmf(ctx, light); }
  // Safe from many threads at once.
  void record(const LightContext& ctx, const SampledLight& s, const NeeRecord& r) const {
    m_sampler.record(ctx, s, r);
  }
  // Between passes, when no stage runs.
  void end_pass() const { m_sampler.end_pass(); }

 private:
  LightSampler& m_sampler;
  bool m_prepares, m_learns;
};

}  // namespace rll
