// Reinforcement Lightcuts Learning (Pantaleoni), rebuilt to DESIGN.md section 2b: per cell of
// a 5D hash grid, a learnt cut of the light tree with the mean and second moment of each
// cluster's reward; NEE picks a cluster from the cell's baked table (the defensive prior folded
// in), then a light inside it from a static table or a short descent. Every NEE sample rewards
// its cluster; between passes the rewards are folded in and the tables are baked again. A cell's
// cut stays the initial cut unless rll.splits > 0 (fermat's settings: 1; rll's default is 0,
// the pooled cut every cell shares): then each pass splits where the variance is and collapses
// where the clusters are darkest (learn/split_collapse.h). The light tree is the render
// session's, lent to the sampler for its lifetime.
#pragma once

#include <functional>
#include <memory>
#include <vector>

#include "rll/learn/cell_grid.h"
#include "rll/learn/cut_store.h"
#include "rll/lights/light_sampler.h"
#include "rll/lights/resident.h"
#include "rll/lights/rll_end_pass.h"
#include "rll/lights/rll_settings.h"
#include "rll/lights/rll_view.h"
#include "rll/lights/tree_sampler.h"

namespace rll {

// Its Rll view (rll_view.h) is what every renderer samples with; the view learns until freeze().
class RllLightSampler final : public LightSampler, public ResidentLearner {
 public:
  RllLightSampler(const Scene& scene, const LightTree& tree, const RllSettings& settings);
  ~RllLightSampler() override;
  // On the device's copy where one holds the state (lent_to), else on the host's arrays.
  void end_pass() override;
  void lights_changed(const Scene& scene) override;
  nlohmann::json describe() const override;
  // The cells in use, their keys, last use and cuts, and the pass count; not the statistics.
  void save_state(BinaryWriter& w) const override;
  void load_state(BinaryReader& r) override;
  SamplerView sampler_view() const override;

  // The end of pass with its whole-array work (rll_end_pass over this sampler's learning arrays,
  // its pool and the cells in use at the last rebuild; with Fermat's reset) done by `run` (the
  // GPU's checks: cuda/endpass_check.h), the bookkeeping (the statistics, the pass, the keyer's
  // jitter, the table's count) as end_pass does it. Does not pull a device's copy (below).
  using EndPassRun = std::function<RllPassCounts(const RllLearnView& v,
                                                 RllPoolState<HostBackend>& pool,
                                                 uint32_t used_before, bool reset)>;
  void end_pass_with(const EndPassRun& run);

  // The learning state may live on a device between passes and renders (lights/resident.h):
  // lent to a DeviceCopy, it stays there until the host reads or changes it. Everything on the
  // host that does (save and load, describe, sampler_view, cuts, table, pool) pulls it back first
  // (sync); end_pass and lights_changed run on the copy. Sampling reads the view, which
  // sampler_view() hands out after a sync.
  ResidentState resident_state() override;
  void lend_to(DeviceCopy& copy) override;
  void sync() const override;
  const DeviceCopy* lent_to() const { return m_remote; }
  // For tests: the coarse cells of pooling.
  const RllPoolState<HostBackend>& pool() const {
    sync();
    return m_pool;
  }

  // Stops learning: the view records nothing and end_pass() does nothing from now on (the
  // oracle).
  void freeze() {
    m_frozen = true;
    set_resident_learner(nullptr);
  }
  // For tests and the oracle: the learnt state.
  const CutStore& cuts() const {
    sync();
    return *m_cuts;
  }
  CutStore& cuts() {
    sync();
    return *m_cuts;
  }
  const CellTable& table() const {
    sync();
    return *m_table;
  }
  uint64_t passes() const { return m_pass; }
  size_t bytes() const;

 private:
  // What the end of pass reads and writes (rll_end_pass.h), this sampler's host arrays, without
  // pulling.
  RllLearnView learn_view();
  // Points m_view at this sampler's arrays, pass and keyer (after anything that changes them),
  // and tells a device's copy that holds the state.
  void refresh_view();
  void refresh_light_powers(const Scene& scene);

  // The coarse cells of pooling (rll_end_pass.h): keys ascending, and per coarse cell Q, M2 and
  // reward weight of each cluster of the shared cut (initial_size() per coarse cell, key order).
  // (mutable: sync, from const readers, pulls a device's copy into it and the arrays.)
  mutable RllPoolState<HostBackend> m_pool;
  mutable DeviceCopy* m_remote = nullptr;  // the device's copy that holds the state, if any
  RllScratch<HostBackend> m_scratch;  // the end of pass's, kept between passes

  const LightTree& m_tree;  // the render session's (it outlives its samplers)
  RllSettings m_s;
  CellKeyer m_keyer;
  std::unique_ptr<CellTable> m_table;
  std::unique_ptr<CutStore> m_cuts;
  std::vector<uint32_t> m_last_used;  // pass of last lookup, per cell
  // A new cell's anchor is the mean of the points that used it in its first pass (a point on
  // the surfaces it covers, where the box centre may lie behind a wall or above a lamp): exact
  // fixed-point sums of position (units of 2^-24 of the scene diameter) and normal, and a count.
  static constexpr int kPointWords = kRllPointWords;
  std::vector<uint64_t> m_points;
  Vec3 m_origin;
  float m_extent = 1;
  std::vector<double> m_power_prefix;  // per light, tree order
  uint64_t m_pass = 0;
  uint64_t m_resets = 0;
  bool m_warned_full = false;
  bool m_frozen = false;
  // Statistics.
  uint64_t m_evictions = 0, m_failed_inserts = 0;
  std::vector<uint32_t> m_splits_per_pass, m_collapses_per_pass, m_touched_per_pass;
  // Clusters whose rewards failed the change test (forget=changes), of cells and of coarse cells.
  std::vector<uint32_t> m_changes_per_pass, m_pool_changes_per_pass;
  std::vector<uint32_t> m_refined_per_pass;  // rll.refine: cells the test marked, per pass
  RllView m_view;  // what rll_prepare, rll_sample, rll_pmf and rll_record read (rll_view.h)
};

}  // namespace rll
