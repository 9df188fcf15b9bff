// rll's cell grid: the key of a point's cell, and the view-direction bins of glossy points
// (rll.direction_bins).
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <thread>

#include "rll/core/params.h"
#include "rll/learn/cell_grid.h"
#include "rll/lights/light_dispatch.h"
#include "rll/lights/rll_sampler.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;

namespace {

// Cell of a point on the floor of cornell-box seen from `wo`.
uint32_t cell_of(const RllLightSampler& rll, const Scene& scene, Vec3 wo, bool glossy) {
  LightContext c;
  c.p = 0.5f * (scene.bounds.lo + scene.bounds.hi);
  c.p.y = scene.bounds.lo.y;
  c.n = c.ns = Vec3(0, 1, 0);
  c.wo = wo;
  c.glossy = glossy;
  c.footprint = 1e-3f * length(scene.bounds.diagonal());
  prepare_point(rll.sampler_view(), c, 0.5f);
  return c.cell;
}

}  // namespace

TEST(CellGrid, DirectionBinsSplitGlossyPointsByViewDirection) {
  Scene scene = small_builtin_scene("cornell-box", 16, 16);
  const LightTree tree = build_light_tree(scene);
  const Vec3 up_left = normalize(Vec3(-1, 1, 0)), up_right = normalize(Vec3(1, 1, 0));
  RllLightSampler binned(scene, tree, rll_settings_from(Params::parse({"rll.direction_bins=4"})));
  RllLightSampler plain(scene, tree, rll_settings_from(Params()));
  // A glossy point seen from two far-apart directions: two cells with bins, one without.
  EXPECT_NE(cell_of(binned, scene, up_left, true), cell_of(binned, scene, up_right, true));
  EXPECT_EQ(cell_of(plain, scene, up_left, true), cell_of(plain, scene, up_right, true));
  // A diffuse point, or one seen from an unknown direction, is never binned.
  EXPECT_EQ(cell_of(binned, scene, up_left, false), cell_of(binned, scene, up_right, false));
  EXPECT_EQ(cell_of(binned, scene, Vec3(0), true), cell_of(binned, scene, Vec3(0), false));
  // Nearby directions share a bin.
  EXPECT_EQ(cell_of(binned, scene, up_left, true),
            cell_of(binned, scene, normalize(Vec3(-1, 1.02f, 0.01f)), true));
}

TEST(CellGrid, DirectionBinsCoverTheSphereAndEnterTheKey) {
  CellGridSettings s;
  s.direction_bins = 3;
  const CellKeyer keyer(s, Bounds3{Vec3(0), Vec3(1)});
  std::vector<int> hits(9, 0);
  for (int i = 0; i < 2000; ++i) {
    const float z = 1 - 2 * (float(i) + 0.5f) / 2000, phi = 2.39996f * float(i),
                r = std::sqrt(1 - z * z);
    const uint32_t b = keyer.direction_bin(Vec3(r * std::cos(phi), r * std::sin(phi), z));
    ASSERT_GE(b, 1u);
    ASSERT_LE(b, 9u);
    ++hits[b - 1];
  }
  for (int h : hits) EXPECT_GT(h, 0);
  // Each bin keys its own cell.
  CellCoord c = keyer.locate_at_level(Vec3(0.3f), Vec3(0, 0, 1), -3);
  std::vector<uint64_t> keys;
  for (uint32_t dir = 0; dir <= 9; ++dir) {
    c.dir = dir;
    keys.push_back(keyer.key(c));
  }
  std::sort(keys.begin(), keys.end());
  EXPECT_EQ(std::unique(keys.begin(), keys.end()), keys.end());
}

