// A test-only light sampler that is a known few percent off: the checks' proof of power.
#pragma once

#include <cstdint>
#include <vector>

#include "rll/lights/light_dispatch.h"
#include "rll/lights/light_sampler.h"
#include "rll/scene/scene.h"

namespace rll::test {

// Wraps a sampler p and draws from q(l) = p(l) w(l) / Z, where w is `factor` for the lights of
// one group A and 1 for the rest, Z = 1 + (factor - 1) P(A): the group's probability scaled by
// `factor` and the whole renormalized at every point. It is the mixture (1 - b) p + b p_A with
// b = 1 - 1/Z (p_A: p restricted to A), so one u maps to a light without rejection and u's
// stratification carries over (each light gets at most one more interval of u than under p).
// With `Pmf::Consistent`, pmf() answers q: sample() and pmf() agree and only a check against
// the truth can see the error (a render with it is unbiased). With `Pmf::Wrapped`, pmf() answers
// p: a sampler with a bug in its sampling but not in its pmf; a render's next-event estimate is
// off by (1 + 0.05 C/L) / (1 + 0.05 P) - 1 where the group has a share P of the probability and C
// of the light L, which is small where the wrapped sampler is good (P near C). With
// `Pmf::Understated`, sample() draws from p but pmf() answers p / factor for the group's lights
// (pmfs no longer sum to one): the group's next-event light is `factor` times too bright, the
// image bias a region-wise render test must see. It learns nothing: train the wrapped sampler first
// (the group's samples carry no cluster for a learner's record_nee). Its view is the host kind
// (over the wrapped sampler's view, taken when it is made).
class BiasedSampler final : public LightSampler {
 public:
  enum class Pmf { Consistent, Wrapped, Understated };
  // `group`: light indices (any order, no repeats). The wrapped sampler must outlive this one.
  BiasedSampler(LightSampler& inner, std::vector<uint32_t> group, double factor, Pmf mode);
  SamplerView sampler_view() const override { return host_view(m_inner.prepares, false); }
  // Its host kind's calls.
  void prepare(LightContext& ctx, float u) const { prepare_point(m_inner, ctx, u); }
  SampledLight sample(const LightContext& ctx, double u) const;
  float pmf(const LightContext& ctx, uint32_t light) const;

  bool in_group(uint32_t light) const { return light < m_in_group.size() && m_in_group[light]; }
  // The mixture weight b at a point: 1 - 1/Z.
  double group_branch(const LightContext& ctx) const;

 private:
  SamplerView m_inner;  // the wrapped sampler's
  std::vector<uint32_t> m_group;
  std::vector<uint8_t> m_in_group;
  double m_factor;
  Pmf m_mode;
};

// A group of at most `max_lights` lights that the tree keeps together (the lights of one node),
// the node of largest total power among those of that size: a group that lights a part of the
// scene, as a wrong learnt cluster or a wrong subtree would.
std::vector<uint32_t> brightest_light_group(const Scene& scene, const LightTree& tree,
                                            uint32_t max_lights);

}  // namespace rll::test
