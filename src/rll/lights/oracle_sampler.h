// The oracle (DESIGN 5): RLL's cells and cuts with the learning replaced by knowledge. Before
// rendering (and outside its time), every cell met by camera and bounce vertices gets each
// cluster's occluded contribution estimated exhaustively with many shadow rays, and its cut
// refined greedily on those estimates. It samples like RLL (same defensive mixture, same
// within-cluster rule), so the gap between the two measures the learning alone.
#pragma once

#include <memory>

#include "rll/core/param_table.h"
#include "rll/lights/rll_sampler.h"

namespace rll {

class Accel;

struct OracleSettings {
  // Camera paths per pixel used to find cells and their points. 16: with 4, cells of secondary
  // vertices were missed, and the oracle in `path` had fireflies (docs/rll.md, "The oracle").
  int discovery_spp = 16;
  int bounces = 2;            // diffuse bounces followed during discovery (0: camera only)
  int points_per_cell = 32;   // shading points kept per cell (reservoir)
  int rays = 8;               // shadow rays per point and cluster
  int refine = 32;            // greedy split-collapse steps per cell on the estimates
  uint64_t seed = 77;
};

// oracle.* from --set, each checked against its range (errors name the key), by the table of the
// oracle's parameters (core/param_table.h).
OracleSettings oracle_settings_from(const Params& params);
const std::vector<ParamSpec<OracleSettings>>& oracle_params();

class OracleLightSampler final : public LightSampler {
 public:
  OracleLightSampler(const Scene& scene, const Accel& accel, const RllSettings& rll, const OracleSettings& settings);
  std::string name() const override { return "oracle"; }
  void prepare(LightContext& ctx, float u) const override { m_rll->prepare(ctx, u); }
  bool prepares() const override { return true; }
  SampledLight sample(const LightContext& ctx, double u) const override { return m_rll->sample(ctx, u); }
  float pmf(const LightContext& ctx, uint32_t light) const override { return m_rll->pmf(ctx, light); }
  // Lights moved or switched: the knowledge is computed again (outside render time too).
  void lights_changed(const Scene& scene) override;
  nlohmann::json describe() const override;
  double precompute_seconds() const { return m_seconds; }
  // For tests: the frozen RLL sampler holding the knowledge (a cell it has no cut for was not
  // found by discovery).
  const RllLightSampler& rll() const { return *m_rll; }

 private:
  void precompute(const Scene& scene);
  OracleSettings m_s;
  const Accel& m_accel;
  RllSettings m_rll_settings;
  std::unique_ptr<RllLightSampler> m_rll;
  double m_seconds = 0;
  uint64_t m_rays = 0;
  uint32_t m_cells = 0;
};

}  // namespace rll
