#include "support/biased_sampler.h"

#include <algorithm>

#include "rll/lights/simple_samplers.h"
#include "rll/lighttree/light_tree.h"

namespace rll::test {

BiasedSampler::BiasedSampler(LightSampler& inner, std::vector<uint32_t> group, double factor,
                             Pmf mode)
    : LightSampler("biased-" + inner.name()),
      m_inner(inner.sampler_view()),
      m_group(std::move(group)),
      m_factor(factor),
      m_mode(mode) {
  set_host_calls(*this);
  for (uint32_t l : m_group) {
    if (l >= m_in_group.size()) m_in_group.resize(size_t(l) + 1, 0);
    m_in_group[l] = 1;
  }
}

double BiasedSampler::group_branch(const LightContext& ctx) const {
  double in_group = 0;
  for (uint32_t l : m_group) in_group += light_pmf(m_inner, ctx, l);
  return 1 - 1 / (1 + (m_factor - 1) * in_group);
}

SampledLight BiasedSampler::sample(const LightContext& ctx, double u) const {
  if (m_mode == Pmf::Understated) {
    SampledLight s = sample_light(m_inner, ctx, u);
    if (s.pmf > 0) s.pmf = pmf(ctx, s.light);
    return s;
  }
  const double b = group_branch(ctx);
  SampledLight s;
  if (u < 1 - b || b <= 0) {
    s = sample_light(m_inner, ctx, std::min(u / (1 - b), 0x1.fffffffffffffp-1));
    if (s.pmf <= 0) return s;  // the wrapped sampler found nothing
  } else {
    // Invert the cumulative of p over the group.
    double in_group = 0;
    for (uint32_t l : m_group) in_group += light_pmf(m_inner, ctx, l);
    const double target = (u - (1 - b)) / b * in_group;
    double sum = 0;
    s.light = m_group.back();
    for (uint32_t l : m_group) {
      const double p = light_pmf(m_inner, ctx, l);
      if (p <= 0) continue;
      s.light = l;
      if ((sum += p) > target) break;
    }
  }
  s.pmf = pmf(ctx, s.light);
  return s;
}

float BiasedSampler::pmf(const LightContext& ctx, uint32_t light) const {
  const float p = light_pmf(m_inner, ctx, light);
  if (m_mode == Pmf::Wrapped) return p;
  if (m_mode == Pmf::Understated) return in_group(light) ? float(p / m_factor) : p;
  const double w = in_group(light) ? m_factor : 1.0;
  return float(double(p) * w * (1 - group_branch(ctx)));
}

std::vector<uint32_t> brightest_light_group(const Scene& scene, const LightTree& tree,
                                            uint32_t max_lights) {
  const std::vector<float> power = light_powers(scene);
  uint32_t best = 0;
  double best_power = -1;
  for (uint32_t i = 0; i < tree.node_count(); ++i) {
    const LightTreeNode& node = tree.node(i);
    if (node.light_count() > max_lights || node.group) continue;
    double sum = 0;
    for (uint32_t l = node.begin; l < node.end; ++l) sum += power[l];
    if (sum > best_power) best_power = sum, best = i;
  }
  std::vector<uint32_t> group;
  for (uint32_t l = tree.node(best).begin; l < tree.node(best).end; ++l) group.push_back(l);
  return group;
}

}  // namespace rll::test
