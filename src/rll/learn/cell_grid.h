// RLL's cells: a sparse 5D grid over (position, normal) addressed by hashing. The position cell
// size follows the ray footprint, quantized to a power-of-two level of detail (the nearest, or by
// stochastic rounding); position and normal are jittered by an offset that changes every pass. The
// table has a fixed capacity and is lock-free: inserts never block, and a failed insert (table
// full) means "no cell" (the sampler falls back to its prior) until end-of-pass eviction frees
// room. The hot functions (locating a point's cell, its key; finding and inserting a key) are
// RLL_HD, over a trivially copyable CellKeyer and a CellTableView (DESIGN 6).
#pragma once

#include <cstdint>
#include <vector>

#include "rll/core/backend.h"
#include "rll/core/device.h"
#include "rll/core/hash.h"
#include "rll/core/math.h"

namespace rll {

struct CellGridSettings {
  float footprint_scale = 4;  // cell radius = footprint_scale * ray footprint ...
  float max_cell = 0.05f;     // ... at most max_cell * scene diameter
  int normal_bins = 4;        // bins per axis of the octahedral normal map
  // Jitter amplitude in cell units (0: none). Renewing the jitter every pass blends cell
  // boundaries but applies each cell's learnt state to a region it did not learn: on
  // cornell-boxes-room it doubled RLL's error, so it is off by default (bench/RESULTS.md).
  float jitter = 0;
  // Bins per axis of an octahedral map of the view direction wo, for points on glossy surfaces
  // (0: none): such a point's cell is also keyed by where it is seen from (Wang et al. 2021 bin
  // wo 8 x 8), since its BSDF, and so which lights matter, depends on wo.
  int direction_bins = 0;
  // How a footprint's fractional level of detail becomes a level: `Nearest`, the nearest power
  // of two in log scale, so that every point of a surface at one distance shares one cell size;
  // `Stochastic` (DESIGN 2), rounded up or down at random in proportion to the fraction, so that
  // the size follows the footprint on average but the points of one region are split between
  // two cells of different sizes, each learning from part of their rewards (docs/rll.md).
  enum class LevelRounding { Stochastic, Nearest };
  LevelRounding level_rounding = LevelRounding::Nearest;
};

// The integer coordinates of a cell in the 5D grid.
struct CellCoord {
  int64_t x = 0, y = 0, z = 0;
  int level = 0;       // edge = scene diameter * 2^level
  int nu = 0, nv = 0;  // octahedral normal bin
  uint32_t dir = 0;    // 1 + the view direction's bin on a glossy surface; 0: not binned
  // Not part of the key: bit a (x, y, z) set where the point lies in the upper half of the cell's
  // box along that axis (rll.refine's disagreement test).
  uint8_t half = 0;
};

// A representative point of a cell: the centre of its box and of its normal bin.
struct CellAnchor {
  Vec3 p, n;
  int level = 0;
};

// Octahedral map of a unit vector to [0,1]^2, and back.
RLL_HD inline Vec2 octahedral_encode(const Vec3& n) {
  float s = std::abs(n.x) + std::abs(n.y) + std::abs(n.z);
  float x = n.x / s, y = n.y / s;
  if (n.z < 0) {
    float ox = (1 - std::abs(y)) * (x >= 0 ? 1.0f : -1.0f);
    float oy = (1 - std::abs(x)) * (y >= 0 ? 1.0f : -1.0f);
    x = ox;
    y = oy;
  }
  return {0.5f * x + 0.5f, 0.5f * y + 0.5f};
}

RLL_HD inline Vec3 octahedral_decode(Vec2 e) {
  float x = 2 * clamp(e.x, 0.0f, 1.0f) - 1, y = 2 * clamp(e.y, 0.0f, 1.0f) - 1;
  float z = 1 - std::abs(x) - std::abs(y);
  if (z < 0) {
    float ox = (1 - std::abs(y)) * (x >= 0 ? 1.0f : -1.0f);
    float oy = (1 - std::abs(x)) * (y >= 0 ? 1.0f : -1.0f);
    x = ox;
    y = oy;
  }
  return normalize(Vec3(x, y, z));
}

// Maps shading points to cells and cells to 64-bit keys (never 0). Trivially copyable: kernels
// take it by value.
class CellKeyer {
 public:
  CellKeyer() = default;  // (a placeholder in a view until assigned)
  CellKeyer(const CellGridSettings& s, const Bounds3& scene_bounds);
  // Sets the jitter for a pass (every pass gets a fresh one, from the pass index and seed).
  void set_pass(uint64_t pass, uint64_t seed);
  // Cell of point p with unit normal n and ray footprint radius `footprint`; u drives the
  // stochastic rounding of the level of detail (with LevelRounding::Stochastic).
  RLL_HD CellCoord locate(const Vec3& p, const Vec3& n, float footprint, float u) const {
    return locate_with(p, n, level_of(footprint, u), m_jitter_disk, m_jitter_normal);
  }
  // The cell of p, n at a given level of detail.
  RLL_HD CellCoord locate_at_level(const Vec3& p, const Vec3& n, int level) const {
    return locate_with(p, n, level, m_jitter_disk, m_jitter_normal);
  }
  // As locate, with a jitter of this sample's own instead of the pass's (Fermat's per-sample
  // jitter): `disk` in the tangent plane in cell edges, `normal` in normal bins.
  RLL_HD CellCoord locate_jittered(const Vec3& p, const Vec3& n, float footprint, float u,
                                   Vec2 disk, Vec2 normal) const {
    return locate_with(p, n, level_of(footprint, u), disk, normal);
  }
  // The same at a given level of detail (a refined cell's child: rll.refine).
  RLL_HD CellCoord locate_jittered_at_level(const Vec3& p, const Vec3& n, int level, Vec2 disk,
                                            Vec2 normal) const {
    return locate_with(p, n, level, disk, normal);
  }
  // The level of detail of a footprint (u: the stochastic rounding's), as locate takes it.
  RLL_HD int level(float footprint, float u) const { return level_of(footprint, u); }
  // The finest level of detail a footprint can have (cell_size's floor of 2^-24 diameters).
  static constexpr int kFinestLevel = -24;
  RLL_HD uint64_t key(const CellCoord& c) const {
    uint64_t h = mix64(uint64_t(c.x) * 0x9e3779b97f4a7c15ull ^ uint64_t(c.level + 64));
    h = mix64(h ^ (uint64_t(c.y) * 0xc2b2ae3d27d4eb4full));
    h = mix64(h ^ (uint64_t(c.z) * 0x165667b19e3779f9ull));
    // (A cell not binned by direction, dir 0, keeps the key it had before direction bins.)
    h = mix64(h ^ (uint64_t(c.dir) << 32 | uint64_t(c.nu) << 16 | uint64_t(c.nv)));
    return h | 1;  // 0 means "empty"
  }
  // 1 + the octahedral bin of the direction wo (any length > 0), direction_bins per axis.
  RLL_HD uint32_t direction_bin(const Vec3& wo) const {
    const int bins = m_s.direction_bins;
    const Vec2 o = octahedral_encode(normalize(wo));
    const int u = clamp(int(std::floor(o.x * bins)), 0, bins - 1),
              v = clamp(int(std::floor(o.y * bins)), 0, bins - 1);
    return 1 + uint32_t(u * bins + v);
  }
  uint64_t key(const Vec3& p, const Vec3& n, float footprint, float u) const {
    return key(locate(p, n, footprint, u));
  }
  // The cell's centre under this pass's jitter (a function of the coordinates alone).
  RLL_HD CellAnchor anchor(const CellCoord& c) const {
    const int bins = m_s.normal_bins;
    CellAnchor a;
    a.level = c.level;
    a.n = octahedral_decode(
        {(c.nu + 0.5f - m_jitter_normal.x) / bins, (c.nv + 0.5f - m_jitter_normal.y) / bins});
    float size = std::ldexp(m_extent, c.level);
    Frame f(a.n);
    Vec3 q((c.x + 0.5f) * size, (c.y + 0.5f) * size, (c.z + 0.5f) * size);
    a.p = q + m_origin - (f.s * m_jitter_disk.x + f.t * m_jitter_disk.y) * size;
    return a;
  }
  // Cell edge length for a footprint, before stochastic rounding (for tests).
  RLL_HD float cell_size(float footprint) const {
    float r = std::min(m_s.footprint_scale * footprint, m_s.max_cell * m_extent);
    return std::max(2 * r, m_extent * 0x1p-24f);
  }
  RLL_HD const CellGridSettings& settings() const { return m_s; }

