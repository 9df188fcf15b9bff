// Pooling (rll.pool, docs/rll.md "Pooling") without a map: the coarse cells as a sorted key
// array with K values each (RllPoolView, RllPoolState), the pass's rewards summed per coarse cell
// over its cells in the order of their keys (pool_fold), folded by the shrinkage rule, and given
// back to the cells as the shares their values are shrunk toward (pool_give_shares). The
// per-cell functions run on either device; the whole pass (rll_pool_pass) is written once over a
// backend (core/backend.h).
#pragma once

#include <cstdint>

#include "rll/core/backend.h"
#include "rll/core/device.h"
#include "rll/core/search.h"
#include "rll/learn/cut_end_pass.h"
#include "rll/learn/moments.h"
#include "rll/lights/rll_learn_view.h"

namespace rll {

// The coarse cells of pooling: keys ascending, and Q, M2 and reward weight of each cluster of
// the shared cut, k clusters per coarse cell, in key order.
struct RllPoolView {
  uint32_t k = 0;
  View<const uint64_t> keys;
  View<float> q, m2, n;
};

// The index of `key` among the coarse cells, or -1 (binary search).
RLL_HD inline long pool_find(const RllPoolView& p, uint64_t key) {
  const size_t lo = lower_bound_index(p.keys.data, size_t(0), p.keys.size, key);
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
// returns the clusters whose rewards failed the change test. Scratch (k clusters): as
// cut_pass_rewards.
RLL_HD inline uint32_t pool_fold(const CutStoreEndView& v, const PoolEntry* entries, size_t count,
                                 const RllPoolView& old, const RllPoolView& next, size_t slot,
                                 double* sum, double* sq, uint64_t* n_rewards,
                                 const CutScratch& scratch) {
  const size_t K = next.k;
  for (size_t k = 0; k < K; ++k) {
    sum[k] = sq[k] = 0;
    n_rewards[k] = 0;
  }
  for (size_t i = 0; i < count; ++i)
    cut_pass_rewards(v, entries[i].cell, sum, sq, n_rewards, scratch);
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
  forget_to_window(&p.n[slot * p.k], p.k, v.s.alpha);
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
    out[k] = q[k] < 0 ? 0.0f : target_value(moment, q[k], m2[k]);
    total += out[k];
  }
  if (normalize && total > 0)
    for (size_t k = 0; k < K; ++k) out[k] = float(out[k] / total);
  return total > 0;
}

// Gives `cell` the distribution its values are shrunk toward: its coarse cell's (`coarse`),
// itself shrunk toward the coarser cell's (`upper`, if `has_upper`: pool_up), times the cell's
// prior with pool_guess=ratio, normalized; none where the coarse cell has no positive value.
// Scratch (k clusters): val, score, pri, w.
RLL_HD inline void pool_give_shares(const CutStoreEndView& v, const RllPoolView& p, uint32_t cell,
                                    uint64_t coarse, bool has_upper, uint64_t upper,
                                    const CutScratch& scratch) {
  const size_t K = p.k;
  const bool moment = v.s.target == LearnTarget::Moment;
  float* shares = scratch.val;
  float* above = scratch.score;
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
    double* pri = scratch.pri;
    if (v.s.pool_ratio) cut_cell_prior(v, cell, pri, scratch);
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

// Pooling's coarse cells (RllPoolView's arrays) in a backend's memory.
template <typename B>
struct RllPoolState {
  typename B::template Buffer<uint64_t> keys;
  typename B::template Buffer<float> q, m2, n;
  RllPoolView view(uint32_t k) { return {k, keys.view(), q.view(), m2.view(), n.view()}; }
  void clear(const B& b) {
    keys = b.template buffer<uint64_t>(0);
    q = b.template buffer<float>(0);
    m2 = b.template buffer<float>(0);
    n = b.template buffer<float>(0);
  }
};

// Pooling: the coarse key of each of `cells` in tier 0 (its anchor, pool levels up) or tier 1
// (pool + pool_up levels up).
template <typename B>
typename B::template Buffer<uint64_t> rll_coarse_keys(const B& b, const RllLearnView& v,
                                                      View<const uint32_t> cells, int tier) {
  const int up = v.cuts.s.pool_levels + (tier > 0 ? v.cuts.s.pool_up : 0);
  auto keys = b.template buffer<uint64_t>(cells.size);
  const View<uint64_t> out = keys.view();
  const View<CellAnchor> anchor = v.cuts.anchor;
  const CellKeyer keyer = v.keyer;
  b.parallel_for(cells.size, [=] RLL_HD(size_t i) {
    // The anchor, a mean of the cell's points, lies inside the cell, so the coarse cell holds it.
    const CellAnchor& a = anchor[cells[i]];
    out[i] = keyer.key(keyer.locate_at_level(a.p, a.n, a.level + up));
  });
  return keys;
}

// Pooling: gives each of `cells` its coarse cell's shares (`coarse`, and `upper` with pool_up:
// empty otherwise); scratch of k clusters per cell.
template <typename B>
void rll_give_pool_shares(const B& b, const RllLearnView& v, RllPoolState<B>& pool,
                          View<const uint32_t> cells, View<const uint64_t> coarse,
                          View<const uint64_t> upper, RllScratch<B>& scratch) {
  const uint32_t K = uint32_t(v.cuts.initial.size);
  const CutScratchArena arena = scratch.arena(b, uint64_t(cells.size) * K);
  const CutStoreEndView ev = v.cuts;
  const RllPoolView p = pool.view(K);
  b.parallel_for(cells.size, [=] RLL_HD(size_t i) {
    pool_give_shares(ev, p, cells[i], coarse[i], !upper.empty(), upper.empty() ? 0 : upper[i],
                     arena.slice(uint64_t(i) * K, K));
  });
}

// The same for every cell in use, from their anchors (after a load or a change of the lights).
template <typename B>
void rll_give_pool_shares(const B& b, const RllLearnView& v, RllPoolState<B>& pool,
                          RllScratch<B>& scratch) {
  const View<uint64_t> key_of = v.table.key_of;
  const auto cells = select_indices(b, v.capacity, [=] RLL_HD(size_t c) { return key_of[c] != 0; });
  const auto coarse = rll_coarse_keys(b, v, cells.view(), 0);
  const auto upper =
      rll_coarse_keys(b, v, v.cuts.s.pool_tiers() > 1 ? cells.view() : View<const uint32_t>{}, 1);
  rll_give_pool_shares(b, v, pool, cells.view(), coarse.view(), upper.view(), scratch);
}

// Pooling (rll.pool): pools this pass's rewards of `cells` into their coarse cells, folds them
// into the coarse cells' values (coarse cells no cell uses any more are forgotten) and gives
// every cell its coarse cell's shares; returns the coarse clusters' changes.
template <typename B>
uint32_t rll_pool_pass(const B& b, const RllLearnView& v, RllPoolState<B>& pool,
                       View<const uint32_t> cells, RllScratch<B>& scratch) {
  const uint32_t K = uint32_t(v.cuts.initial.size);
  const size_t n = cells.size;
  // Two tiers (pool_up): every cell's rewards also reach the cell pool_up levels coarser still.
  // Keys hold the level, so both tiers share one key space; a coarse cell of either tier sums
  // the cells under it.
  const size_t tiers = v.cuts.s.pool_tiers() > 1 ? 2 : 1;
  const auto coarse = rll_coarse_keys(b, v, cells, 0);
  const auto upper = rll_coarse_keys(b, v, tiers > 1 ? cells : View<const uint32_t>{}, 1);
  // One entry per cell and tier, sorted by (coarse key, cell key): each coarse cell's cells in
  // the order of their keys, so that the sums do not depend on which thread created which cell
  // id. Two stable sorts: by cell key, then by coarse key. (Entries equal in both are one cell's,
  // alike.)
  const size_t E = n * tiers;
  auto sort_keys = b.template buffer<uint64_t>(E);
  auto order = b.template buffer<uint32_t>(E);
  {
    const View<uint64_t> sk = sort_keys.view();
    const View<uint32_t> o = order.view();
    const View<uint64_t> key_of = v.table.key_of;
    b.parallel_for(E, [=] RLL_HD(size_t e) {
      sk[e] = key_of[cells[e / tiers]];
      o[e] = uint32_t(e);
    });
    b.sort_pairs(sk, o);
    const View<const uint64_t> c0 = coarse.view(), c1 = upper.view();
    b.parallel_for(E, [=] RLL_HD(size_t j) {
      const uint32_t e = o[j];
      sk[j] = e % tiers == 0 ? c0[e / tiers] : c1[e / tiers];
    });
    b.sort_pairs(sk, o);
  }
  // The entries in that order, and the coarse cells of this pass, each a segment of them.
  auto entries = b.template buffer<PoolEntry>(E);
  auto head = b.template buffer<uint32_t>(E);
  auto slot_of = b.template buffer<uint64_t>(E);
  const View<const uint64_t> sk = sort_keys.view();
  {
    const View<PoolEntry> en = entries.view();
    const View<uint32_t> h = head.view();
    const View<const uint32_t> o = order.view();
    const View<uint64_t> key_of = v.table.key_of;
    b.parallel_for(E, [=] RLL_HD(size_t j) {
      const uint32_t cell = cells[o[j] / tiers];
      en[j] = {sk[j], key_of[cell], cell};
      h[j] = j == 0 || sk[j] != sk[j - 1];
    });
  }
  const size_t coarse_count = b.exclusive_scan(head.view(), slot_of.view());
  auto keys = b.template buffer<uint64_t>(coarse_count);
  auto first = b.template buffer<uint64_t>(coarse_count + 1);
  {
    const View<uint64_t> ks = keys.view(), fi = first.view();
    const View<const uint32_t> h = head.view();
    const View<const uint64_t> at = slot_of.view();
    b.parallel_for(E, [=] RLL_HD(size_t j) {
      if (h[j]) {
        ks[at[j]] = sk[j];
        fi[at[j]] = j;
      }
    });
    b.parallel_for(1, [=] RLL_HD(size_t) { fi[coarse_count] = E; });
  }
  // Each coarse cell's fold, from its state of the last pass.
  RllPoolState<B> next{std::move(keys), b.template buffer<float>(coarse_count * K),
                       b.template buffer<float>(coarse_count * K),
                       b.template buffer<float>(coarse_count * K)};
  auto sum = b.template buffer<double>(coarse_count * K);
  auto sq = b.template buffer<double>(coarse_count * K);
  auto count = b.template buffer<uint64_t>(coarse_count * K);
  auto changes = b.template buffer<uint32_t>(coarse_count);
  {
    const CutStoreEndView ev = v.cuts;
    const RllPoolView old = pool.view(K), nv = next.view(K);
    const CutScratchArena arena = scratch.arena(b, uint64_t(coarse_count) * K);
    const View<const PoolEntry> en = entries.view();
    const View<const uint64_t> fi = first.view();
    const View<double> su = sum.view(), sqv = sq.view();
    const View<uint64_t> co = count.view();
    const View<uint32_t> ch = changes.view();
    b.parallel_for(coarse_count, [=] RLL_HD(size_t j) {
      const size_t at = j * K;
      ch[j] = pool_fold(ev, &en[fi[j]], fi[j + 1] - fi[j], old, nv, j, &su[at], &sqv[at], &co[at],
                        arena.slice(at, K));
    });
  }
  const uint32_t total = uint32_t(b.sum(changes.view()));
  pool = std::move(next);
  rll_give_pool_shares(b, v, pool, cells, coarse.view(), upper.view(), scratch);
  return total;
}

}  // namespace rll
