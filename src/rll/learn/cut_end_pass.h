// RLL's end of pass for one cell as host-and-device functions over a mutable view of a CutStore
// (DESIGN 2 "End of pass", DESIGN 6): the prior, the effective values, the fold of the pass's
// rewards into Q, M2 and n, split-collapse, and the bake of the CDF and of the guided factors.
// Cells are independent: the CPU runs cut_end_pass through host_parallel_for over the cells in
// use, a GPU through cuda::parallel_for (cuda/endpass_check.cu); CutStore's methods forward
// here. No allocation: a cell's cut is edited in place in its slice of the store (M clusters of
// room), and its scratch is its slice of an arena sized by the cells' cuts (CutScratch), which the
// caller allocates once for all the cells of a loop.
#pragma once

#include <cmath>
#include <cstdint>

#include "rll/core/device.h"
#include "rll/core/search.h"
#include "rll/learn/cut_store.h"
#include "rll/learn/moments.h"
#include "rll/learn/split_collapse.h"

namespace rll {

// The shared cut arrays and every per-cell array of rll's CutStore, writable: what the end of
// pass reads and writes.
struct CutStoreEndView : CutArraysRwView {
  CutSettings s;
  LightTreeView tree;
  double scale = 1;     // the unit of a cell's sums before it has learnt anything
  double log_keep = 0;  // log(1 - alpha), the exponential rule's
  View<float> q, m2, n, weight;
  View<float> gl, gr;  // guided descent only (empty otherwise)
  View<float> vis;     // per cluster: CutStore::target_factor
  View<uint8_t> learnt;
  View<float> seen, eps;
  View<CellAnchor> anchor;
  View<float> pool;        // pooling only: per cluster, the coarse cell's share
  View<uint8_t> has_pool;  // pooling only: per cell
  View<double> inv_unit;
  View<ExactSum> sum, sq;
  View<uint32_t> count;
  View<ExactSum> up;        // rll.refine only: CutStoreView::up
  View<uint32_t> up_count;  // rll.refine only: CutStoreView::up_count
  View<uint8_t> refined;    // rll.refine only: per cell
};

// One cell's scratch during the end of pass: per cluster of its room (cut_scratch_room), two
// doubles and three floats, in the named arrays below. The functions that take one say which
// arrays they use; a function never hands an array it uses to one it calls.
struct CutScratch {
  double* pri;   // the prior of the cell's clusters
  double* g;     // guided factors (cut_bake_guide), target factors (cut_bake_target)
  float* val;    // effective values; pooling's shares
  float* score;  // split scores; pooling's coarser shares (pool_up)
  float* w;      // prior weights of the initial cut (cut_cell_prior)
};

// The clusters a cell's scratch must hold this pass: its cut (the initial one while it has none)
// and the clusters split-collapse may add, at most M.
RLL_HD inline uint32_t cut_scratch_room(const CutStoreEndView& v, uint32_t cell) {
  const uint32_t K = v.active(cell) ? v.size[cell] : uint32_t(v.initial.size);
  return std::min(v.m, K + uint32_t(std::max(v.s.splits, 0)));
}

// An arena of scratch for many cells (or coarse cells): cell i's slice starts at cluster offset
// offset[i] (an exclusive scan of the rooms) and holds room clusters.
struct CutScratchArena {
  static constexpr size_t kDoubles = 2, kFloats = 3;  // per cluster of room
  View<double> d;                                     // kDoubles per cluster of room in all
  View<float> f;                                      // kFloats per cluster of room in all

