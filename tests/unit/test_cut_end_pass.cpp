// RLL's end of pass as host-and-device functions (learn/cut_end_pass.h, lights/rll_end_pass.h):
// cut_end_pass run over many cells at once by host_parallel_for leaves every array as the
// class's end_pass does cell by cell; the guided factors baked without a stack equal a
// recursive bake; pooling's sorted coarse cells are found by binary search and fold a coarse
// cell's rewards in the order of its cells' keys, as a map of sums does.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <memory>

#include "rll/core/device.h"
#include "rll/core/rng.h"
#include "rll/learn/cut_end_pass.h"
#include "rll/lights/rll_end_pass.h"
#include "support/test_support.h"

using namespace rll;

namespace {

struct Variant {
  const char* name;
  CutSettings s;
};

std::vector<Variant> variants() {
  CutSettings splits;
  splits.cut_size = 24;  // small, so that collapses happen constantly
  splits.initial_size = 16;
  splits.splits = 6;
  splits.threshold = 1.1f;
  CutSettings exponential = splits;
  exponential.rule = LearningRule::Exponential;
  exponential.target = LearnTarget::Mean;
  CutSettings fermat = splits;
  fermat.prior = fermat.split = ClusterWeight::Uniform;
  fermat.q_init = 0.01f;
  fermat.trust = 0;
  CutSettings guided;
  guided.cut_size = guided.initial_size = 32;
  guided.guided = true;
  CutSettings power = splits;
  power.prior = power.split = ClusterWeight::Power;
  power.prior_in_cdf = false;
  return {{"splits", splits},
          {"exponential", exponential},
          {"fermat", fermat},
          {"guided", guided},
          {"power", power}};
}

constexpr uint32_t kCells = 40;

// Two stores given the same anchors and, every pass, the same rewards.
struct Twins {
  std::unique_ptr<CutStore> a, b;
  Twins(const LightTree& tree, const CutSettings& s) {
    a = std::make_unique<CutStore>(tree, kCells, s, 2.0);
    b = std::make_unique<CutStore>(tree, kCells, s, 2.0);
    Pcg32 rng(7);
    for (uint32_t c = 0; c < kCells; ++c) {
      const CellAnchor anchor{
          Vec3(rng.next_float() * 20 - 10, rng.next_float() * 4, rng.next_float() * 20 - 10),
          Vec3(0, 1, 0), -4};
      a->set_anchor(c, anchor);
      b->set_anchor(c, anchor);
    }
  }
  void record(Pcg32& rng, int pass) {
    for (uint32_t c = 0; c < kCells; ++c) {
      if (c % 7 == 3 && pass % 2 == 1) continue;  // some cells see nothing in some passes
      const uint32_t K = a->active(c) ? a->size(c) : a->initial_size();
      for (int i = 0; i < 30; ++i) {
        const uint32_t k = rng.next_bounded(K);
        const float r = (k + pass / 5) % 4 == 0
                            ? 10 * rng.next_float()
                            : (rng.next_float() < 0.6f ? 0.0f : rng.next_float());
        a->record(c, k, r);
        b->record(c, k, r);
      }
    }
  }
};

void expect_equal_cells(const CutStore& a, const CutStore& b, bool guided) {
  for (uint32_t c = 0; c < kCells; ++c) {
    ASSERT_EQ(a.size(c), b.size(c)) << "cell " << c;
    const uint32_t K = a.size(c);
    for (uint32_t k = 0; k < K; ++k) {
      EXPECT_EQ(a.nodes(c)[k], b.nodes(c)[k]) << "cell " << c << " cluster " << k;
      EXPECT_EQ(a.ends(c)[k], b.ends(c)[k]);
      EXPECT_EQ(a.q(c)[k], b.q(c)[k]);
      EXPECT_EQ(a.m2(c)[k], b.m2(c)[k]);
      EXPECT_EQ(a.cdf(c)[k], b.cdf(c)[k]);
      if (guided && k + 1 < K) {
        EXPECT_EQ(a.guide_left(c)[k], b.guide_left(c)[k]);
        EXPECT_EQ(a.guide_right(c)[k], b.guide_right(c)[k]);
      }
    }
    EXPECT_EQ(a.defensive_weight(c), b.defensive_weight(c));
    EXPECT_EQ(a.learnt(c), b.learnt(c));
  }
}

}  // namespace

