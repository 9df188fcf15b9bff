// The resampled hierarchical tree (`rht`; Conty Estevez, Hellmuth & Lecocq 2024, as the public
// code of Kvasnica & Havran's study runs it; docs/rht.md): per vertex a split descent of the
// light tree yields several candidates, two reservoir stages keep up to rht.samples of them, each
// with its own shadow ray. It draws several samples, so every renderer reaches it through its
// view's Rht kind and draw_nee (render/nee_draw.h), not through sample_light; its light_pmf is
// the probability that a draw yields the light, the density the BSDF strategy's MIS weight needs.
// It learns nothing.
#pragma once

#include <vector>

#include "rll/core/param_table.h"
#include "rll/lights/light_sampler.h"
#include "rll/lights/rht_view.h"

namespace rll {

struct RhtSettings {
  // Measured at equal time on cornell-boxes-room path and arch-interior direct (docs/rht.md):
  // 3.3x and 4.5x the efficiency of the public code's gamma 0.2, 16 reservoirs, one sample.
  float gamma = 0.05f;  // rht.gamma: width of the split probability's bell
  int reservoirs = 8;   // rht.reservoirs: first-stage reservoirs
  int samples = 4;      // rht.samples: second-stage reservoirs, shadow rays per vertex
};
// rht.* from --set, each checked against its range (errors name the key), by the table of
// rht's parameters (core/param_table.h).
RhtSettings rht_settings_from(const Params& params);
const std::vector<ParamSpec<RhtSettings>>& rht_params();

class RhtLightSampler final : public LightSampler {
 public:
  RhtLightSampler(const Scene& scene, const LightTree& tree, const RhtSettings& settings);
  // Its Rht kind: sample_light yields nothing (a caller that asks for one light gets no light,
  // never a wrong image); light_pmf is the probability that a draw yields the light (rht_pmf),
  // which sums to the expected number of candidates, not to one.
  SamplerView sampler_view() const override;
  nlohmann::json describe() const override;

 private:
  RhtSettings m_s;  // as given: describe() reports them by rht's table
  RhtView m_view;
};

}  // namespace rll
