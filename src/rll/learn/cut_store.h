// RLL's learner of cuts, on the shared cut arrays (learn/cut_arrays.h: per cell, a cut of K <= M
// nodes of the light tree and its sampling CDF, which ltc uses too): per cluster, the learnt mean
// Q and second moment M2 of its reward and a prior weight, the CDF baked at the end of each pass
// with the defensive prior folded in, and the reward accumulators of the pass. All of it is flat
// arrays indexed by cell * M + k (structure of arrays, nothing allocated per sample).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "rll/core/binary_io.h"
#include "rll/learn/cell_grid.h"
#include "rll/learn/cut.h"
#include "rll/learn/cut_arrays.h"
#include "rll/learn/cut_settings.h"
#include "rll/learn/moments.h"
#include "rll/lighttree/light_tree.h"

namespace rll {

// What sampling from a CutStore and recording rewards read and write (DESIGN 6): the shared cut
// arrays (per cell, the cut and its baked CDF; the initial cut), and rll's own: the guided and
// target factors, the defensive weight, the anchor, the unit of the sums, and the exact sums and
// counts of this pass.
struct CutStoreView : CutArraysView {
  View<const float> gl, gr;  // guided descent only (empty otherwise): CutStore::guide_left/right
  View<const float> vis;     // per cluster: CutStore::target_factor (nee.target=learnt)
  View<const float> eps;     // per cell: the defensive weight during this pass
  View<CellAnchor> anchor;
  View<const double> inv_unit;  // per cell: 1 / the unit of its sums during this pass
  View<ExactSum> sum, sq;       // per cluster: rewards and their squares
  View<uint32_t> count;         // per cluster: rewards this pass
  // rll.refine only (empty otherwise): per cluster, the sum and count of this pass's rewards from
  // points in the upper half of the cell's box along the pass's axis; per cell, refined.
  View<ExactSum> up;
  View<uint32_t> up_count;
  View<const uint8_t> refined;
};

// Adds one reward to cluster k of `cell` (see CutStore::record); `upper`: the point lies in the
// upper half of the cell along this pass's axis (noted only with rll.refine).
RLL_HD inline void cut_record(const CutStoreView& v, uint32_t cell, uint32_t k, float reward,
                              bool upper = false) {
  const size_t i = size_t(cell) * v.m + k;
  const double x = double(reward) * v.inv_unit[cell];
  add_reward(v.sum[i], v.sq[i], x);
  atomic_add(&v.count[i], 1u);
  if (upper && !v.up.empty()) {
    if (x > 0) v.up[i].add(x);  // (the same fixed point as the sum: exact in any order)
    atomic_add(&v.up_count[i], 1u);
  }
}

// What the end of pass did to one cell (CutStore::end_pass, cut_end_pass).
struct CutPassStats {
  uint32_t splits = 0, collapses = 0;
  uint32_t changes = 0;  // clusters whose rewards failed the change test (forget=changes)
  bool touched = false;
};

struct CutStoreEndView;

class CutStore {
 public:
  // Checks the settings (check_cut_settings, errors naming PREFIX.KEY: the sampler's own).
  CutStore(const LightTree& tree, uint32_t cells, const CutSettings& settings, double reward_scale,
           const std::string& prefix = "rll");
  // The memory a store of `cells` cells of cuts of `cut_size` clusters takes (bytes()).
  // Pooling in `pool_tiers` tiers (0: off) adds, per cell, its coarse shares and at most one
  // coarse cell's Q, M2 and weights per tier.
  // Refinement (rll.refine > 0) adds, per cluster, the upper half's sum and count, and a flag per
  // cell.
  static size_t bytes_for(uint32_t cells, int cut_size, bool guided = false, int pool_tiers = 0,
                          bool refine = false);

  const CutSettings& settings() const { return m_s; }
  int max_size() const { return m_m; }

  // The shared initial cut: the clusters of cells that have no cut of their own yet.
  uint32_t initial_size() const { return uint32_t(m_cuts.initial.size()); }
  const uint32_t* initial_ends() const { return m_cuts.initial_ends.data(); }
  const uint32_t* initial_nodes() const { return m_cuts.initial.data(); }

