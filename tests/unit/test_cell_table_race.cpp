// The cell table's lock-free insert under a race, over the header-only CellTableView (the very
// functions a GPU runs, with core/device.h's host atomics): 8 threads insert overlapping keys into
// a small table at once. No key may end in two cells, every thread must get the key's one cell,
// and a cell's full key must be the one its slot word names. The same file, compiled alone with
// -fsanitize=thread (scripts/tsan-cell-table.sh), checks the memory orders: the full key is
// written before the slot word's release and read after its acquire, so ThreadSanitizer reports
// no race (with a relaxed load of the slot word it does).
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <thread>
#include <utility>
#include <vector>

#include "rll/learn/cell_grid.h"

namespace rll {
namespace {

// A fresh table's arrays (what CellTable's constructor and rebuild make): no slot taken, every
// cell free, handed out in id order.
struct RaceTable {
  std::vector<uint64_t> slots, key_of;
  std::vector<uint32_t> free;
  uint32_t next_free = 0;
  uint64_t failed = 0;
  RaceTable(uint32_t capacity, uint32_t slot_count)
      : slots(slot_count, 0), key_of(capacity, 0), free(capacity) {
    for (uint32_t i = 0; i < capacity; ++i) free[i] = i;
  }
  CellTableView view() {
    return {view_of(slots), view_of(key_of), view_of(std::as_const(free)), &next_free, &failed};
  }
};

// Keys that crowd their slots: four keys to a home slot (the key's high word), homes 16 slots
// apart, so that the 8 threads race for the same slots and probe through each other's short runs.
// The keys of a home share the slot word's tag (the key's bits above the cell id): only the full
// key, key_of, tells them apart.
std::vector<uint64_t> crowded_keys(size_t count) {
  std::vector<uint64_t> keys;
  for (uint64_t i = 0; i < count; ++i) keys.push_back((1 + i % 50) * 16 << 32 | (i + 1));
  return keys;
}

TEST(CellTableRace, EightThreadsInsertingOverlappingKeysGiveEachKeyOneCell) {
  constexpr int kThreads = 8;
  constexpr int kRounds = 20;  // fresh tables, each raced over anew
  const std::vector<uint64_t> keys = crowded_keys(200);
  const size_t n = keys.size();
  // Room for every thread's reservation of every key (a thread that loses a key's race gives its
  // reserved cell back only at the next rebuild); slots for twice that, as CellTable takes.
  const uint32_t capacity = uint32_t(kThreads * n);
  for (int round = 0; round < kRounds; ++round) {
    RaceTable table(capacity, 4096);
    const CellTableView t = table.view();
    std::vector<std::vector<uint32_t>> got(kThreads, std::vector<uint32_t>(n, ~0u));
    std::vector<std::vector<uint8_t>> created(kThreads, std::vector<uint8_t>(n, 0));
    std::atomic<int> ready{0};
    std::vector<std::thread> pool;
    for (int th = 0; th < kThreads; ++th)
      pool.emplace_back([&, th] {
        ready.fetch_add(1);
        while (ready.load() < kThreads) std::this_thread::yield();  // start together
        // Each thread from its own offset and in its own direction: every key raced for.
        for (size_t j = 0; j < n; ++j) {
          const size_t k = th % 2 ? (j + size_t(th) * 7) % n : (n - 1 - j + size_t(th) * 13) % n;
          bool made = false;
          got[th][k] = cell_find_or_insert(t, keys[k], &made);
          created[th][k] = made;
          // A lookup of a key another thread is inserting: none, or its one cell (checked below).
          const size_t other = (k + 1) % n;
          const uint32_t seen = cell_find(t, keys[other]);
          if (seen != CellTableView::kNone) EXPECT_EQ(table.key_of[seen], keys[other]);
        }
      });
    for (auto& th : pool) th.join();

    std::vector<int> owner(capacity, -1);
    for (size_t k = 0; k < n; ++k) {
      const uint32_t id = got[0][k];
      ASSERT_LT(id, capacity) << "round " << round << ": key " << k << " got no cell";
      int makers = 0;
      for (int th = 0; th < kThreads; ++th) {
        ASSERT_EQ(got[th][k], id) << "round " << round << ": key " << k << " in two cells";
        makers += created[th][k];
      }
      EXPECT_EQ(makers, 1) << "round " << round << ": key " << k;
      ASSERT_EQ(owner[id], -1) << "round " << round << ": cell " << id << " of two keys";
      owner[id] = int(k);
      EXPECT_EQ(table.key_of[id], keys[k]);
      EXPECT_EQ(cell_find(t, keys[k]), id);
    }
    // Every taken slot names a cell whose full key has the slot word's tag; no key twice.
    std::vector<uint64_t> in_slots;
    for (uint64_t w : table.slots)
      if (w != 0) {
        const uint64_t key = table.key_of[w & CellTableView::kIdMask];
        EXPECT_EQ(key & ~CellTableView::kIdMask, w & ~CellTableView::kIdMask);
        in_slots.push_back(key);
      }
    EXPECT_EQ(in_slots.size(), n);
    std::sort(in_slots.begin(), in_slots.end());
    EXPECT_EQ(std::adjacent_find(in_slots.begin(), in_slots.end()), in_slots.end())
        << "round " << round << ": a key in two slots";
    EXPECT_EQ(table.failed, 0u);
  }
}

}  // namespace
}  // namespace rll
