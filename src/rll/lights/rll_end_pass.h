// RLL's end of pass above the single cell (DESIGN 6): a new cell's anchor from its first pass's
// point sums, then the whole end of pass (rll_end_pass) written once over a backend
// (core/backend.h): the cells in use, their anchors, pooling (lights/rll_pool.h), every cell's
// cut_end_pass, eviction, the table's rebuild and Fermat's reset; the CPU runs it with
// HostBackend (RllLightSampler::end_pass), the GPU with the CUDA backend
// (rll/cuda/backend.cuh), over the same functions.
#pragma once

#include <cstdint>

#include "rll/core/backend.h"
#include "rll/core/device.h"
#include "rll/learn/cut_end_pass.h"
#include "rll/lights/rll_learn_view.h"
#include "rll/lights/rll_pool.h"
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

// --- The end of pass over a backend -------------------------------------------------------------

// RLL's end of pass over a backend: new cells' anchors, pooling, every cell's cut_end_pass
// (rewards folded, split-collapse, tables baked) in scratch sized by its cut, then, when the
// table is nearly full or turned points away, eviction of the least recently used cells until
// it is 70% full (ties: the lower cell id), cells whose insert lost a race or were evicted back
// on the free list, the table rebuilt; and with `reset` (Fermat's periodic reset), every cell
// forgotten. `used_before`: the cells in use at the last rebuild. Nothing here depends on the
// order threads run in: sums are of integers, the sorts' keys hold the cell key or id.
template <typename B>
RllPassCounts rll_end_pass(const B& b, const RllLearnView& v, RllPoolState<B>& pool,
                           RllScratch<B>& scratch, uint32_t used_before, bool reset) {
  RllPassCounts out;
  const CutStoreEndView ev = v.cuts;
  const uint32_t cap = v.capacity;
  const View<uint64_t> key_of = v.table.key_of;
  const auto cells_buffer = select_indices(b, cap, [=] RLL_HD(size_t c) { return key_of[c] != 0; });
  const View<const uint32_t> cells = cells_buffer.view();
  const size_t n = cells.size;
  {
    const View<uint64_t> points = v.points;
    const Vec3 origin = v.origin;
    const float extent = v.extent;
    b.parallel_for(n, [=] RLL_HD(size_t i) {
      rll_anchor_from_points(ev, cells[i], &points[size_t(cells[i]) * kRllPointWords], origin,
                             extent);
    });
  }
  if (ev.s.pool_levels > 0) out.pool_changes = rll_pool_pass(b, v, pool, cells, scratch);
  if (ev.s.refine > 0) {
    // New children of refined cells start from their parents' values (cut_seed_child).
    const CellKeyer keyer = v.keyer;
    const CellTableView table = v.table;
    b.parallel_for(n, [=] RLL_HD(size_t i) {
      const CellAnchor& a = ev.anchor[cells[i]];
      if (ev.active(cells[i])) return;
      const uint32_t parent =
          cell_find(table, keyer.key(keyer.locate_at_level(a.p, a.n, a.level + 1)));
      cut_seed_child(ev, cells[i], parent);
    });
  }
  {
    // Each cell's scratch: its slice of an arena, at an exclusive scan of the cells' rooms.
    auto room = b.template buffer<uint32_t>(n);
    auto offset = b.template buffer<uint64_t>(n);
    // splits, collapses, touched, changes, refined (rll.refine: the disagreement test, on the
    // pass's rewards before the fold resets them)
    constexpr size_t kFields = 5;
    auto stats = b.template buffer<uint32_t>(kFields * n);
    const View<uint32_t> r = room.view(), st = stats.view();
    b.parallel_for(n, [=] RLL_HD(size_t i) { r[i] = cut_scratch_room(ev, cells[i]); });
    const uint64_t clusters = b.exclusive_scan(r, offset.view());
    const CutScratchArena arena = scratch.arena(b, clusters);
    const View<const uint64_t> at = offset.view();
    b.parallel_for(n, [=] RLL_HD(size_t i) {
      st[4 * n + i] = cut_refine_test(ev, cells[i]);
      const CutPassStats s = cut_end_pass(ev, cells[i], arena.slice(at[i], r[i]));
      st[i] = s.splits;
      st[n + i] = s.collapses;
      st[2 * n + i] = s.touched;
      st[3 * n + i] = s.changes;
    });
    uint32_t* fields[kFields] = {&out.splits, &out.collapses, &out.touched, &out.changes,
                                 &out.refined};
    for (size_t f = 0; f < kFields; ++f)
      *fields[f] = uint32_t(b.sum(View<const uint32_t>{st.data + f * n, n}));
  }
  out.failed = b.read(v.table.failed);
  if (out.failed > 0 || used_before > cap * 9ull / 10) {
    const size_t target = cap * 7ull / 10;
    if (n > target) {
      auto last = b.template buffer<uint64_t>(n);
      auto lru = b.template buffer<uint32_t>(n);
      const View<uint64_t> l = last.view();
      const View<uint32_t> ids = lru.view();
      const View<uint32_t> last_used = v.last_used;
      b.parallel_for(n, [=] RLL_HD(size_t i) {
        l[i] = last_used[cells[i]];
        ids[i] = cells[i];
      });
      b.sort_pairs(l, ids);  // stable: ties keep the order of cell ids
      out.evicted = uint32_t(n - target);
      b.parallel_for(out.evicted, [=] RLL_HD(size_t i) {
        cut_clear(ev, ids[i]);
        key_of[ids[i]] = 0;
      });
    }
  }
  // Cells whose insert lost a race, or were evicted, go back to the free list.
  b.parallel_for(cap, [=] RLL_HD(size_t c) {
    if (key_of[c] == 0 && ev.active(uint32_t(c))) cut_clear(ev, uint32_t(c));
  });
  out.used = cell_table_rebuild(b, v.table, v.free_room);
  if (reset) {
    // Fermat's periodic reset: every cell starts over.
    b.parallel_for(cap, [=] RLL_HD(size_t c) {
      if (key_of[c] != 0) {
        cut_clear(ev, uint32_t(c));
        key_of[c] = 0;
      }
    });
    out.used = cell_table_rebuild(b, v.table, v.free_room);
    pool.clear(b);
  }
  return out;
}

