#include "rll/lights/simple_samplers.h"

#include "rll/lighttree/light_bounds.h"
#include "rll/scene/scene.h"

namespace rll {

std::vector<float> light_powers(const Scene& scene) {
  std::vector<float> w(scene.lights.size());
  double total = 0;
  for (size_t i = 0; i < w.size(); ++i) {
    const float p = light_power(scene.lights[i], scene.radius);
    // Capped as light_bounds caps it (lighttree/light_bounds.h): a power that overflowed a float
    // made every pmf NaN.
    total += w[i] = p <= kMaxSamplingPower ? p : kMaxSamplingPower;
  }
  if (!(total > 0)) std::fill(w.begin(), w.end(), 1.0f);
  return w;
}

UniformLightSampler::UniformLightSampler(const Scene& scene)
    : LightSampler("uniform"), m_count(uint32_t(scene.lights.size())) {}

SamplerView UniformLightSampler::sampler_view() const {
  SamplerView v;
  v.kind = SamplerKind::Uniform;
  v.light_count = m_count;
  return v;
}

PowerLightSampler::PowerLightSampler(const Scene& scene) : LightSampler("power") {
  lights_changed(scene);
}

void PowerLightSampler::lights_changed(const Scene& scene) {
  auto w = light_powers(scene);
  m_distribution = DiscreteDistribution(w);
}

SamplerView PowerLightSampler::sampler_view() const {
  SamplerView v;
  v.kind = SamplerKind::Power;
  v.power = m_distribution.view();
  return v;
}

}  // namespace rll
