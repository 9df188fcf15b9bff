// RLL's cells: a sparse 5D grid over (position, normal) addressed by hashing. The position cell
// size follows the ray footprint, quantized to a power-of-two level of detail (the nearest, or by
// stochastic rounding); position and normal are jittered by an offset that changes every pass. The
// table has a fixed capacity and is lock-free: inserts never block, and a failed insert (table
// full) means "no cell" (the sampler falls back to its prior) until end-of-pass eviction frees
// room.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

#include "rll/core/math.h"

namespace rll {

struct CellGridSettings {
  float footprint_scale = 4;   // cell radius = footprint_scale * ray footprint ...
  float max_cell = 0.05f;      // ... at most max_cell * scene diameter
  int normal_bins = 4;         // bins per axis of the octahedral normal map
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
  int level = 0;  // edge = scene diameter * 2^level
  int nu = 0, nv = 0;  // octahedral normal bin
  uint32_t dir = 0;    // 1 + the view direction's bin on a glossy surface; 0: not binned
};

// A representative point of a cell: the centre of its box and of its normal bin.
struct CellAnchor {
  Vec3 p, n;
  int level = 0;
};

// Maps shading points to cells and cells to 64-bit keys (never 0).
class CellKeyer {
 public:
  CellKeyer(const CellGridSettings& s, const Bounds3& scene_bounds);
  // Sets the jitter for a pass (every pass gets a fresh one, from the pass index and seed).
  void set_pass(uint64_t pass, uint64_t seed);
  // Cell of point p with unit normal n and ray footprint radius `footprint`; u drives the
  // stochastic rounding of the level of detail (with LevelRounding::Stochastic).
  CellCoord locate(const Vec3& p, const Vec3& n, float footprint, float u) const;
  // The cell of p, n at a given level of detail.
  CellCoord locate_at_level(const Vec3& p, const Vec3& n, int level) const;
  // As locate, with a jitter of this sample's own instead of the pass's (Fermat's per-sample
  // jitter): `disk` in the tangent plane in cell edges, `normal` in normal bins.
  CellCoord locate_jittered(const Vec3& p, const Vec3& n, float footprint, float u, Vec2 disk,
                            Vec2 normal) const;
  uint64_t key(const CellCoord& c) const;
  // 1 + the octahedral bin of the direction wo (any length > 0), direction_bins per axis.
  uint32_t direction_bin(const Vec3& wo) const;
  uint64_t key(const Vec3& p, const Vec3& n, float footprint, float u) const { return key(locate(p, n, footprint, u)); }
  // The cell's centre under this pass's jitter (a function of the coordinates alone).
  CellAnchor anchor(const CellCoord& c) const;
  // Cell edge length for a footprint, before stochastic rounding (for tests).
  float cell_size(float footprint) const;

 private:
  int level_of(float footprint, float u) const;
  CellCoord locate_with(const Vec3& p, const Vec3& n, int level, Vec2 disk, Vec2 normal) const;
  CellGridSettings m_s;
  Vec3 m_origin;
  float m_extent;       // scene diameter
  float m_log2_extent;
  Vec2 m_jitter_disk;   // in the tangent plane, cell units
  Vec2 m_jitter_normal; // in normal bins
};

// Octahedral map of a unit vector to [0,1]^2, and back.
Vec2 octahedral_encode(const Vec3& n);
Vec3 octahedral_decode(Vec2 e);

// Open-addressing hash table from key to a cell id in [0, capacity).
class CellTable {
 public:
  static constexpr uint32_t kNone = ~0u;
  explicit CellTable(uint32_t capacity);
  uint32_t capacity() const { return m_capacity; }

  // Thread-safe during a pass. Returns the key's cell, inserting it if absent (then *created
  // is set); kNone if the table has no free cell or the probe limit is reached.
  uint32_t find_or_insert(uint64_t key, bool* created);
  // Thread-safe lookup without insertion.
  uint32_t find(uint64_t key) const;

  // Between passes only. Removes the given cells and rebuilds the index and the free list.
  void remove_and_rebuild(const std::vector<uint32_t>& cells);
  // Between passes only. Replaces every cell's key (0: free) and rebuilds the index; false if
  // the keys cannot come from a table of this capacity (wrong count, a key twice).
  bool restore(const std::vector<uint64_t>& key_of);
  bool in_use(uint32_t cell) const { return m_key_of[cell] != 0; }
  uint64_t key_of(uint32_t cell) const { return m_key_of[cell]; }
  uint32_t used() const { return m_used; }
  // Number of cells that could not be given to a point since the last rebuild.
  uint64_t failed_inserts() const { return m_failed.load(std::memory_order_relaxed); }
  size_t bytes() const;

 private:
  static constexpr int kMaxProbes = 64;
  uint32_t m_capacity, m_mask;
  // Slot word: (key >> 24) << 24 | cell id, or 0 when empty. The full key is kept per cell.
  std::unique_ptr<std::atomic<uint64_t>[]> m_slots;
  std::vector<uint64_t> m_key_of;        // per cell: full key, 0 = free
  std::vector<uint32_t> m_free;          // free cell ids, consumed from m_next_free up
  std::atomic<uint32_t> m_next_free{0};
  std::atomic<uint64_t> m_failed{0};
  uint32_t m_used = 0;
  uint32_t m_slot_count;
};

}  // namespace rll