// Every cell's prior weights and table anew (cut_refresh), in scratch sized by its cut.
template <typename B>
void rll_refresh_all(const B& b, const RllLearnView& v, RllScratch<B>& scratch) {
  const CutStoreEndView ev = v.cuts;
  const uint32_t cap = v.capacity;
  auto room = b.template buffer<uint32_t>(cap);
  auto offset = b.template buffer<uint64_t>(cap);
  const View<uint32_t> r = room.view();
  b.parallel_for(cap, [=] RLL_HD(size_t c) { r[c] = ev.active(uint32_t(c)) ? ev.size[c] : 0; });
  const CutScratchArena arena = scratch.arena(b, b.exclusive_scan(r, offset.view()));
  const View<const uint64_t> at = offset.view();
  b.parallel_for(cap,
                 [=] RLL_HD(size_t c) { cut_refresh(ev, uint32_t(c), arena.slice(at[c], r[c])); });
}

// The lights changed: under forget=changes every cluster's memory, a cell's and a coarse cell's,
// is cut back to the last 1/alpha rewards (what a cluster learnt under the old lights may be
// wrong under the new); every cell's prior weights and table anew; with pool_guess=ratio, whose
// pool shares are the coarse factors times a cell's prior (a lamp switched off has prior 0), the
// shares given again from the new priors and the tables baked once more.
template <typename B>
void rll_lights_changed(const B& b, const RllLearnView& v, RllPoolState<B>& pool,
                        RllScratch<B>& scratch) {
  const CutStoreEndView ev = v.cuts;
  b.parallel_for(v.capacity, [=] RLL_HD(size_t c) { cut_forget(ev, uint32_t(c)); });
  const RllPoolView p = pool.view(uint32_t(ev.initial.size));
  b.parallel_for(p.keys.size, [=] RLL_HD(size_t j) { pool_forget(ev, p, j); });
  rll_refresh_all(b, v, scratch);
  if (ev.s.pool_levels > 0 && ev.s.pool_ratio && p.keys.size > 0) {
    rll_give_pool_shares(b, v, pool, scratch);
    rll_refresh_all(b, v, scratch);
  }
}

}  // namespace rll
