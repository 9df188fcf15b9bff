// The visibility-blind baselines without a hierarchy: uniform and power-proportional.
#pragma once

#include "rll/core/sampling.h"
#include "rll/lights/light_sampler.h"

namespace rll {

// P(l) = 1/N.
class UniformLightSampler final : public LightSampler {
 public:
  explicit UniformLightSampler(const Scene& scene);
  SamplerView sampler_view() const override;

 private:
  uint32_t m_count;
};

// P(l) proportional to emitted power (area x radiance): the paper's "energy-based" baseline.
class PowerLightSampler final : public LightSampler {
 public:
  explicit PowerLightSampler(const Scene& scene);
  void lights_changed(const Scene& scene) override;
  SamplerView sampler_view() const override;

 private:
  DiscreteDistribution m_distribution;
};

// Power of every light of the scene (zero-power scenes fall back to equal weights).
std::vector<float> light_powers(const Scene& scene);

}  // namespace rll
