#include "rll/learn/cell_grid.h"

#include <algorithm>

#include "rll/core/error.h"
#include "rll/core/rng.h"
#include "rll/core/sampling.h"

namespace rll {

Vec2 octahedral_encode(const Vec3& n) {
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

Vec3 octahedral_decode(Vec2 e) {
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

CellKeyer::CellKeyer(const CellGridSettings& s, const Bounds3& b) : m_s(s) {
  m_extent = std::max(1e-6f, length(b.diagonal()));
  m_origin = b.lo - Vec3(m_extent);
  m_log2_extent = std::log2(m_extent);
  set_pass(0, 0);
}

void CellKeyer::set_pass(uint64_t pass, uint64_t seed) {
  Pcg32 rng(mix64(seed ^ 0x5bd1e995ull) + pass, 0x2545f4914f6cdd1dull);
  Vec2 d = sample_uniform_disk_concentric({rng.next_float(), rng.next_float()});
  m_jitter_disk = {d.x * m_s.jitter, d.y * m_s.jitter};
  m_jitter_normal = {(rng.next_float() - 0.5f) * m_s.jitter, (rng.next_float() - 0.5f) * m_s.jitter};
}

float CellKeyer::cell_size(float footprint) const {
  float r = std::min(m_s.footprint_scale * footprint, m_s.max_cell * m_extent);
  return std::max(2 * r, m_extent * 0x1p-24f);
}

int CellKeyer::level_of(float footprint, float u) const {
  // Level of detail: the cell edge is a power of two times the scene diameter: the nearest in
  // log scale, or rounded up or down at random in proportion to the fractional level, so that
  // cell size follows the footprint on average.
  float lf = std::log2(cell_size(footprint)) - m_log2_extent;
  if (m_s.level_rounding == CellGridSettings::LevelRounding::Nearest)
    return int(std::floor(lf + 0.5f));
  float lo = std::floor(lf);
  return int(lo) + (u < lf - lo ? 1 : 0);
}

CellCoord CellKeyer::locate(const Vec3& p, const Vec3& n, float footprint, float u) const {
  return locate_with(p, n, level_of(footprint, u), m_jitter_disk, m_jitter_normal);
}

CellCoord CellKeyer::locate_at_level(const Vec3& p, const Vec3& n, int level) const {
  return locate_with(p, n, level, m_jitter_disk, m_jitter_normal);
}

CellCoord CellKeyer::locate_jittered(const Vec3& p, const Vec3& n, float footprint, float u,
                                     Vec2 disk, Vec2 normal) const {
  return locate_with(p, n, level_of(footprint, u), disk, normal);
}

CellCoord CellKeyer::locate_with(const Vec3& p, const Vec3& n, int level, Vec2 disk,
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
    Frame f(octahedral_decode({(c.nu + 0.5f - normal.x) / bins, (c.nv + 0.5f - normal.y) / bins}));
    q = q + (f.s * disk.x + f.t * disk.y) * size;
  }
  c.x = int64_t(std::floor(q.x / size));
  c.y = int64_t(std::floor(q.y / size));
  c.z = int64_t(std::floor(q.z / size));
  return c;
}

uint64_t CellKeyer::key(const CellCoord& c) const {
  uint64_t h = mix64(uint64_t(c.x) * 0x9e3779b97f4a7c15ull ^ uint64_t(c.level + 64));
  h = mix64(h ^ (uint64_t(c.y) * 0xc2b2ae3d27d4eb4full));
  h = mix64(h ^ (uint64_t(c.z) * 0x165667b19e3779f9ull));
  // (A cell not binned by direction, dir 0, keeps the key it had before direction bins.)
  h = mix64(h ^ (uint64_t(c.dir) << 32 | uint64_t(c.nu) << 16 | uint64_t(c.nv)));
  return h | 1;  // 0 means "empty"
}

uint32_t CellKeyer::direction_bin(const Vec3& wo) const {
  const int bins = m_s.direction_bins;
  const Vec2 o = octahedral_encode(normalize(wo));
  const int u = clamp(int(std::floor(o.x * bins)), 0, bins - 1), v = clamp(int(std::floor(o.y * bins)), 0, bins - 1);
  return 1 + uint32_t(u * bins + v);
}

CellAnchor CellKeyer::anchor(const CellCoord& c) const {
  const int bins = m_s.normal_bins;
  CellAnchor a;
  a.level = c.level;
  a.n = octahedral_decode({(c.nu + 0.5f - m_jitter_normal.x) / bins, (c.nv + 0.5f - m_jitter_normal.y) / bins});
  float size = std::ldexp(m_extent, c.level);
  Frame f(a.n);
  Vec3 q((c.x + 0.5f) * size, (c.y + 0.5f) * size, (c.z + 0.5f) * size);
  a.p = q + m_origin - (f.s * m_jitter_disk.x + f.t * m_jitter_disk.y) * size;
  return a;
}

CellTable::CellTable(uint32_t capacity) : m_capacity(capacity) {
  if (capacity < 1 || capacity > (1u << 24)) fail("rll.capacity must be in [1, 16777216] (got {})", capacity);
  uint32_t slots = 1;
  while (slots < 2 * capacity) slots <<= 1;
  m_slot_count = slots;
  m_mask = slots - 1;
  m_slots = std::make_unique<std::atomic<uint64_t>[]>(slots);
  for (uint32_t i = 0; i < slots; ++i) m_slots[i].store(0, std::memory_order_relaxed);
  m_key_of.assign(capacity, 0);
  remove_and_rebuild({});
}

size_t CellTable::bytes() const {
  return m_slot_count * sizeof(uint64_t) + m_key_of.size() * sizeof(uint64_t) + m_free.size() * sizeof(uint32_t);
}

namespace {
constexpr uint64_t kIdMask = (uint64_t(1) << 24) - 1;
inline uint64_t tag(uint64_t key) { return key & ~kIdMask; }
}  // namespace

uint32_t CellTable::find(uint64_t key) const {
  uint32_t slot = uint32_t(key >> 32) & m_mask;
  for (int probe = 0; probe < kMaxProbes; ++probe, slot = (slot + 1) & m_mask) {
    uint64_t w = m_slots[slot].load(std::memory_order_acquire);
    if (w == 0) return kNone;
    uint32_t id = uint32_t(w & kIdMask);
    if (tag(w) == tag(key) && m_key_of[id] == key) return id;
  }
  return kNone;
}

uint32_t CellTable::find_or_insert(uint64_t key, bool* created) {
  *created = false;
  uint32_t slot = uint32_t(key >> 32) & m_mask;
  uint32_t mine = kNone;
  for (int probe = 0; probe < kMaxProbes; ++probe, slot = (slot + 1) & m_mask) {
    uint64_t w = m_slots[slot].load(std::memory_order_acquire);
    for (;;) {
      if (w != 0) {
        uint32_t id = uint32_t(w & kIdMask);
        // The full key is published before the slot word (release below), so it is valid here.
        if (tag(w) == tag(key) && m_key_of[id] == key) {
          if (mine != kNone) m_key_of[mine] = 0;  // our reserved id goes back at the next rebuild
          return id;
        }
        break;  // another key: probe on
      }
      if (mine == kNone) {
        uint32_t i = m_next_free.fetch_add(1, std::memory_order_relaxed);
        if (i >= m_free.size()) {
          m_failed.fetch_add(1, std::memory_order_relaxed);
          return kNone;
        }
        mine = m_free[i];
        m_key_of[mine] = key;
      }
      if (m_slots[slot].compare_exchange_weak(w, tag(key) | mine, std::memory_order_acq_rel,
                                              std::memory_order_acquire)) {
        *created = true;
        return mine;
      }
      // w now holds the competing word: re-examine this slot.
    }
  }
  if (mine != kNone) m_key_of[mine] = 0;
  m_failed.fetch_add(1, std::memory_order_relaxed);
  return kNone;
}

void CellTable::remove_and_rebuild(const std::vector<uint32_t>& cells) {
  for (uint32_t c : cells) m_key_of[c] = 0;
  for (uint32_t i = 0; i < m_slot_count; ++i) m_slots[i].store(0, std::memory_order_relaxed);
  m_free.clear();
  m_used = 0;
  for (uint32_t c = 0; c < m_capacity; ++c) {
    uint64_t key = m_key_of[c];
    if (key == 0) {
      m_free.push_back(c);
      continue;
    }
    ++m_used;
    uint32_t slot = uint32_t(key >> 32) & m_mask;
    while (m_slots[slot].load(std::memory_order_relaxed) != 0) slot = (slot + 1) & m_mask;
    m_slots[slot].store(tag(key) | c, std::memory_order_relaxed);
  }
  m_next_free.store(0, std::memory_order_relaxed);
  m_failed.store(0, std::memory_order_relaxed);
  std::atomic_thread_fence(std::memory_order_release);
}

bool CellTable::restore(const std::vector<uint64_t>& key_of) {
  if (key_of.size() != m_capacity) return false;
  std::vector<uint64_t> keys;
  for (uint64_t k : key_of)
    if (k != 0) keys.push_back(k);
  std::sort(keys.begin(), keys.end());
  if (std::adjacent_find(keys.begin(), keys.end()) != keys.end()) return false;
  m_key_of = key_of;
  remove_and_rebuild({});
  return true;
}

}  // namespace rll