  // The shared cut arrays (read only: the end of pass writes them).
  const CutArrays& cuts() const { return m_cuts; }
  bool active(uint32_t cell) const { return m_cuts.active(cell); }
  uint32_t size(uint32_t cell) const { return m_cuts.size[cell]; }
  const uint32_t* ends(uint32_t cell) const { return m_cuts.ends(cell); }
  const uint32_t* nodes(uint32_t cell) const { return m_cuts.nodes(cell); }
  const float* cdf(uint32_t cell) const { return m_cuts.cdf_of(cell); }
  const float* q(uint32_t cell) const { return &m_q[size_t(cell) * m_m]; }
  const float* m2(uint32_t cell) const { return &m_m2[size_t(cell) * m_m]; }
  // The weight, in rewards, behind each cluster's q and m2 (its memory: every reward seen, or
  // at most 1/alpha of them since the last change, as rll.forget says).
  const float* memory(uint32_t cell) const { return &m_n[size_t(cell) * m_m]; }
  // Guided descent: the inner nodes above a cell's cut are one per boundary between adjacent
  // clusters j and j + 1 (the node whose children meet there); guide_left(cell)[j] and
  // guide_right(cell)[j] are the factors of that node's first and second child: the mean of
  // their clusters' factors g(k) = (1 - e) rho(k) / mean rho + e, weighted by the prior at the
  // anchor, e the cell's defensive weight and rho the learnt ratio (1 everywhere before the cell
  // has learnt: the light tree itself).
  const float* guide_left(uint32_t cell) const { return &m_gl[size_t(cell) * m_m]; }
  const float* guide_right(uint32_t cell) const { return &m_gr[size_t(cell) * m_m]; }
  // Resampled NEE's learnt target (nee.target=learnt, docs/nee.md): per cluster of the cut, the
  // factor t(k) = (1 - e) rho(k) / mean rho + e, rho(k) = V(k) / prior(k) the learnt value over
  // the visibility-blind prior share (guided: the learnt ratio itself, t = g), the mean weighted
  // by the prior, e the cell's defensive weight: so t >= e > 0, and t = 1 everywhere before the
  // cell has learnt. Baked with the table; recomputed, not saved, by load_cell.
  const float* target_factor(uint32_t cell) const { return &m_vis[size_t(cell) * m_m]; }
  // False while the cell has learnt nothing (every value zero): its CDF is then the prior's.
  bool learnt(uint32_t cell) const { return m_learnt[cell] != 0; }
  // The weight of the defensive term for this cell during this pass (1 before it learnt).
  float defensive_weight(uint32_t cell) const { return m_eps[cell]; }
  // Rewards the cell has received in earlier passes (huge for a cell the oracle assigned).
  float rewards_seen(uint32_t cell) const { return m_seen[cell]; }
  // The learnt distribution of the cell's clusters, V(s) / sum V (V = sqrt(M2) or Q), before the
  // defensive prior is mixed in; empty while the cell has learnt nothing. For tests and tools.
  std::vector<double> learnt_shares(uint32_t cell) const;

  // Called when a cell is created, from any thread: its anchor for prior weights.
  void set_anchor(uint32_t cell, const CellAnchor& a) { m_anchor[cell] = a; }
  const CellAnchor& anchor(uint32_t cell) const { return m_anchor[cell]; }

  // Adds one reward to cluster k of `cell` (an index in the cell's cut, or in the initial cut
  // for a cell without one). Thread-safe and never loses an update: sums are exact, so the
  // result does not depend on the order threads deliver rewards in. The unit of a cell's sums
  // is its own largest learnt sqrt(M2) (the brightest light's largest irradiance until it has
  // one), fixed during a pass: rewards from 2^-40 to 2^36 of it and squares from 2^-20 to 2^18
  // are resolved, whatever other lights of the scene emit.
  void record(uint32_t cell, uint32_t k, float reward) { cut_record(view(), cell, k, reward); }
  // The arrays for sampling and cut_record; valid while the store lives (between passes, until
  // end_pass, clear, assign or load_cell change a cell's cut).
  CutStoreView view();