TEST(CellGrid, LevelRoundingNearestOrStochastic) {
  // The level of detail of a footprint: with `Nearest` one level whatever u, the cell edge
  // within a factor sqrt(2) of the footprint's cell size; with `Stochastic` the level below or
  // above, the upper one for a fraction of u equal to the fractional level (so that the edge
  // follows the footprint on average).
  const Bounds3 bounds{Vec3(0), Vec3(1)};
  const float diameter = length(bounds.diagonal());
  CellGridSettings near, random;
  random.level_rounding = CellGridSettings::LevelRounding::Stochastic;
  ASSERT_EQ(near.level_rounding, CellGridSettings::LevelRounding::Nearest) << "the default";
  const CellKeyer kn(near, bounds), kr(random, bounds);
  const Vec3 p(0.3f), n(0, 0, 1);
  for (float footprint : {1e-4f, 3e-4f, 7.1e-4f, 1.5e-3f, 4e-3f}) {
    const float size = kn.cell_size(footprint), lf = std::log2(size / diameter);
    const int level = kn.locate(p, n, footprint, 0.0f).level;
    const float edge = std::ldexp(diameter, level);
    EXPECT_LE(edge, size * std::sqrt(2.0f) * 1.0001f) << footprint;
    EXPECT_GE(edge, size / std::sqrt(2.0f) * 0.9999f) << footprint;
    int upper = 0;
    const int samples = 1000;
    for (int i = 0; i < samples; ++i) {
      const float u = (float(i) + 0.5f) / samples;
      EXPECT_EQ(kn.locate(p, n, footprint, u).level, level) << "nearest must not depend on u";
      const int l = kr.locate(p, n, footprint, u).level;
      ASSERT_TRUE(l == int(std::floor(lf)) || l == int(std::floor(lf)) + 1) << l << " for " << lf;
      upper += l == int(std::floor(lf)) + 1;
    }
    EXPECT_NEAR(double(upper) / samples, lf - std::floor(lf), 2.0 / samples) << footprint;
  }
}

TEST(CellGrid, LevelRoundingIsAParameterFermatKeepsStochastic) {
  EXPECT_EQ(rll_settings_from(Params{}).grid.level_rounding,
            CellGridSettings::LevelRounding::Nearest);
  EXPECT_EQ(rll_settings_from(Params::parse({"rll.level_rounding=stochastic"})).grid.level_rounding,
            CellGridSettings::LevelRounding::Stochastic);
  EXPECT_EQ(fermat_settings().grid.level_rounding, CellGridSettings::LevelRounding::Stochastic);
  EXPECT_THROW(rll_settings_from(Params::parse({"rll.level_rounding=up"})), std::exception);
}

// CellTable, through its public API only: many threads inserting and looking up overlapping keys
// at once, a table that fills up, and eviction between passes.
namespace {

// Distinct, well-spread nonzero keys (splitmix64 of 1..count): slots come from the key's high bits.
std::vector<uint64_t> table_keys(size_t count, uint64_t salt) {
  std::vector<uint64_t> keys;
  for (uint64_t i = 1; keys.size() < count; ++i) {
    uint64_t z = (i + salt * 0x100000000ull) * 0x9e3779b97f4a7c15ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    if (z != 0) keys.push_back(z);
  }
  return keys;
}

struct ThreadResult {
  std::vector<uint32_t> id;      // per key: what find_or_insert returned
  std::vector<uint8_t> created;  // per key: whether this thread's call created the cell
  std::vector<uint32_t> found;   // per key: what a find() right after another thread's insert saw
  uint64_t none = 0;             // calls that returned kNone
};

// `threads` threads, each calling find_or_insert on every key, starting at its own offset so that
// the threads race on the same keys, with a find() of a key another thread is inserting between.
// With `overlap` false each thread inserts only its own share of the keys (k % threads == t):
// then no two threads race for one key, whose loser's reserved cell stays unused until the next
// rebuild (by design: "goes back at the next rebuild").
std::vector<ThreadResult> insert_concurrently(CellTable& table, const std::vector<uint64_t>& keys,
                                              int threads, bool overlap = true) {
  std::vector<ThreadResult> out(static_cast<size_t>(threads));
  std::atomic<int> ready{0};
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t)
    pool.emplace_back([&, t] {
      ThreadResult& r = out[size_t(t)];
      const size_t n = keys.size();
      r.id.assign(n, CellTable::kNone);
      r.created.assign(n, 0);
      r.found.assign(n, CellTable::kNone);
      ready.fetch_add(1);
      while (ready.load() < threads) std::this_thread::yield();  // start together
      for (size_t j = 0; j < n; ++j) {
        const size_t k = (j + size_t(t) * n / size_t(threads)) % n;
        if (!overlap && k % size_t(threads) != size_t(t)) continue;
        bool created = false;
        r.id[k] = table.find_or_insert(keys[k], &created);
        r.created[k] = created;
        r.none += r.id[k] == CellTable::kNone;
        const size_t other = (k + n / size_t(threads)) % n;  // the key the next thread is at
        r.found[other] = table.find(keys[other]);
      }
    });
  for (auto& th : pool) th.join();
  return out;
}

}  // namespace