 private:
  RLL_HD int level_of(float footprint, float u) const {
    // Level of detail: the cell edge is a power of two times the scene diameter: the nearest in
    // log scale, or rounded up or down at random in proportion to the fractional level, so that
    // cell size follows the footprint on average.
    float lf = std::log2(cell_size(footprint)) - m_log2_extent;
    if (m_s.level_rounding == CellGridSettings::LevelRounding::Nearest)
      return int(std::floor(lf + 0.5f));
    float lo = std::floor(lf);
    return int(lo) + (u < lf - lo ? 1 : 0);
  }
  RLL_HD CellCoord locate_with(const Vec3& p, const Vec3& n, int level, Vec2 disk,
                               Vec2 normal) const {
    CellCoord c;
    c.level = level;
    const int bins = m_s.normal_bins;
    Vec2 o = octahedral_encode(n);
    c.nu = clamp(int(std::floor(o.x * bins + normal.x)), 0, bins - 1);
    c.nv = clamp(int(std::floor(o.y * bins + normal.y)), 0, bins - 1);
    // The position jitter lies in the tangent plane of the bin's central normal, so that every
    // point of a cell shares it.
    float size = std::ldexp(m_extent, c.level);
    Vec3 q = p - m_origin;
    if (disk.x != 0 || disk.y != 0) {  // (no jitter, the default: no frame to build per lookup)
      Frame f(
          octahedral_decode({(c.nu + 0.5f - normal.x) / bins, (c.nv + 0.5f - normal.y) / bins}));
      q = q + (f.s * disk.x + f.t * disk.y) * size;
    }
    const Vec3 t(q.x / size, q.y / size, q.z / size);  // (divisions, as the keys always were)
    const Vec3 f(std::floor(t.x), std::floor(t.y), std::floor(t.z));
    c.x = int64_t(f.x);
    c.y = int64_t(f.y);
    c.z = int64_t(f.z);
    c.half = uint8_t((t.x - f.x >= 0.5f) | (t.y - f.y >= 0.5f) << 1 | (t.z - f.z >= 0.5f) << 2);
    return c;
  }
  CellGridSettings m_s;
  Vec3 m_origin;
  float m_extent = 1;  // scene diameter
  float m_log2_extent = 0;
  Vec2 m_jitter_disk;    // in the tangent plane, cell units
  Vec2 m_jitter_normal;  // in normal bins
};

// What lookups and inserts of a CellTable read and write (DESIGN 6): the slots, the full key of
// each cell, the free list and its counters. Owns nothing; threads share one and update it with
// core/device.h's atomics.
struct CellTableView {
  static constexpr uint32_t kNone = ~0u;
  static constexpr int kMaxProbes = 64;
  static constexpr uint64_t kIdMask = (uint64_t(1) << 24) - 1;
  // Slot word: (key >> 24) << 24 | cell id, or 0 when empty. The full key is kept per cell.
  View<uint64_t> slots;       // a power of two of them
  View<uint64_t> key_of;      // per cell: full key, 0 = free
  View<const uint32_t> free;  // free cell ids, consumed from *next_free up
  uint32_t* next_free = nullptr;
  uint64_t* failed = nullptr;  // inserts that found no cell since the last rebuild
};

namespace detail {
RLL_HD inline uint64_t cell_tag(uint64_t key) {
  return key & ~CellTableView::kIdMask;
}
}  // namespace detail

// The key's cell, or kNone; thread-safe during a pass.
RLL_HD inline uint32_t cell_find(const CellTableView& t, uint64_t key) {
  const uint32_t mask = uint32_t(t.slots.size - 1);
  uint32_t slot = uint32_t(key >> 32) & mask;
  for (int probe = 0; probe < CellTableView::kMaxProbes; ++probe, slot = (slot + 1) & mask) {
    // Acquire loads, of the slot word and then of the key it published (cell_find_or_insert).
    uint64_t w = atomic_load(&t.slots[slot]);
    if (w == 0) return CellTableView::kNone;
    uint32_t id = uint32_t(w & CellTableView::kIdMask);
    if (detail::cell_tag(w) == detail::cell_tag(key) && atomic_load(&t.key_of[id]) == key)
      return id;
  }
  return CellTableView::kNone;
}

// The key's cell, inserting it if absent (then *created is set); kNone if the table has no free
// cell or the probe limit is reached. Lock-free and thread-safe during a pass.
RLL_HD inline uint32_t cell_find_or_insert(const CellTableView& t, uint64_t key, bool* created) {
  using detail::cell_tag;
  *created = false;
  const uint32_t mask = uint32_t(t.slots.size - 1);
  uint32_t slot = uint32_t(key >> 32) & mask;
  uint32_t mine = CellTableView::kNone;
  for (int probe = 0; probe < CellTableView::kMaxProbes; ++probe, slot = (slot + 1) & mask) {
    uint64_t w = atomic_load(&t.slots[slot]);
    for (;;) {
      if (w != 0) {
        uint32_t id = uint32_t(w & CellTableView::kIdMask);
        // The full key was written before the slot word was published (a release, below), and
        // the word was read by an acquire: the key is read after it, atomically, so that it
        // cannot be an earlier value (the device's L1 keeps no stale copy of it either).
        if (cell_tag(w) == cell_tag(key) && atomic_load(&t.key_of[id]) == key) {
          if (mine != CellTableView::kNone) t.key_of[mine] = 0;  // back at the next rebuild
          return id;
        }
        break;  // another key: probe on
      }
      if (mine == CellTableView::kNone) {
        uint32_t i = atomic_add(t.next_free, 1u);
        if (i >= t.free.size) {
          atomic_add(t.failed, uint64_t(1));
          return CellTableView::kNone;
        }
        mine = t.free[i];
        t.key_of[mine] = key;  // published by the compare-and-swap's release
      }
      // On failure an acquire of the competing word, whose key is read next.
      const uint64_t seen = atomic_cas(&t.slots[slot], w, cell_tag(key) | mine);
      if (seen == w) {
        *created = true;
        return mine;
      }
      w = seen;  // the competing word: re-examine this slot
    }
  }
  if (mine != CellTableView::kNone) t.key_of[mine] = 0;
  atomic_add(t.failed, uint64_t(1));
  return CellTableView::kNone;
}

// Between passes: puts `cell` of `key` in the first free slot from the key's home (linear
// probing, as cell_find looks). Safe in parallel: a slot is taken by compare-and-swap.
RLL_HD inline void cell_place(View<uint64_t> slots, uint64_t key, uint32_t cell) {
  const uint32_t mask = uint32_t(slots.size - 1);
  for (uint32_t slot = uint32_t(key >> 32) & mask;; slot = (slot + 1) & mask)
    if (atomic_cas(&slots[slot], 0, detail::cell_tag(key) | cell) == 0) return;
}

// Between passes, over a backend (core/backend.h): rebuilds the table's index from the cells'
// keys (0: free) and its free list (free cells by id, into `free_room`, capacity long), and
// starts a new pass's counters; returns the cells in use. The slots are filled in id order on
// the host (the layout of earlier versions); in parallel on the GPU, where the order of the
// compare-and-swaps moves keys between the slots of a run but no lookup's answer: cell_find
// finds every key and, linear probing's set of taken slots not depending on the order of
// inserts, cell_find_or_insert reaches the same free slot.
template <typename B>
uint32_t cell_table_rebuild(const B& b, const CellTableView& t, View<uint32_t> free_room) {
  const View<uint64_t> slots = t.slots, key_of = t.key_of;
  b.parallel_for(slots.size, [=] RLL_HD(size_t i) { slots[i] = 0; });
  select_into(
      b, key_of.size, [=] RLL_HD(size_t c) { return key_of[c] == 0; }, free_room);
  const auto used = select_indices(b, key_of.size, [=] RLL_HD(size_t c) { return key_of[c] != 0; });
  const View<const uint32_t> u = used.view();
  b.ordered_for(u.size, [=] RLL_HD(size_t i) { cell_place(slots, key_of[u[i]], u[i]); });
  uint32_t* next_free = t.next_free;
  uint64_t* failed = t.failed;
  b.parallel_for(1, [=] RLL_HD(size_t) {
    *next_free = 0;
    *failed = 0;
  });
  return uint32_t(u.size);
}

// Open-addressing hash table from key to a cell id in [0, capacity): the owner of a
// CellTableView's arrays; lookups and inserts are cell_find and cell_find_or_insert.
class CellTable {
 public:
  static constexpr uint32_t kNone = CellTableView::kNone;
  explicit CellTable(uint32_t capacity);
  uint32_t capacity() const { return m_capacity; }

