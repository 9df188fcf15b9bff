#include "rll/learn/cell_grid.h"

#include <algorithm>
#include <atomic>

#include "rll/core/error.h"
#include "rll/core/rng.h"
#include "rll/core/sampling.h"

namespace rll {

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
  m_jitter_normal = {(rng.next_float() - 0.5f) * m_s.jitter,
                     (rng.next_float() - 0.5f) * m_s.jitter};
}

CellTable::CellTable(uint32_t capacity) : m_capacity(capacity) {
  if (capacity < 1 || capacity > (1u << 24))
    fail("rll.capacity must be in [1, 16777216] (got {})", capacity);
  uint32_t slots = 1;
  while (slots < 2 * capacity) slots <<= 1;
  m_slot_count = slots;
  m_mask = slots - 1;
  m_slots.assign(slots, 0);
  m_key_of.assign(capacity, 0);
  m_free.assign(capacity, 0);
  remove_and_rebuild({});
}

size_t CellTable::bytes() const {
  return m_slot_count * sizeof(uint64_t) + m_key_of.size() * sizeof(uint64_t) +
         m_free.size() * sizeof(uint32_t);  // (the free list's array holds capacity ids)
}

void CellTable::remove_and_rebuild(const std::vector<uint32_t>& cells) {
  for (uint32_t c : cells) m_key_of[c] = 0;
  m_used = cell_table_rebuild(HostBackend{}, view(), free_room());
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