TEST(CellTable, ConcurrentInsertsGiveEveryKeyExactlyOneCell) {
  // Room for every thread's reservation of every key: a thread that loses the race for a key's
  // slot to another inserting the same key gives its reserved cell back only at the next rebuild,
  // so racing threads use up cells (in a table of 4096, 3000 keys from 8 threads got kNone in 26
  // of 500 runs on a loaded machine).
  const uint32_t capacity = 8 * 4096;
  const std::vector<uint64_t> keys = table_keys(3000, 1);
  CellTable table(capacity);
  const auto results = insert_concurrently(table, keys, 8);
  std::vector<uint32_t> owner(capacity, CellTable::kNone);
  for (size_t k = 0; k < keys.size(); ++k) {
    const uint32_t id = results[0].id[k];
    ASSERT_LT(id, capacity) << "key " << k << " got no cell in a table with room";
    int creators = 0;
    for (const ThreadResult& r : results) {
      ASSERT_EQ(r.id[k], id) << "two threads got different cells for key " << k;
      creators += r.created[k];
      // A lookup racing the insert sees no cell or the key's own, never another key's.
      ASSERT_TRUE(r.found[k] == CellTable::kNone || r.found[k] == id) << "key " << k;
    }
    EXPECT_EQ(creators, 1) << "key " << k << " created " << creators << " times";
    ASSERT_EQ(owner[id], CellTable::kNone)
        << "cell " << id << " given to keys " << owner[id] << " and " << k;
    owner[id] = uint32_t(k);
    EXPECT_EQ(table.find(keys[k]), id);
    EXPECT_EQ(table.key_of(id), keys[k]);
    EXPECT_TRUE(table.in_use(id));
  }
  EXPECT_EQ(table.failed_inserts(), 0u);
  // Between passes the index is rebuilt: every key keeps its cell and the count is exact.
  table.remove_and_rebuild({});
  EXPECT_EQ(table.used(), keys.size());
  for (size_t k = 0; k < keys.size(); ++k) EXPECT_EQ(table.find(keys[k]), results[0].id[k]);
  EXPECT_EQ(table.find(table_keys(1, 7)[0]), CellTable::kNone) << "a key never inserted";
}

