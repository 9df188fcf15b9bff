// RLL's end of pass above the single cell, as host-and-device functions (DESIGN 6): a new cell's
// anchor from its first pass's point sums, and pooling (rll.pool) without a map: the coarse
// cells as a sorted key array with K values each, the pass's rewards summed per coarse cell over
// its cells in the order of their keys, folded, and given back to the cells as shares. The
// sorts that order the cells stay host code (RllLightSampler::pool_pass; a device build sorts
// with CUB); everything per cell or per coarse cell is here.
#pragma once

#include <cstdint>

#include "rll/core/device.h"
#include "rll/learn/cut_end_pass.h"
#include "rll/lights/rll_view.h"

namespace rll {

// A new cell's anchor: the mean of its first pass's points (sums in `w`, kRllPointWords of them,
// relative to the scene box at `origin` of size `extent`); the sums are reset for the next pass.
// A cell that already has a cut keeps its anchor.
RLL_HD inline void rll_anchor_from_points(const CutStoreEndView& v, uint32_t cell, uint64_t* w,
                                          const Vec3& origin, float extent) {
  if (const int64_t count = int64_t(w[6]); count > 0 && !v.active(cell)) {
    double sum[6];
    for (int j = 0; j < 6; ++j) sum[j] = double(int64_t(w[j])) / double(count) * 0x1p-24;
    CellAnchor a = v.anchor[cell];
    a.p = origin + Vec3(float(sum[0]), float(sum[1]), float(sum[2])) * extent;
    const Vec3 n{float(sum[3]), float(sum[4]), float(sum[5])};
    if (length_sq(n) > 1e-6f) a.n = normalize(n);
    v.anchor[cell] = a;
  }
  for (int j = 0; j < kRllPointWords; ++j) w[j] = 0;
}

// The coarse cells of pooling: keys ascending, and Q, M2 and reward weight of each cluster of
// the shared cut, k clusters per coarse cell, in key order.
struct RllPoolView {
  uint32_t k = 0;
  View<const uint64_t> keys;
  View<float> q, m2, n;
};

// The index of `key` among the coarse cells, or -1 (binary search).
RLL_HD inline long pool_find(const RllPoolView& p, uint64_t key) {
  size_t lo = 0, count = p.keys.size;
  while (count > 0) {
    const size_t half = count / 2;
    if (p.keys[lo + half] < key) {
      lo += half + 1;
      count -= half + 1;
    } else {
      count = half;
    }
  }
  return lo < p.keys.size && p.keys[lo] == key ? long(lo) : -1;
}

// One cell's contribution to one coarse cell: the coarse key, then the cell's key (the order of
// the sums), and the cell.
struct PoolEntry {
  uint64_t coarse, cell_key;
  uint32_t cell;
};

// A coarse cell's fold: the pass's rewards of its cells (entries[0, count), in the order of their
// keys) summed into sum, sq and n_rewards (k each, scratch), then folded into the coarse cell
// `slot` of `next` by the shrinkage rule without a prior (a cluster's first rewards are its
// values), from its state in `old` if it had one, forgetting as the cells do (rll.forget);
// returns the clusters whose rewards failed the change test.
RLL_HD inline uint32_t pool_fold(const CutStoreEndView& v, const PoolEntry* entries, size_t count,
                                 const RllPoolView& old, const RllPoolView& next, size_t slot,
                                 double* sum, double* sq, uint64_t* n_rewards) {
  const size_t K = next.k;
  for (size_t k = 0; k < K; ++k) {
    sum[k] = sq[k] = 0;
    n_rewards[k] = 0;
  }
  for (size_t i = 0; i < count; ++i) cut_pass_rewards(v, entries[i].cell, sum, sq, n_rewards);
  float* q = &next.q[slot * K];
  float* m2 = &next.m2[slot * K];
  float* n = &next.n[slot * K];
  const long o = pool_find(old, next.keys[slot]);
  for (size_t k = 0; k < K; ++k) {
    q[k] = o >= 0 ? old.q[size_t(o) * K + k] : -1.0f;
    m2[k] = o >= 0 ? old.m2[size_t(o) * K + k] : 0.0f;
    n[k] = o >= 0 ? old.n[size_t(o) * K + k] : 0.0f;
  }
  uint32_t changes = 0;
  for (size_t k = 0; k < K; ++k) {
    if (n_rewards[k] == 0) continue;
    const double nk = double(n_rewards[k]);
    const bool visited = q[k] >= 0;
    changes += shrinkage_update(v.s, q[k], m2[k], n[k], visited ? double(n[k]) : 0.0, visited,
                                std::max(q[k], 0.0f), m2[k], nk, RewardMoments(nk, sum[k], sq[k]));
  }
  return changes;
}

// The lights changed (forget=changes): the memory of every cluster of coarse cell `slot` is cut
// back to the last 1/alpha rewards, as cut_forget does for a cell's.
RLL_HD inline void pool_forget(const CutStoreEndView& v, const RllPoolView& p, size_t slot) {
  if (v.s.forget != Forgetting::Changes) return;
  const float cap = float(1.0 / v.s.alpha);
  for (size_t k = 0; k < p.k; ++k) p.n[slot * p.k + k] = std::min(p.n[slot * p.k + k], cap);
}

// A coarse cell's values into out (zero where it has none), normalized if `normalize`; false if
// none is positive.
RLL_HD inline bool pool_values(const RllPoolView& p, size_t slot, bool moment, float* out,
                               bool normalize) {
  const size_t K = p.k;
  const float* q = &p.q[slot * K];
  const float* m2 = &p.m2[slot * K];
  double total = 0;
  for (size_t k = 0; k < K; ++k) {
    out[k] = q[k] < 0 ? 0.0f : moment ? std::sqrt(std::max(m2[k], 0.0f)) : q[k];
    total += out[k];
  }
  if (normalize && total > 0)
    for (size_t k = 0; k < K; ++k) out[k] = float(out[k] / total);
  return total > 0;
}

// Gives `cell` the distribution its values are shrunk toward: its coarse cell's (`coarse`),
// itself shrunk toward the coarser cell's (`upper`, if `has_upper`: pool_up), times the cell's
// prior with pool_guess=ratio, normalized; none where the coarse cell has no positive value.
RLL_HD inline void pool_give_shares(const CutStoreEndView& v, const RllPoolView& p, uint32_t cell,
                                    uint64_t coarse, bool has_upper, uint64_t upper) {
  const size_t K = p.k;
  const bool moment = v.s.target == LearnTarget::Moment;
  float shares[kMaxCutSize], above[kMaxCutSize];
  double total = 0;
  if (const long c = pool_find(p, coarse); c >= 0) {
    const float* q = &p.q[size_t(c) * K];
    pool_values(p, size_t(c), moment, shares, false);
    // pool_up: the coarse cell's values shrunk toward its own coarse cell's.
    if (has_upper)
      if (const long up = pool_find(p, upper);
          up >= 0 && pool_values(p, size_t(up), moment, above, true))
        shrink_toward(
            K, [&](size_t k) { return q[k] >= 0; }, &p.n[size_t(c) * K], above, v.s.pool_weight,
            shares);
    // pool_guess=ratio: the coarse cell's factors times this cell's prior.
    double pri[kMaxCutSize];
    if (v.s.pool_ratio) cut_cell_prior(v, cell, pri);
    for (size_t k = 0; k < K; ++k) {
      if (v.s.pool_ratio) shares[k] = float(shares[k] * pri[k]);
      total += shares[k];
    }
    if (total > 0)
      for (size_t k = 0; k < K; ++k) shares[k] = float(shares[k] / total);
  }
  v.has_pool[cell] = total > 0;
  if (total > 0)
    for (size_t k = 0; k < K; ++k) v.pool[v.base(cell) + k] = shares[k];
}

}  // namespace rll
