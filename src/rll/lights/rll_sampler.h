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
#include "rll/lights/rll_end_pass.h"
#include "rll/lights/rll_settings.h"
#include "rll/lights/rll_view.h"
#include "rll/lights/tree_sampler.h"

namespace rll {

class RllLightSampler final : public LightSampler {
 public:
  RllLightSampler(const Scene& scene, const LightTree& tree, const RllSettings& settings);
  std::string name() const override { return m_s.name; }
  void prepare(LightContext& ctx, float u) const override;
  bool prepares() const override { return true; }
  SampledLight sample(const LightContext& ctx, double u) const override;
  float pmf(const LightContext& ctx, uint32_t light) const override;
  bool learns() const override { return !m_frozen; }
  void record(const LightContext& ctx, const SampledLight& s, const NeeRecord& r) override;
  void end_pass() override;
  void lights_changed(const Scene& scene) override;
  nlohmann::json describe() const override;
  // The cells in use, their keys, last use and cuts, and the pass count; not the statistics.
  bool has_state() const override { return true; }
  void save_state(BinaryWriter& w) const override;
  void load_state(BinaryReader& r) override;
  SamplerView sampler_view() const override;

  // The end of pass with its whole-array work (rll_end_pass over this sampler's learning arrays,
  // its pool and the cells in use at the last rebuild; with Fermat's reset) done by `run`, on
  // another device (the GPU: cuda/device_rll.cuh, cuda/endpass_check.h), the bookkeeping (the
  // statistics, the pass, the keyer's jitter, the table's count) as end_pass does it. Does not
  // pull a remote state (below): run works on the device's copy.
  using EndPassRun = std::function<RllPassCounts(const RllLearnView& v,
                                                 RllPoolState<HostBackend>& pool,
                                                 uint32_t used_before, bool reset)>;
  void end_pass_with(const EndPassRun& run);
  // The learning state may live on a device between passes and renders (`rll render --device
  // cuda`, `rll interactive`): set_remote says so, with `pull`, which copies the device's arrays
  // back into this sampler's and its coarse cells into `pool`; `remote` is the device state's
  // token (null: the host's arrays are current). Everything on the host that reads or changes
  // the learnt state (end_pass, save and load, describe, sampler_view, cuts, table, pool) pulls
  // first (sync) and the state is the host's again. prepare, sample, pmf and record do not
  // (they are the CPU renderers' hot path, which reach the sampler through sampler_view or
  // end_pass first; a session with a GPU renders every pass there). lights_changed hands the
  // new light tree and powers to `lights` where one is given, which runs it on the device's
  // copy (rll_lights_changed), else it pulls too.
  using RemoteLightsChanged =
      std::function<void(const LightTreeView& tree, View<const double> power_prefix)>;
  void set_remote(const void* token, std::function<void(RllPoolState<HostBackend>& pool)> pull,
                  RemoteLightsChanged lights = {}) {
    m_remote = token;
    m_pull = std::move(pull);
    m_remote_lights = std::move(lights);
  }
  const void* remote() const { return m_remote; }
  void sync() const;
  // What the end of pass reads and writes (rll_end_pass.h), this sampler's host arrays, without
  // pulling (for a device's copy).
  RllLearnView learn_view();
  // The sampling view (its pass, keyer and free cells) without pulling: for the device's copy.
  const RllView& rll_view() const { return m_view; }
  // For tests: the coarse cells of pooling.
  const RllPoolState<HostBackend>& pool() const {
    sync();
    return m_pool;
  }

  // Stops learning: record() and end_pass() do nothing from now on (the oracle).
  void freeze() { m_frozen = true; }
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
  // Points m_view at this sampler's arrays, pass and keyer (after anything that changes them).
  void refresh_view();
  void refresh_light_powers(const Scene& scene);

  // The coarse cells of pooling (rll_end_pass.h): keys ascending, and per coarse cell Q, M2 and
  // reward weight of each cluster of the shared cut (initial_size() per coarse cell, key order).
  // (mutable: sync, from const readers, pulls a device's copy into it and the arrays.)
  mutable RllPoolState<HostBackend> m_pool;
  mutable const void* m_remote = nullptr;
  mutable std::function<void(RllPoolState<HostBackend>&)> m_pull;
  mutable RemoteLightsChanged m_remote_lights;
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
  RllView m_view;  // what prepare, sample, pmf and record read (rll_view.h)
};

}  // namespace rll