// The parallel loop over cells (RllLightSampler::end_pass's) and the class's end_pass cell by
// cell, in the opposite order, leave every array equal to the bit: cells are independent.
TEST(CutEndPass, ParallelLoopOverCellsEqualsTheClassCellByCell) {
  Scene scene = test::small_builtin_scene("many-lights-open", 16, 12);
  const LightTree tree = build_light_tree(scene);
  for (const Variant& v : variants()) {
    SCOPED_TRACE(v.name);
    Twins t(tree, v.s);
    Pcg32 rng(11);
    uint64_t splits = 0;
    for (int pass = 0; pass < 40; ++pass) {
      t.record(rng, pass);
      std::vector<CutPassStats> by_class(kCells), by_loop(kCells);
      for (uint32_t c = kCells; c-- > 0;) by_class[c] = t.a->end_pass(c);
      const CutStoreEndView ev = t.b->end_view();
      // Each cell's scratch its own slice of one arena, at a scan of the cells' rooms.
      std::vector<uint64_t> at(kCells + 1, 0);
      for (uint32_t c = 0; c < kCells; ++c) at[c + 1] = at[c] + cut_scratch_room(ev, c);
      std::vector<double> d(at[kCells] * CutScratchArena::kDoubles);
      std::vector<float> f(at[kCells] * CutScratchArena::kFloats);
      const CutScratchArena arena{view_of(d), view_of(f)};
      host_parallel_for(kCells, [&](size_t c) {
        by_loop[c] = cut_end_pass(ev, uint32_t(c), arena.slice(at[c], uint32_t(at[c + 1] - at[c])));
      });
      for (uint32_t c = 0; c < kCells; ++c) {
        EXPECT_EQ(by_class[c].splits, by_loop[c].splits);
        EXPECT_EQ(by_class[c].collapses, by_loop[c].collapses);
        EXPECT_EQ(by_class[c].touched, by_loop[c].touched);
        splits += by_class[c].splits;
      }
      expect_equal_cells(*t.a, *t.b, v.s.guided);
    }
    if (v.s.splits > 0) {
      EXPECT_GT(splits, 100u);  // the test exercises split-collapse
    }
  }
}

// The guided factors baked without a stack (cut_bake_guide) equal those of the recursion
// they replace: each inner node's children's prior-weighted mean of g, sums added child by child.
TEST(CutEndPass, GuidedFactorsEqualARecursiveBake) {
  Scene scene = test::small_builtin_scene("many-lights-open", 16, 12);
  const LightTree tree = build_light_tree(scene);
  CutSettings s;
  s.cut_size = s.initial_size = 64;
  s.guided = true;
  Twins t(tree, s);
  Pcg32 rng(5);
  for (int pass = 0; pass < 6; ++pass) {
    t.record(rng, pass);
    for (uint32_t c = 0; c < kCells; ++c) t.a->end_pass(c);
  }
  const CutStoreEndView ev = t.a->end_view();
  int checked = 0;
  for (uint32_t c = 0; c < kCells; ++c) {
    const uint32_t K = t.a->size(c);
    ASSERT_GT(K, 1u);
    std::vector<double> pri(K), g(K);
    std::vector<float> val(K);
    cut_cell_prior(ev, c, pri.data(), HostCutScratch(K));
    cut_values(ev, c, K, pri.data(), val.data());
    const double eps = t.a->learnt(c) ? t.a->defensive_weight(c) : 1.0;
    guide_factors(K, pri.data(), val.data(), eps, g.data());
    std::vector<float> gl(K - 1, -1), gr(K - 1, -1);
    auto visit = [&](auto&& self, uint32_t node, uint32_t k0, uint32_t k1) -> detail::GuideSums {
      if (k1 - k0 == 1) return {pri[k0], pri[k0] * g[k0], g[k0], 1};
      const LightTreeNode& nd = tree.node(node);
      const uint32_t j = children_boundary(tree, nd, t.a->ends(c), k0, k1);
      const detail::GuideSums a = self(self, nd.child, k0, j + 1),
                              b = self(self, nd.child + 1, j + 1, k1);
      gl[j] = float(a.factor());
      gr[j] = float(b.factor());
      return {a.w + b.w, a.wg + b.wg, a.g + b.g, a.count + b.count};
    };
    visit(visit, LightTree::kRoot, 0u, K);
    for (uint32_t j = 0; j + 1 < K; ++j) {
      EXPECT_EQ(t.a->guide_left(c)[j], gl[j]) << "cell " << c << " boundary " << j;
      EXPECT_EQ(t.a->guide_right(c)[j], gr[j]) << "cell " << c << " boundary " << j;
      checked += gl[j] != 1.0f || gr[j] != 1.0f;
    }
  }
  EXPECT_GT(checked, 100);  // learnt factors, not the tree's own step everywhere
}

