// Reinforcement Lightcuts Learning (Pantaleoni), as specified in DESIGN.md section 2: per cell
// of a jittered 5D hash grid, a learnt cut of the light tree with a value per cluster; NEE
// picks a cluster from the cell's CDF (mixed with a defensive prior), then a light inside it.
// Every NEE sample rewards its cluster; between passes Q is folded, cuts are adapted by
// split-collapse and CDFs rebuilt.
#pragma once

#include <atomic>
#include <memory>
#include <vector>

#include "rll/learn/cell_grid.h"
#include "rll/learn/cuts.h"
#include "rll/lights/light_sampler.h"
#include "rll/lights/tree_sampler.h"

namespace rll {

enum class WithinCluster { Uniform, Power, Tree };
enum class RewardKind { Cluster, FullPdf };
// The defensive term of the cluster distribution: the light tree's probability of the cluster
// at the shading point itself, or a per-cell prior mixed into the cell's CDF (the paper).
enum class Defensive { Tree, Cell };

struct RllSettings {
  CutSettings cut;
  CellGridSettings grid;
  uint32_t capacity = 32768;  // cells
  WithinCluster within = WithinCluster::Tree;
  RewardKind reward = RewardKind::Cluster;
  Defensive defensive = Defensive::Tree;
  bool inherit = true;  // new cells start from the learnt state of the coarser cell around them
};

// Reads rll.* parameters (see docs/rll.md for each).
RllSettings rll_settings_from(const Params& params);

class RllLightSampler final : public LightSampler {
 public:
  RllLightSampler(const Scene& scene, const RllSettings& settings);
  std::string name() const override { return "rll"; }
  void prepare(LightContext& ctx, float u) const override;
  bool prepares() const override { return true; }
  SampledLight sample(const LightContext& ctx, double u) const override;
  float pmf(const LightContext& ctx, uint32_t light) const override;
  bool learns() const override { return !m_frozen; }
  void record(const LightContext& ctx, const SampledLight& s, float estimate) override;
  void end_pass() override;
  void lights_changed(const Scene& scene) override;
  nlohmann::json describe() const override;

  // Stops learning: record() and end_pass() do nothing from now on (the oracle).
  void freeze() { m_frozen = true; }
  // For tests and the oracle: the learnt state.
  const CutStore& cuts() const { return *m_cuts; }
  CutStore& cuts() { return *m_cuts; }
  const CellTable& table() const { return *m_table; }
  uint64_t passes() const { return m_pass; }
  size_t bytes() const;

 private:
  struct View {  // the cut of a point's cell, or the shared initial cut
    uint32_t size;
    const uint32_t* ends;
    const uint32_t* nodes;
    const float* cdf;
  };
  bool has_cut(uint32_t cell) const;
  bool learnt(uint32_t cell) const;
  uint32_t cluster_of(const View& v, uint32_t light) const;
  // Probability of cluster k in the cell's CDF: the exact width of its interval.
  float cdf_width(const View& v, uint32_t k) const;
  View view(uint32_t cell) const;
  // Light inside cluster node `node` covering [begin, end), and its probability.
  SampledLight sample_within(const LightContext& ctx, uint32_t node, uint32_t begin, uint32_t end, double u) const;
  float pmf_within(const LightContext& ctx, uint32_t node, uint32_t begin, uint32_t end, uint32_t light) const;
  // The full pmf of light l in cluster k (which contains it), and the cluster's probability.
  // `within` is pmf_within(l), already known to the caller.
  // `path`: a descent from the root that reached l, if the caller has one (saves the reach).
  float mixture_pmf(const LightContext& ctx, const View& v, uint32_t k, uint32_t l, float within,
                    const DescentPath* path, float* cluster_pmf) const;
  void refresh_light_powers(const Scene& scene);

  const LightTree& m_tree;
  RllSettings m_s;
  CellKeyer m_keyer;
  std::unique_ptr<CellTable> m_table;
  std::unique_ptr<CutStore> m_cuts;
  std::unique_ptr<std::atomic<uint32_t>[]> m_last_used;  // pass of last lookup, per cell
  std::vector<double> m_power_prefix;                    // per light, tree order
  std::vector<uint8_t> m_was_active;  // end_pass scratch: cells that had a cut before the pass
  uint64_t m_pass = 0;
  bool m_frozen = false;
  // Statistics.
  uint64_t m_evictions = 0, m_failed_inserts = 0;
  std::vector<uint32_t> m_splits_per_pass, m_collapses_per_pass, m_touched_per_pass;
};

}  // namespace rll
