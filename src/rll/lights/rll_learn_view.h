// What RLL's end of pass works on (DESIGN 6): the learning arrays as views into one backend's
// memory (RllLearnView), the end of pass's scratch kept from pass to pass (RllScratch), and the
// few numbers one end of pass hands back to the host (RllPassCounts).
#pragma once

#include <cstdint>

#include "rll/core/backend.h"
#include "rll/core/device.h"
#include "rll/learn/cut_end_pass.h"
#include "rll/lights/rll_view.h"

namespace rll {

// What RLL's end of pass reads and writes, as views into one backend's memory.
struct RllLearnView {
  CutStoreEndView cuts;
  CellTableView table;
  View<uint32_t> free_room;  // the table's free list, capacity long (CellTable::free_room)
  View<uint32_t> last_used;  // per cell: the pass of its last lookup
  View<uint64_t> points;     // per cell, kRllPointWords: the point sums of its first pass
  CellKeyer keyer;           // this pass's
  Vec3 origin;               // of the point sums
  float extent = 1;
  uint32_t capacity = 0;  // cells
};

// The end of pass's scratch (CutScratch per cell), kept from pass to pass and grown as needed.
template <typename B>
struct RllScratch {
  typename B::template Buffer<double> d;
  typename B::template Buffer<float> f;
  // An arena of at least `clusters` clusters of room.
  CutScratchArena arena(const B& b, uint64_t clusters) {
    if (d.size() < clusters * CutScratchArena::kDoubles) {
      d = b.template buffer<double>(clusters * CutScratchArena::kDoubles);
      f = b.template buffer<float>(clusters * CutScratchArena::kFloats);
    }
    return {d.view(), f.view()};
  }
  size_t bytes() const { return d.size() * sizeof(double) + f.size() * sizeof(float); }
};

// What one end of pass did: the few numbers the host keeps per pass.
struct RllPassCounts {
  uint32_t splits = 0, collapses = 0, touched = 0, changes = 0;
  uint32_t pool_changes = 0;  // pooling's coarse cells' changes (forget=changes)
  uint64_t failed = 0;        // points that found no cell during the pass
  uint32_t evicted = 0;
  uint32_t used = 0;     // cells in use after the rebuild
  uint32_t refined = 0;  // cells the disagreement test marked refined (rll.refine)
};

}  // namespace rll