TEST(RllPool, FindIsABinarySearchOverTheSortedKeys) {
  Pcg32 rng(3);
  std::vector<uint64_t> keys;
  for (int i = 0; i < 500; ++i) keys.push_back(uint64_t(rng.next_bounded(100000)) * 3 + 1);
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  RllPoolView p;
  p.keys = view_of(std::as_const(keys));
  for (uint64_t key = 0; key < 300010; ++key) {
    const auto it = std::lower_bound(keys.begin(), keys.end(), key);
    const long want = it != keys.end() && *it == key ? long(it - keys.begin()) : -1;
    ASSERT_EQ(pool_find(p, key), want) << key;
  }
  EXPECT_EQ(pool_find(RllPoolView{}, 5), -1);
}

// pool_fold over a coarse cell's entries (its cells in key order) equals sums gathered in a map
// per coarse cell in the order of the cells' keys, folded by the shrinkage rule without a prior,
// from the coarse cell's previous values where it had some.
TEST(RllPool, FoldEqualsSumsInTheOrderOfTheCellsKeys) {
  Scene scene = test::small_builtin_scene("many-lights-open", 16, 12);
  const LightTree tree = build_light_tree(scene);
  CutSettings s;
  s.cut_size = s.initial_size = 16;
  s.pool_levels = 1;
  s.pool_ratio = true;
  CutStore store(tree, kCells, s, 2.0);
  Pcg32 rng(9);
  std::vector<PoolEntry> entries;
  for (uint32_t c = 0; c < kCells; ++c) {
    store.set_anchor(
        c, {Vec3(rng.next_float() * 20 - 10, 1, rng.next_float() * 20 - 10), Vec3(0, 1, 0), -4});
    for (int i = 0; i < 50; ++i)
      store.record(c, rng.next_bounded(16), rng.next_float() < 0.5f ? 0.0f : 5 * rng.next_float());
    entries.push_back({uint64_t(rng.next_bounded(5)) * 10, uint64_t(rng.next_u32()) << 8 | c, c});
  }
  const size_t K = 16;
  // The reference: a map of sums per coarse key, cells added in the order of their keys.
  std::map<uint64_t, std::map<uint64_t, uint32_t>> by_coarse;
  for (const PoolEntry& e : entries) by_coarse[e.coarse][e.cell_key] = e.cell;
  // The previous pass knew coarse cell 20 only.
  std::vector<uint64_t> old_keys{20};
  std::vector<float> old_q(K), old_m2(K), old_n(K);
  for (size_t k = 0; k < K; ++k) {
    old_q[k] = k % 3 == 0 ? -1.0f : 0.5f + float(k);
    old_m2[k] = old_q[k] < 0 ? 0.0f : old_q[k] * old_q[k] * 1.5f;
    old_n[k] = old_q[k] < 0 ? 0.0f : 30.0f + float(k);
  }
  const RllPoolView old{uint32_t(K), view_of(std::as_const(old_keys)), view_of(old_q),
                        view_of(old_m2), view_of(old_n)};
  std::sort(entries.begin(), entries.end(), [](const PoolEntry& a, const PoolEntry& b) {
    return a.coarse != b.coarse ? a.coarse < b.coarse : a.cell_key < b.cell_key;
  });
  std::vector<uint64_t> keys;
  for (const auto& [key, cells] : by_coarse) keys.push_back(key);
  std::vector<float> q(keys.size() * K), m2(keys.size() * K), n(keys.size() * K);
  const RllPoolView next{uint32_t(K), view_of(std::as_const(keys)), view_of(q), view_of(m2),
                         view_of(n)};
  const CutStoreEndView ev = store.end_view();
  size_t first = 0;
  for (size_t j = 0; j < keys.size(); ++j) {
    size_t count = 0;
    while (first + count < entries.size() && entries[first + count].coarse == keys[j]) ++count;
    std::vector<double> sum(K), sq(K);
    std::vector<uint64_t> rewards(K);
    pool_fold(ev, &entries[first], count, old, next, j, sum.data(), sq.data(), rewards.data(),
              HostCutScratch(uint32_t(K)));
    first += count;
    // The reference.
    std::vector<double> rsum(K, 0.0), rsq(K, 0.0);
    std::vector<uint64_t> rcount(K, 0);
    for (const auto& [cell_key, cell] : by_coarse[keys[j]])
      store.add_pass_rewards(cell, rsum.data(), rsq.data(), rcount.data());
    const bool had = keys[j] == 20;
    for (size_t k = 0; k < K; ++k) {
      float rq = had ? old_q[k] : -1.0f, rm2 = had ? old_m2[k] : 0.0f, rn = had ? old_n[k] : 0.0f;
      if (rcount[k] > 0) {
        const double nk = double(rcount[k]);
        shrinkage_update(s, rq, rm2, rn, rq >= 0 ? double(rn) : 0.0, rq >= 0, std::max(rq, 0.0f),
                         rm2, nk, RewardMoments(nk, rsum[k], rsq[k]));
      }
      EXPECT_EQ(q[j * K + k], rq) << "coarse " << keys[j] << " cluster " << k;
      EXPECT_EQ(m2[j * K + k], rm2);
      EXPECT_EQ(n[j * K + k], rn);
      EXPECT_EQ(rewards[k], rcount[k]);
      EXPECT_EQ(sum[k], rsum[k]);  // the same additions in the same order
      EXPECT_EQ(sq[k], rsq[k]);
    }
  }
  EXPECT_EQ(first, entries.size());
  EXPECT_GE(keys.size(), 4u);
}

