// The oracle (DESIGN 5): RLL's cells and cuts with the learning replaced by knowledge. Before
// rendering (and outside its time), every cell met by camera and bounce vertices gets each
// cluster's occluded contribution estimated exhaustively with many shadow rays, and its cut
// refined greedily on those estimates. It samples like RLL (same defensive mixture, same
// within-cluster rule), so the gap between the two measures the learning alone.
#pragma once

#include <memory>
#include <utility>
#include <vector>

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

// The most shadow rays the oracle's estimates may plan to trace (cells x points x rays x
// estimates per cell, checked before the first): 2^32, minutes on a few cores, and more than ten
// times what the defaults plan on a large image.
inline constexpr double kMaxOracleShadowRays = 0x1p32;

// oracle.* from --set, each checked against its range (errors name the key), by the table of the
// oracle's parameters (core/param_table.h).
OracleSettings oracle_settings_from(const Params& params);
const std::vector<ParamSpec<OracleSettings>>& oracle_params();

class OracleLightSampler final : public LightSampler {
 public:
  OracleLightSampler(const Scene& scene, const LightTree& tree, const Accel& accel,
                     const RllSettings& rll, const OracleSettings& settings);
  // The frozen rll's: the oracle samples as rll does, with its knowledge, on any renderer.
  SamplerView sampler_view() const override { return m_rll->sampler_view(); }
  // Lights moved or switched: the knowledge is computed again (outside render time too).
  void lights_changed(const Scene& scene) override;
  nlohmann::json describe() const override;
  double precompute_seconds() const { return m_seconds; }
  // For tests: the frozen RLL sampler holding the knowledge (a cell it has no cut for was not
  // found by discovery).
  const RllLightSampler& rll() const { return *m_rll; }
  // The shadow rays the estimates of a cell's cut took (its `rewards` diagnostic: the oracle
  // learns from no rewards); NaN for a cell it has no cut for.
  float shadow_rays_of(uint32_t cell) const;
  // The precompute stopped early at the cancel flag (core/long_work.h): cells it did not reach
  // sample like the light tree.
  bool interrupted() const { return m_interrupted; }

 private:
  void precompute(const Scene& scene);
  OracleSettings m_s;
  const LightTree& m_tree;  // the render session's (it outlives its samplers)
  const Accel& m_accel;
  RllSettings m_rll_settings;
  std::unique_ptr<RllLightSampler> m_rll;
  double m_seconds = 0;
  uint64_t m_rays = 0;
  uint32_t m_cells = 0;
  bool m_interrupted = false;
  std::vector<std::pair<uint32_t, float>> m_cell_rays;  // (cell, shadow rays), by cell
};

}  // namespace rll