  RLL_HD CutScratch slice(uint64_t offset, uint32_t room) const {
    // Pointer arithmetic, not &d[i]: an empty arena (room 0) has no element to bind to.
    double* d0 = d.data + size_t(offset) * kDoubles;
    float* f0 = f.data + size_t(offset) * kFloats;
    return {d0, d0 + room, f0, f0 + room, f0 + 2 * size_t(room)};
  }
};

// Scratch for one cell at a time on the host (CutStore's methods, tests): an arena of one slice.
class HostCutScratch {
 public:
  explicit HostCutScratch(uint32_t room)
      : m_d(room * CutScratchArena::kDoubles), m_f(room * CutScratchArena::kFloats), m_room(room) {}
  operator CutScratch() { return CutScratchArena{view_of(m_d), view_of(m_f)}.slice(0, m_room); }

 private:
  std::vector<double> m_d;
  std::vector<float> m_f;
  uint32_t m_room;
};

namespace detail {
// Shares of the prior that follow power, and that are uniform over the clusters with power,
// so that every cluster with power keeps a probability the float CDF can represent, even where
// the importance at the anchor is zero (a cluster's power can be 1e-7 of a sky dome's).
inline constexpr double kPowerShare = 0.04;
inline constexpr double kUniformShare = 0.01;

// The guided bake's sums over the clusters under a node.
struct GuideSums {
  double w = 0, wg = 0, g = 0, count = 0;
  RLL_HD double factor() const { return w > 0 ? wg / w : g / count; }
};
}  // namespace detail

// The prior weight of `node` entering the cut of `cell`: its importance at the cell's anchor,
// its power, or 1 (CutSettings::prior).
RLL_HD inline float cut_weight_of(const CutStoreEndView& v, uint32_t cell, uint32_t node) {
  if (v.s.prior == ClusterWeight::Power) return v.tree.node(node).bounds.power;
  if (v.s.prior == ClusterWeight::Uniform) return 1.0f;
  return tree_importance(v.tree, node, v.anchor[cell].p, v.anchor[cell].n);
}

// The normalized prior of K clusters (nodes, prior weights): (1 - power_share - uniform) *
// weight + power_share * power + uniform / count over the clusters with power; uniform where
// nothing emits; under ClusterWeight::Uniform (Fermat's) every cluster alike, no floor.
RLL_HD inline void cut_prior(const CutStoreEndView& v, const uint32_t* nodes, const float* weight,
                             size_t K, double* out) {
  if (v.s.prior != ClusterWeight::Uniform) {
    const double power_share =
        v.s.prior == ClusterWeight::Power ? 1.0 - detail::kUniformShare : detail::kPowerShare;
    auto power = [&](size_t k) {
      return std::max(0.0, double(v.tree.node(nodes[k]).bounds.power));
    };
    double psum = 0, wsum = 0;
    size_t with_power = 0;
    for (size_t k = 0; k < K; ++k) {
      const double p = power(k);
      psum += p;
      wsum += std::max(0.0, double(weight[k]));
      with_power += p > 0;
    }
    if (psum > 0) {
      const double ps = wsum > 0 ? power_share : 1.0 - detail::kUniformShare;
      const double ws = (1 - ps - detail::kUniformShare) / (wsum > 0 ? wsum : 1.0);
      const double us = detail::kUniformShare / double(with_power);
      for (size_t k = 0; k < K; ++k) {
        const double p = power(k);
        out[k] = ws * std::max(0.0, double(weight[k])) + ps * p / psum + (p > 0 ? us : 0.0);
      }
      return;
    }
  }
  for (size_t k = 0; k < K; ++k) out[k] = 1.0 / double(K);  // (nothing emits: uniform)
}

// The prior of the cell's cut as its baked table mixes it in (of the initial cut at the cell's
// anchor while it has no cut). Scratch: w.
RLL_HD inline void cut_cell_prior(const CutStoreEndView& v, uint32_t cell, double* out,
                                  const CutScratch& scratch) {
  if (v.active(cell)) {
    const size_t b = v.base(cell);
    cut_prior(v, &v.node[b], &v.weight[b], v.size[cell], out);
    return;
  }
  float* w = scratch.w;
  for (size_t k = 0; k < v.initial.size; ++k) w[k] = cut_weight_of(v, cell, v.initial[k]);
  cut_prior(v, v.initial.data, w, v.initial.size, out);
}

// The effective target value of the first K clusters of the cell's slice: sqrt(M2) or Q where
// visited, else the prior's share of what the visited clusters say the cell's total is (guided:
// ratios, the visited clusters' mean ratio); with pooling, shrunk toward the coarse cell's shares.
RLL_HD inline void cut_values(const CutStoreEndView& v, uint32_t cell, size_t K, const double* pri,
                              float* out) {
  const size_t b = v.base(cell);
  const float* q = &v.q[b];
  const float* m2 = &v.m2[b];
  const bool moment = v.s.target == LearnTarget::Moment;
  // What the visited clusters say the cell's total is.
  VisitedTotal sums;
  for (size_t k = 0; k < K; ++k) {
    if (q[k] < 0) continue;
    out[k] = target_value(moment, q[k], m2[k]);
    sums.add(out[k], pri[k]);
  }
  if (v.s.guided) {
    // Ratios to the tree's importance: a cluster never visited gets the visited clusters' mean
    // ratio, weighted by prior. (Guided excludes pooling.)
    double wv = 0;
    for (size_t k = 0; k < K; ++k)
      if (q[k] >= 0) wv += pri[k] * out[k];
    const float mean = sums.shares > 0 ? float(wv / sums.shares) : 0.0f;
    for (size_t k = 0; k < K; ++k)
      if (q[k] < 0) out[k] = mean;
    return;
  }
  const double total = sums.total();
  for (size_t k = 0; k < K; ++k)
    if (q[k] < 0) out[k] = v.s.q_init >= 0 ? v.s.q_init : float(total * pri[k]);
  if (v.has_pool.empty() || !v.has_pool[cell]) return;
  shrink_toward(
      K, [&](size_t k) { return q[k] >= 0; }, &v.n[b], &v.pool[b], v.s.pool_weight, out);
}

// Guided descent: each cluster's factor g(k) = (1 - e) rho(k) / mean rho + e: the learnt ratios
// (val) relative to their prior-weighted mean, mixed with 1 (the tree's own step) by the
// defensive weight e, so that g >= e > 0.
RLL_HD inline void guide_factors(size_t K, const double* pri, const float* val, double eps,
                                 double* g) {
  double wsum = 0, wv = 0;
  for (size_t k = 0; k < K; ++k) {
    wsum += pri[k];
    wv += pri[k] * val[k];
  }
  const double mean = wsum > 0 ? wv / wsum : 0.0;
  for (size_t k = 0; k < K; ++k) g[k] = mean > 0 ? (1 - eps) * double(val[k]) / mean + eps : 1.0;
}

// Guided descent: bakes the cell's guide_left/right from its values and prior (CutStore's
// guide_left says what they are). The inner nodes above the cut are visited from the root as a
// recursion would (children's sums first, left then right, added in the same order), without a
// stack (a frame per level was 14 KB of every GPU thread's stack): up through the tree's parent
// links, each node's clusters found again from its range (a cut is a union of tree nodes), and
// the sums of a finished first child kept in the factors of its clusters, which are read once,
// at the cluster, and not needed again (cut_bake_target overwrites them). Scratch: g.
RLL_HD inline void cut_bake_guide(const CutStoreEndView& v, uint32_t cell, uint32_t K,
                                  const double* pri, const float* val, double eps,
                                  const CutScratch& scratch) {
  const size_t b = v.base(cell);
  double* g = scratch.g;
  guide_factors(K, pri, val, eps, g);
  if (K < 2) return;
  // Every inner node above the cut: its children's factors are the prior-weighted means of
  // their clusters' g (the unweighted mean where no cluster has prior).
  const uint32_t* ends = &v.end[b];
  auto leaf = [&](uint32_t k) { return detail::GuideSums{pri[k], pri[k] * g[k], g[k], 1}; };
  // The sums of a first child over clusters [k0, j], parked in g[k0, j] while its sibling is
  // visited: one cluster's are its own (g[k0] untouched); two clusters' weight is the sum of
  // their priors, which stay.
  auto park = [&](const detail::GuideSums& s, uint32_t k0, uint32_t j) {
    if (j - k0 >= 2) g[k0 + 2] = s.w;
    if (j - k0 >= 1) {
      g[k0] = s.wg;
      g[k0 + 1] = s.g;
    }
  };
  auto unpark = [&](uint32_t k0, uint32_t j) -> detail::GuideSums {
    if (j == k0) return leaf(k0);
    const double w = j - k0 >= 2 ? g[k0 + 2] : pri[k0] + pri[k0 + 1];
    return {w, g[k0], g[k0 + 1], double(j - k0 + 1)};
  };
  uint32_t node = LightTree::kRoot, k0 = 0, k1 = K;  // a subtree and its clusters [k0, k1)
  for (;;) {
    // Down the first children to the subtree's first cluster.
    while (k1 - k0 > 1) {
      const LightTreeNode& nd = v.tree.node(node);
      k1 = children_boundary(v.tree, nd, ends, k0, k1) + 1;
      node = nd.child;
    }
    detail::GuideSums done = leaf(k0);  // the sums of the subtree last finished
    // Up while the finished subtree is a second child: its parent is finished too.
    for (;;) {
      if (node == LightTree::kRoot) return;
      const uint32_t parent = v.tree.node(node).parent;
      const LightTreeNode& pn = v.tree.node(parent);
      if (node == pn.child) {
        // A first child: park its sums, then visit its sibling, whose clusters end with the
        // parent's range.
        park(done, k0, k1 - 1);
        const uint32_t end = pn.end;
        k0 = k1;
        k1 = lower_bound_index(ends, k1, K, end) + 1;
        node = pn.child + 1;
        break;
      }
      // A second child: the first child's clusters start with the parent's range.
      const uint32_t begin = pn.begin, j = k0 - 1;
      k0 = upper_bound_index(ends, 0u, k0, begin);
      const detail::GuideSums a = unpark(k0, j);
      v.gl[b + j] = float(a.factor());
      v.gr[b + j] = float(done.factor());
      done = {a.w + done.w, a.wg + done.wg, a.g + done.g, a.count + done.count};
      node = parent;
    }
  }
}

// Resampled NEE's learnt target (nee.target=learnt): bakes the cell's target factors
// (CutStore::target_factor) from its values and prior, e its defensive weight (1 before it has
// learnt: every factor 1). Without the guided descent the ratios are rho(k) = V(k) / prior(k),
// whose prior-weighted mean is sum V / sum prior; a cluster without prior (it has no power, so
// it contributes nothing) gets 1. Scratch: g.
RLL_HD inline void cut_bake_target(const CutStoreEndView& v, uint32_t cell, uint32_t K,
                                   const double* pri, const float* val, double eps,
                                   const CutScratch& scratch) {
  double* t = scratch.g;
  if (v.s.guided) {
    guide_factors(K, pri, val, eps, t);  // (the values are the ratios already)
  } else {
    double v_sum = 0, p_sum = 0;
    for (size_t k = 0; k < K; ++k) {
      v_sum += val[k];
      p_sum += pri[k];
    }
    const double mean = p_sum > 0 ? v_sum / p_sum : 0.0;
    for (size_t k = 0; k < K; ++k)
      t[k] = mean > 0 && pri[k] > 0 ? (1 - eps) * (double(val[k]) / pri[k]) / mean + eps : 1.0;
  }
  const size_t b = v.base(cell);
  for (size_t k = 0; k < K; ++k) v.vis[b + k] = float(t[k]);
}

// Bakes the cell's table from the first K clusters of its slice: P(s) = (1 - e) V(s) / sum V +
// e prior(s), e the cell's defensive weight (folded in here when the prior lives in the CDF);
// without any learnt value, the prior alone. Sets the cell's size, range ends, learnt flag and
// defensive weight, its target factors, and with the guided descent its factors. Scratch: pri,
// val, g.
RLL_HD inline void cut_bake(const CutStoreEndView& v, uint32_t cell, uint32_t K,
                            const CutScratch& scratch) {
  double* pri = scratch.pri;
  float* val = scratch.val;
  const size_t b = v.base(cell);
  v.size[cell] = K;
  cut_prior(v, &v.node[b], &v.weight[b], K, pri);
  cut_values(v, cell, K, pri, val);
  double v_sum = 0;
  for (size_t k = 0; k < K; ++k) v_sum += val[k];
  v.learnt[cell] = v_sum > 0;
  // (trust = 0: the configured weight from the start, also for a cell without rewards yet.)
  const float distrust = v.s.trust > 0 ? v.s.trust / (v.s.trust + v.seen[cell]) : 0.0f;
  v.eps[cell] = v_sum > 0 ? v.s.epsilon + (1 - v.s.epsilon) * distrust : 1.0f;
  const double eps = v_sum > 0 ? (v.s.prior_in_cdf ? v.eps[cell] : 0.0) : 1.0;
  double acc = 0;
  for (size_t k = 0; k < K; ++k) {
    acc += (1 - eps) * (v_sum > 0 ? val[k] / v_sum : 0.0) + eps * pri[k];
    v.cdf[b + k] = float(acc);
    v.end[b + k] = v.tree.node(v.node[b + k]).end;
  }
  for (size_t k = 0; k < K; ++k) v.cdf[b + k] = float(std::min(1.0, double(v.cdf[b + k]) / acc));
  v.cdf[b + K - 1] = 1.0f;
  const double target_eps = v_sum > 0 ? v.eps[cell] : 1.0;
  if (v.s.guided) cut_bake_guide(v, cell, K, pri, val, target_eps, scratch);
  cut_bake_target(v, cell, K, pri, val, target_eps, scratch);
}

// Light powers or positions changed: the cell's prior weights anew, and its table. Scratch: as
// cut_bake.
RLL_HD inline void cut_refresh(const CutStoreEndView& v, uint32_t cell, const CutScratch& scratch) {
  if (!v.active(cell)) return;
  const size_t b = v.base(cell);
  for (size_t k = 0; k < v.size[cell]; ++k) v.weight[b + k] = cut_weight_of(v, cell, v.node[b + k]);
  cut_bake(v, cell, v.size[cell], scratch);
}

// The lights changed (forget=changes): every cluster's memory is cut back to the last 1/alpha
// rewards, as if each had failed the change test.
RLL_HD inline void cut_forget(const CutStoreEndView& v, uint32_t cell) {
  if (v.s.forget != Forgetting::Changes || v.s.rule != LearningRule::Shrinkage || !v.active(cell))
    return;
  forget_to_window(&v.n[v.base(cell)], v.size[cell], v.s.alpha);
}

// Forgets a cell (eviction).
RLL_HD inline void cut_clear(const CutStoreEndView& v, uint32_t cell) {
  const size_t b = v.base(cell);
  v.size[cell] = 0;
  v.learnt[cell] = 0;
  v.seen[cell] = 0;
  v.eps[cell] = 1;
  if (!v.has_pool.empty()) v.has_pool[cell] = 0;
  v.inv_unit[cell] = 1 / v.scale;
  for (uint32_t k = 0; k < v.m; ++k) {
    v.sum[b + k].reset();
    v.sq[b + k].reset();
    v.count[b + k] = 0;
  }
  if (!v.refined.empty()) {
    v.refined[cell] = 0;
    for (uint32_t k = 0; k < v.m; ++k) {
      v.up[b + k].reset();
      v.up_count[b + k] = 0;
    }
  }
}

// rll.refine: how much giving each half of the cell's box (along the pass's axis, as the rewards'
// `up` sums were noted) its own distribution over the clusters would lower the cost of the
// one-sample estimator, from this pass's rewards (before the fold resets them). I_kh, cluster k's
// mean reward in half h (its mean contribution there), with w_h the half's share of the rewards:
// one distribution for both halves costs at best (sum_k sqrt(sum_h w_h I_kh^2))^2, one per half
// sum_h w_h (sum_k I_kh)^2; the gain is their ratio less 1 (>= 0 by Minkowski's inequality, 0
// where both halves want the same shares). Each I_kh^2 is corrected for the noise of its mean
// (the half's share of the squares, clamped at 0), so that noise alone makes little
// disagreement; a cluster not drawn in one half takes its mean over the cell in both. Only sums of
// integers: the same whatever the order of the rewards.
RLL_HD inline double cut_refine_gain(const CutStoreEndView& v, uint32_t cell) {
  const size_t b = v.base(cell);
  const uint32_t K = v.active(cell) ? v.size[cell] : uint32_t(v.initial.size);
  uint64_t n = 0, n_up = 0;
  for (uint32_t k = 0; k < K; ++k) {
    n += v.count[b + k];
    n_up += v.up_count[b + k];
  }
  if (n_up == 0 || n_up >= n) return 0;
  const double w_up = double(n_up) / double(n), w_lo = 1 - w_up;
  double parent = 0, up = 0, lo = 0;
  for (uint32_t k = 0; k < K; ++k) {
    const uint32_t c = v.count[b + k], c_up = v.up_count[b + k], c_lo = c - c_up;
    if (c == 0) continue;
    const double s = v.sum[b + k].value(), s_up = v.up[b + k].value(), q = v.sq[b + k].value();
    // A mean's square less its noise: (S_h^2 - sq_h) / c_h^2, sq_h the half's share of the squares.
    auto square = [&](double sum, uint32_t count) {
      return std::max(0.0, sum * sum - q * double(count) / double(c)) / (double(count) * count);
    };
    const double whole = square(s, c);
    const double i_up = c_up > 0 && c_lo > 0 ? square(s_up, c_up) : whole;
    const double i_lo = c_up > 0 && c_lo > 0 ? square(s - s_up, c_lo) : whole;
    parent += std::sqrt(w_up * i_up + w_lo * i_lo);
    up += std::sqrt(i_up);
    lo += std::sqrt(i_lo);
  }
  const double children = w_up * up * up + w_lo * lo * lo;
  return children > 0 ? std::max(0.0, parent * parent / children - 1) : 0.0;
}

// rll.refine: a new cell (its first pass ending, no cut yet) whose parent, the cell one level
// coarser around its anchor, is refined and has the shared initial cut starts from the parent's
// values, each cluster's weight capped at pool_weight rewards so that its own rewards soon speak;
// the table is baked by this end of pass (its last CDF entry 0 says so). Reads the parent (a cell
// with a cut, which this does not write): run over all cells before their cut_end_pass.
RLL_HD inline void cut_seed_child(const CutStoreEndView& v, uint32_t cell, uint32_t parent) {
  if (v.refined.empty() || v.active(cell) || parent == ~0u || !v.active(parent) ||
      !v.refined[parent])
    return;
  const uint32_t K = uint32_t(v.initial.size);
  const size_t b = v.base(cell), pb = v.base(parent);
  if (v.size[parent] != K) return;
  for (uint32_t k = 0; k < K; ++k)
    if (v.node[pb + k] != v.initial[k]) return;
  for (uint32_t k = 0; k < K; ++k) {
    v.node[b + k] = v.initial[k];
    v.q[b + k] = v.q[pb + k];
    v.m2[b + k] = v.m2[pb + k];
    v.n[b + k] = std::min(v.n[pb + k], v.s.pool_weight);
    v.weight[b + k] = cut_weight_of(v, cell, v.initial[k]);
  }
  v.inv_unit[cell] = v.inv_unit[parent];
  v.size[cell] = K;
  v.cdf[b + K - 1] = 0.0f;
}

// rll.refine: the disagreement test of the end of pass (before cut_end_pass folds the rewards):
// marks the cell refined where the gain of its halves' own distributions (cut_refine_gain) is
// above refine_gain, with at least refine_min rewards this pass, and its level above the finest;
// the upper halves' sums start again. True where it marked the cell. A refined cell stays so
// until it is evicted.
RLL_HD inline bool cut_refine_test(const CutStoreEndView& v, uint32_t cell) {
  if (v.refined.empty()) return false;
  const size_t b = v.base(cell);
  const uint32_t K = v.active(cell) ? v.size[cell] : uint32_t(v.initial.size);
  uint64_t n = 0;
  for (uint32_t k = 0; k < K; ++k) n += v.count[b + k];
  const bool marked = !v.refined[cell] && n >= uint64_t(v.s.refine_min) &&
                      v.anchor[cell].level > CellKeyer::kFinestLevel &&
                      cut_refine_gain(v, cell) > v.s.refine_gain;
  if (marked) v.refined[cell] = 1;
  for (uint32_t k = 0; k < K; ++k) {
    v.up[b + k].reset();
    v.up_count[b + k] = 0;
  }
  return marked;
}

// Pooling: adds the pass's rewards of `cell` (under the shared cut's indices) in absolute units
// to sum, sq and count (each initial.size long); with pool_ratio, each divided by the cell's
// prior share of its cluster. Scratch (initial.size clusters): pri, w.
RLL_HD inline void cut_pass_rewards(const CutStoreEndView& v, uint32_t cell, double* sum,
                                    double* sq, uint64_t* count, const CutScratch& scratch) {
  const size_t b = v.base(cell);
  const double unit = 1 / v.inv_unit[cell];
  double* pri = scratch.pri;
  if (v.s.pool_ratio) cut_cell_prior(v, cell, pri, scratch);
  for (size_t k = 0; k < v.initial.size; ++k) {
    const uint32_t n = v.count[b + k];
    if (n == 0) continue;
    const double u = v.s.pool_ratio ? unit / pri[k] : unit;
    count[k] += n;
    sum[k] += v.sum[b + k].value() * u;
    sq[k] += v.sq[b + k].value() * u * u;
  }
}

// End of pass for one cell (cells are independent). A cell without a cut gets the initial one;
// the pass's rewards are folded into Q and M2, split-collapse runs, the table is baked. A cell
// with a cut and no reward this pass keeps its cut and table. Scratch: all of it, of
// cut_scratch_room(v, cell) clusters (taken before the call).
RLL_HD inline CutPassStats cut_end_pass(const CutStoreEndView& v, uint32_t cell,
                                        const CutScratch& scratch) {
  CutPassStats st;
  const size_t b = v.base(cell);
  const bool active = v.active(cell);
  uint32_t K = active ? v.size[cell] : uint32_t(v.initial.size);
  uint64_t n_total = 0;
  for (size_t k = 0; k < K; ++k) n_total += v.count[b + k];
  // Nothing new: the cut and CDF stand (but for a cell seeded from its parent, cut_seed_child,
  // whose table is yet to be baked: its last CDF entry, 1 in every baked table, is 0).
  if (active && n_total == 0 && v.cdf[b + K - 1] == 1.0f) return st;
  float* q = &v.q[b];
  float* m2 = &v.m2[b];
  float* n = &v.n[b];
  if (!active)
    for (size_t k = 0; k < K; ++k) {
      v.node[b + k] = v.initial[k];
      q[k] = -1.0f;
      m2[k] = 0.0f;
      n[k] = 0.0f;
      v.weight[b + k] = cut_weight_of(v, cell, v.initial[k]);
    }

  // Fold this pass's rewards into Q and M2. Shrinkage: a running mean of all rewards, started
  // from the prior estimate counted as prior_samples rewards, cut back to the last 1/alpha where
  // the pass's rewards fail the change test (forget=changes), or over at most the last 1/alpha
  // rewards (forget=floor). Exponential: the
  // paper's rule Q := (1-a) Q + a r once per reward, each reward replaced by the pass mean,
  // gives Q := b Q + (1-b) mean with b = (1-a)^n. Either way the result does not depend on the
  // order the threads delivered the rewards in.
  if (n_total > 0) {
    st.touched = true;
    v.seen[cell] += float(n_total);
    double* pri = scratch.pri;
    float* val = scratch.val;
    float* score = scratch.score;
    cut_prior(v, &v.node[b], &v.weight[b], K, pri);
    cut_values(v, cell, K, pri, val);
    const bool moment = v.s.target == LearnTarget::Moment;
    const double unit = 1 / v.inv_unit[cell];
    double largest = 0;
    for (size_t k = 0; k < K; ++k) {
      const uint32_t count = v.count[b + k];
      if (count == 0) continue;
      const RewardMoments r(count, v.sum[b + k].value() * unit, v.sq[b + k].value() * unit * unit);
      // The prior estimate of a cluster never visited: its effective value, without variance.
      const double old_q = q[k] >= 0 ? q[k] : val[k];
      const double old_m2 = q[k] >= 0 ? m2[k] : double(val[k]) * val[k];
      if (v.s.rule == LearningRule::Exponential) {
        const double bk = std::exp(double(count) * v.log_keep);
        q[k] = float(bk * old_q + (1 - bk) * r.mean);
        m2[k] = float(bk * old_m2 + (1 - bk) * r.mean2);
      } else {
        const bool visited = q[k] >= 0;
        const double w = visited ? double(n[k]) : double(v.s.prior_samples);
        st.changes += shrinkage_update(v.s, q[k], m2[k], n[k], w, visited, old_q, old_m2, count, r);
      }
      largest = std::max(largest, std::sqrt(double(m2[k])));
      v.sum[b + k].reset();
      v.sq[b + k].reset();
      v.count[b + k] = 0;
    }
    // The next pass's unit: the largest learnt sqrt(M2).
    next_unit(v.inv_unit[cell], largest);
    // Split-collapse on the new values: split by the cluster's share of the cell's variance
    // (the standard deviation of its reward) under target=moment, by value (the paper's Q)
    // under target=mean. (The prior is unchanged: folding touches no node or weight.)
    cut_values(v, cell, K, pri, val);
    for (size_t k = 0; k < K; ++k)
      score[k] = !moment     ? val[k]
                 : q[k] >= 0 ? float(std::sqrt(std::max(0.0, double(m2[k]) - double(q[k]) * q[k])))
                             : val[k];
    auto prior_weight = [&](uint32_t node) { return cut_weight_of(v, cell, node); };
    auto share = [&](uint32_t node) {
      if (v.s.split == ClusterWeight::Uniform) return 1.0f;  // half and half
      return v.s.split == ClusterWeight::Power
                 ? v.tree.node(node).bounds.power
                 : tree_importance(v.tree, node, v.anchor[cell].p, v.anchor[cell].n);
    };
    for (int i = 0; i < v.s.splits; ++i) {
      const int r = split_collapse_step(v.tree, int(v.m), v.s.threshold, K, &v.node[b], q, m2, n,
                                        &v.weight[b], val, score, prior_weight, share);
      if (r == 0) break;
      ++st.splits;
      if (r == 1) ++st.collapses;
    }
  }
  cut_bake(v, cell, K, scratch);  // (pri and val are free again: the bake recomputes them)
  return st;
}

}  // namespace rll