TEST(CellTable, FullTableFailsInsertsWithoutBlockingAndKeepsItsCells) {
  // Four times as many keys as cells, from 8 threads at once: the table fills, every later insert
  // of a new key returns kNone and is counted, and none of this blocks (a hang fails by timeout).
  const uint32_t capacity = 256;
  const std::vector<uint64_t> keys = table_keys(4 * capacity, 2);
  CellTable table(capacity);
  const auto results = insert_concurrently(table, keys, 8);
  uint64_t none = 0;
  std::vector<uint32_t> owner(capacity, CellTable::kNone);
  std::vector<uint32_t> id_of(keys.size(), CellTable::kNone);
  for (const ThreadResult& r : results) none += r.none;
  for (size_t k = 0; k < keys.size(); ++k)
    for (const ThreadResult& r : results) {
      if (r.id[k] == CellTable::kNone) continue;
      ASSERT_LT(r.id[k], capacity);
      // A key that got a cell got the same one in every thread that got one.
      if (id_of[k] != CellTable::kNone) {
        ASSERT_EQ(r.id[k], id_of[k]) << "key " << k;
      }
      id_of[k] = r.id[k];
    }
  size_t stored = 0;
  for (size_t k = 0; k < keys.size(); ++k) {
    if (id_of[k] == CellTable::kNone) continue;
    ++stored;
    ASSERT_EQ(owner[id_of[k]], CellTable::kNone) << "cell " << id_of[k] << " given to two keys";
    owner[id_of[k]] = uint32_t(k);
  }
  EXPECT_LE(stored, capacity);
  EXPECT_GT(stored, 0u);  // how many depends on the races (see above)
  EXPECT_GT(none, 0u);
  EXPECT_EQ(table.failed_inserts(), none) << "every kNone is counted";
  // Full: the keys it holds are still found (by lookup and by insert), a new key fails, counted.
  bool created = true;
  for (size_t k = 0; k < keys.size(); ++k) {
    if (id_of[k] == CellTable::kNone) continue;
    EXPECT_EQ(table.find(keys[k]), id_of[k]);
    EXPECT_EQ(table.find_or_insert(keys[k], &created), id_of[k]);
    EXPECT_FALSE(created);
  }
  EXPECT_EQ(table.find_or_insert(table_keys(1, 9)[0], &created), CellTable::kNone);
  EXPECT_EQ(table.failed_inserts(), none + 1);
  table.remove_and_rebuild({});
  EXPECT_EQ(table.used(), stored);
  EXPECT_EQ(table.failed_inserts(), 0u) << "the count restarts at every rebuild";
}

TEST(CellTable, EvictionFreesCellsForReuseAndSurvivorsKeepTheirs) {
  const uint32_t capacity = 256;
  CellTable table(capacity);
  const std::vector<uint64_t> first = table_keys(capacity, 3);
  std::vector<uint32_t> id(capacity);
  bool created = false;
  for (uint32_t k = 0; k < capacity; ++k) {
    id[k] = table.find_or_insert(first[k], &created);
    ASSERT_NE(id[k], CellTable::kNone) << "key " << k << " of a table with room";
  }
  EXPECT_EQ(table.find_or_insert(table_keys(1, 9)[0], &created), CellTable::kNone) << "full";
  // Evict every third cell.
  std::vector<uint32_t> evicted;
  for (uint32_t k = 0; k < capacity; k += 3) evicted.push_back(id[k]);
  table.remove_and_rebuild(evicted);
  EXPECT_EQ(table.used(), capacity - evicted.size());
  EXPECT_EQ(table.failed_inserts(), 0u);
  for (uint32_t k = 0; k < capacity; ++k) {
    if (k % 3 == 0) {
      EXPECT_FALSE(table.in_use(id[k]));
      EXPECT_EQ(table.find(first[k]), CellTable::kNone) << "evicted key " << k << " still found";
    } else {
      EXPECT_EQ(table.find(first[k]), id[k]) << "survivor " << k << " lost its cell";
      EXPECT_EQ(table.key_of(id[k]), first[k]);
    }
  }
  // New keys, from 8 threads at once (each its own), take exactly the freed cells; then the table
  // is full again.
  const std::vector<uint64_t> second = table_keys(evicted.size(), 4);
  const auto results = insert_concurrently(table, second, 8, false);
  std::vector<uint32_t> reused;
  for (size_t k = 0; k < second.size(); ++k) {
    const uint32_t got = results[k % results.size()].id[k];
    ASSERT_NE(got, CellTable::kNone) << "new key " << k << " found no freed cell";
    EXPECT_EQ(table.find(second[k]), got);
    reused.push_back(got);
  }
  std::sort(reused.begin(), reused.end());
  std::sort(evicted.begin(), evicted.end());
  EXPECT_EQ(reused, evicted);
  EXPECT_EQ(table.find_or_insert(table_keys(1, 9)[0], &created), CellTable::kNone);
  table.remove_and_rebuild({});
  EXPECT_EQ(table.used(), capacity);
  for (uint32_t k = 1; k < capacity; k += 3) EXPECT_EQ(table.find(first[k]), id[k]);
}