  // Thread-safe during a pass. Returns the key's cell, inserting it if absent (then *created
  // is set); kNone if the table has no free cell or the probe limit is reached.
  uint32_t find_or_insert(uint64_t key, bool* created) {
    return cell_find_or_insert(view(), key, created);
  }
  // Thread-safe lookup without insertion.
  uint32_t find(uint64_t key) const { return cell_find(const_cast<CellTable*>(this)->view(), key); }
  // The arrays for cell_find / cell_find_or_insert; valid while the table lives.
  CellTableView view() {
    return {view_of(m_slots),
            view_of(m_key_of),
            {m_free.data(), m_capacity - m_used},
            &m_next_free,
            &m_failed};
  }
  // What cell_table_rebuild writes the free list into (capacity long); after a rebuild elsewhere
  // (a device's, copied back), `rebuilt` takes the count of cells it found in use.
  View<uint32_t> free_room() { return view_of(m_free); }
  void rebuilt(uint32_t used) { m_used = used; }

  // Between passes only. Removes the given cells and rebuilds the index and the free list.
  void remove_and_rebuild(const std::vector<uint32_t>& cells);
  // Between passes only. Replaces every cell's key (0: free) and rebuilds the index; false if
  // the keys cannot come from a table of this capacity (wrong count, a key twice).
  bool restore(const std::vector<uint64_t>& key_of);
  bool in_use(uint32_t cell) const { return m_key_of[cell] != 0; }
  uint64_t key_of(uint32_t cell) const { return m_key_of[cell]; }
  uint32_t used() const { return m_used; }
  // Number of cells that could not be given to a point since the last rebuild.
  uint64_t failed_inserts() const { return atomic_load(&m_failed); }
  size_t bytes() const;

 private:
  uint32_t m_capacity, m_mask;
  std::vector<uint64_t> m_slots;   // CellTableView::slots
  std::vector<uint64_t> m_key_of;  // per cell: full key, 0 = free
  std::vector<uint32_t> m_free;    // free cell ids (capacity - used), consumed from m_next_free up
  uint32_t m_next_free = 0;
  uint64_t m_failed = 0;
  uint32_t m_used = 0;
  uint32_t m_slot_count;
};

}  // namespace rll