namespace {
// A one-cell store of 4 clusters on many-lights-open's tree, with `forget`.
struct OneCell {
  Scene scene = test::small_builtin_scene("many-lights-open", 16, 12);
  LightTree tree = build_light_tree(scene);
  std::unique_ptr<CutStore> store;
  explicit OneCell(Forgetting forget, float change_z = 5) {
    CutSettings s;
    s.cut_size = s.initial_size = 4;
    s.forget = forget;
    s.change_z = change_z;
    store = std::make_unique<CutStore>(tree, 1, s, 1.0);
    store->set_anchor(0, {Vec3(0, 1, 0), Vec3(0, 1, 0), -4});
  }
  // One pass: 100 rewards of cluster 0 from `reward(i)`, 100 of 1 each, the others none.
  template <typename F>
  CutPassStats pass(F reward) {
    for (int i = 0; i < 100; ++i) {
      store->record(0, 0, reward(i));
      store->record(0, 1, 1.0f);
    }
    return store->end_pass(0);
  }
};
}  // namespace

// forget=changes (DESIGN 2b.3): a cluster whose rewards do not change keeps every one of them
// (the rate stays 1/n), where forget=floor keeps the last 1/alpha = 50; a lamp that switches off
// fails the change test and its cluster falls back to the last 50 rewards at once, the others
// keeping theirs; a rare bright reward among zeros is no change; the lights changing cuts every
// cluster back (cut_forget).
TEST(RllForgetting, StaticClustersKeepEveryRewardAndChangesForget) {
  Pcg32 rng(3);
  auto noisy = [&](int) { return 2 * rng.next_float(); };
  OneCell changes(Forgetting::Changes), floor(Forgetting::Floor);
  uint32_t found = 0;
  for (int p = 0; p < 20; ++p) {
    found += changes.pass(noisy).changes;
    floor.pass(noisy);
  }
  EXPECT_EQ(found, 0u) << "noise alone failed the change test";
  // Cluster 0's prior estimate counts as prior_samples = 4 rewards.
  EXPECT_EQ(changes.store->memory(0)[0], 2004.0f);
  EXPECT_EQ(changes.store->memory(0)[1], 2004.0f);
  EXPECT_EQ(floor.store->memory(0)[0], 50.0f);
  EXPECT_NEAR(changes.store->q(0)[0], 1.0f, 0.05f);
  // The lamp of cluster 0 switches off.
  const CutPassStats off = changes.pass([](int) { return 0.0f; });
  EXPECT_EQ(off.changes, 1u);
  EXPECT_EQ(changes.store->memory(0)[0], 150.0f);  // the last 50 of before, and the 100 zeros
  EXPECT_EQ(changes.store->memory(0)[1], 2104.0f);
  EXPECT_LT(changes.store->q(0)[0], 0.4f);
  // A lamp seen through a gap: one reward in 200 is bright, the others zero.
  OneCell gap(Forgetting::Changes);
  found = 0;
  for (int p = 0; p < 40; ++p)
    found += gap.pass([&](int) { return rng.next_float() < 0.005f ? 100.0f : 0.0f; }).changes;
  EXPECT_EQ(found, 0u) << "rare bright rewards failed the change test";
  EXPECT_GT(gap.store->memory(0)[0], 3000.0f);
  // change_z = 0: no test, only the lights changing forgets.
  OneCell untested(Forgetting::Changes, 0);
  for (int p = 0; p < 5; ++p) untested.pass(noisy);
  EXPECT_EQ(untested.pass([](int) { return 0.0f; }).changes, 0u);
  EXPECT_EQ(untested.store->memory(0)[0], 604.0f);
  // The lights change: every cluster back to at most 50 rewards; a floor store is untouched.
  const CutStoreEndView v = changes.store->end_view();
  cut_forget(v, 0);
  for (uint32_t k = 0; k < 4; ++k) EXPECT_LE(changes.store->memory(0)[k], 50.0f);
  EXPECT_EQ(changes.store->memory(0)[1], 50.0f);
  cut_forget(floor.store->end_view(), 0);
  EXPECT_EQ(floor.store->memory(0)[0], 50.0f);
}
