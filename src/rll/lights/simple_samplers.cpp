#include "rll/lights/simple_samplers.h"

#include "rll/scene/scene.h"

namespace rll {

std::vector<float> light_powers(const Scene& scene) {
  std::vector<float> w(scene.lights.size());
  double total = 0;
  for (size_t i = 0; i < w.size(); ++i) total += w[i] = light_power(scene.lights[i], scene.radius);
  if (!(total > 0)) std::fill(w.begin(), w.end(), 1.0f);
  return w;
}

UniformLightSampler::UniformLightSampler(const Scene& scene) : m_count(uint32_t(scene.lights.size())) {}

SampledLight UniformLightSampler::sample(const LightContext&, double u) const {
  if (m_count == 0) return {};
  uint32_t i = std::min(m_count - 1, uint32_t(u * m_count));
  return {i, 1.0f / m_count};
}

float UniformLightSampler::pmf(const LightContext&, uint32_t light) const {
  return light < m_count ? 1.0f / m_count : 0.0f;
}

PowerLightSampler::PowerLightSampler(const Scene& scene) { lights_changed(scene); }

void PowerLightSampler::lights_changed(const Scene& scene) {
  auto w = light_powers(scene);
  m_distribution = DiscreteDistribution(w);
}

SampledLight PowerLightSampler::sample(const LightContext&, double u) const {
  if (m_distribution.empty()) return {};
  size_t i = m_distribution.sample(u);
  return {uint32_t(i), m_distribution.pmf(i)};
}

float PowerLightSampler::pmf(const LightContext&, uint32_t light) const {
  return light < m_distribution.size() ? m_distribution.pmf(light) : 0.0f;
}

}  // namespace rll