  using PassStats = CutPassStats;
  // What the end of pass reads and writes (learn/cut_end_pass.h): every per-cell array. Valid
  // while the store lives; the const methods pass it only to functions that read.
  CutStoreEndView end_view();
  // End of pass for one cell (cells are independent: call in parallel). A cell without a cut
  // gets the initial one; rewards are folded into Q and M2, split-collapse runs, the CDF is
  // baked.
  PassStats end_pass(uint32_t cell);
  // Light powers or positions changed: recompute prior weights and the CDF of a cell.
  void refresh(uint32_t cell);
  // Pooling: adds the pass's rewards of `cell` (under the shared cut's indices) in absolute
  // units to sum, sq and count (each K = initial_size() long); with pool_ratio, each divided by
  // the cell's prior share of its cluster (cell_prior).
  void add_pass_rewards(uint32_t cell, double* sum, double* sq, uint64_t* count) const;
  // The normalized prior of every cluster of the cell's cut, as its baked table mixes it in (of
  // the initial cut at the cell's anchor while it has no cut).
  void cell_prior(uint32_t cell, std::vector<double>& out) const;
  // Pooling: the coarse distribution the cell's values are shrunk toward (K shares; nullptr:
  // none, the prior as without pooling). Called between passes, before end_pass.
  void set_pool(uint32_t cell, const float* shares);
  // Pooling: the shares set_pool gave the cell (initial_size() of them), nullptr if none.
  const float* pool_shares(uint32_t cell) const {
    return !m_has_pool.empty() && m_has_pool[cell] ? &m_pool[size_t(cell) * m_m] : nullptr;
  }
  // Forgets a cell (eviction).
  void clear(uint32_t cell);
  // rll.refine: the cell's points look up the cell one level finer (cut_refine_test marked it).
  bool refined(uint32_t cell) const { return !m_refined.empty() && m_refined[cell] != 0; }
  // Gives a cell a cut with known values (the oracle; value = mean): prior weights from the
  // cell's anchor, and only the configured defensive weight.
  void assign(uint32_t cell, const std::vector<uint32_t>& nodes, const std::vector<float>& q);

  size_t bytes() const;

  // A cell's learnt state between passes (cut, values, prior weights, CDF, anchor), for saved
  // sampler states. load_cell checks what it reads against the tree and throws rll::Error
  // naming the file if the state could not have been written by save_cell.
  void save_cell(uint32_t cell, BinaryWriter& w) const;
  void load_cell(uint32_t cell, BinaryReader& r);

 private:
  CutStoreEndView end_view() const;

  const LightTree& m_tree;
  CutSettings m_s;
  int m_m;
  double m_scale;     // the unit of a cell's sums before it has learnt anything
  double m_log_keep;  // log(1 - alpha)

  CutArrays m_cuts;  // per cell: the cut and its CDF; the initial cut
  std::vector<float> m_q, m_m2, m_n, m_weight;
  std::vector<float> m_gl, m_gr;  // guided descent only (empty otherwise)
  std::vector<float> m_vis;       // per cluster: target_factor
  std::vector<uint8_t> m_learnt;  // per cell: sum of values > 0
  std::vector<float> m_seen;      // per cell: rewards received so far
  std::vector<float> m_eps;       // per cell: defensive weight, frozen during a pass
  std::vector<CellAnchor> m_anchor;
  std::vector<float> m_pool;                // pooling: per cluster, the coarse cell's share
  std::vector<uint8_t> m_has_pool;          // pooling: per cell, m_pool holds shares
  std::vector<double> m_inv_unit;           // per cell: 1 / the unit of its sums during this pass
  std::unique_ptr<ExactSum[]> m_sum, m_sq;  // per cluster: rewards and their squares
  std::unique_ptr<uint32_t[]> m_count;      // per cluster: rewards this pass
  // rll.refine only: per cluster, the upper half's rewards this pass; per cell, refined.
  std::unique_ptr<ExactSum[]> m_up;
  std::vector<uint32_t> m_up_count;
  std::vector<uint8_t> m_refined;
};

}  // namespace rll
