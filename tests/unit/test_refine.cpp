// rll.refine's disagreement test (learn/cut_end_pass.h, cut_refine_gain and cut_refine_test): a
// cell whose two halves see different lights is marked refined, one whose halves see the same
// lights is not, whatever the noise of the rewards; and the test needs refine_min rewards and a
// level above the finest.
#include <gtest/gtest.h>

#include "rll/core/rng.h"
#include "rll/learn/cut_end_pass.h"
#include "rll/learn/cut_store.h"
#include "rll/scene/builtin.h"
#include "support/test_support.h"

using namespace rll;

namespace {

struct Store {
  Scene scene = test::small_builtin_scene("many-lights-open", 16, 12);
  LightTree tree = build_light_tree(scene);
  CutStore store;
  explicit Store(int refine_min = 64) : store(tree, 2, settings(refine_min), 1.0) {
    for (uint32_t c = 0; c < 2; ++c) store.set_anchor(c, {Vec3(0), Vec3(0, 1, 0), -4});
  }
  static CutSettings settings(int refine_min) {
    CutSettings cs;
    cs.cut_size = cs.initial_size = 8;
    cs.refine = 1;
    cs.refine_gain = 0.5f;
    cs.refine_min = refine_min;
    return cs;
  }
  // `n` rewards in `cell`, a point in either half alike, its cluster uniform among the first 4.
  // Lit by cluster 0 in the upper half and cluster 1 in the lower (`disagree`), or by both
  // everywhere; each reward noisy (exponential, mean 1).
  void record(uint32_t cell, int n, bool disagree, uint64_t seed) {
    Pcg32 rng(seed);
    const CutStoreView v = store.view();
    for (int i = 0; i < n; ++i) {
      const bool upper = rng.next_float() < 0.5f;
      const uint32_t k = std::min(3u, uint32_t(rng.next_float() * 4));
      const bool lit = disagree ? (upper ? k == 0 : k == 1) : k <= 1;
      const float r = lit ? -std::log(1 - rng.next_float()) : 0.0f;
      cut_record(v, cell, k, r, upper);
    }
  }
};

}  // namespace

TEST(Refine, MarksACellWhoseHalvesSeeDifferentLightsAndNotOneWhoseHalvesAgree) {
  Store s;
  for (uint64_t seed = 1; seed <= 20; ++seed) {
    s.store.clear(0);
    s.store.clear(1);
    s.record(0, 400, true, seed);
    s.record(1, 400, false, seed + 100);
    const CutStoreEndView v = s.store.end_view();
    // Each half wants its own light alone: one distribution for both costs twice as much (gain
    // 1, less noise); where the halves agree, the gain is the noise's.
    const double differ = cut_refine_gain(v, 0), same = cut_refine_gain(v, 1);
    EXPECT_GT(differ, 0.7) << "seed " << seed;
    EXPECT_LT(same, 0.15) << "seed " << seed;
    EXPECT_TRUE(cut_refine_test(v, 0));
    EXPECT_FALSE(cut_refine_test(v, 1));
    EXPECT_TRUE(s.store.refined(0));
    EXPECT_FALSE(s.store.refined(1));
    // The upper halves' sums start again; a refined cell is not marked twice.
    EXPECT_FALSE(cut_refine_test(v, 0));
    EXPECT_EQ(cut_refine_gain(v, 0), 0.0);
  }
}

TEST(Refine, NeedsRefineMinRewardsAndALevelAboveTheFinest) {
  Store s(/*refine_min=*/1000);
  s.record(0, 400, true, 1);
  EXPECT_FALSE(cut_refine_test(s.store.end_view(), 0)) << "400 rewards, refine_min 1000";
  Store t;
  t.store.set_anchor(0, {Vec3(0), Vec3(0, 1, 0), CellKeyer::kFinestLevel});
  t.record(0, 400, true, 1);
  EXPECT_GT(cut_refine_gain(t.store.end_view(), 0), 0.7);
  EXPECT_FALSE(cut_refine_test(t.store.end_view(), 0)) << "a cell at the finest level";
  // Eviction forgets the flag.
  t.store.set_anchor(1, {Vec3(0), Vec3(0, 1, 0), -4});
  t.record(1, 400, true, 2);
  EXPECT_TRUE(cut_refine_test(t.store.end_view(), 1));
  t.store.clear(1);
  EXPECT_FALSE(t.store.refined(1));
}

TEST(Refine, TheGainDoesNotDependOnTheOrderOfTheRewards) {
  // Exact sums: the same rewards delivered in another order give the same gain to the bit.
  Store a, b;
  Pcg32 rng(5);
  std::vector<std::tuple<uint32_t, float, bool>> rewards;
  for (int i = 0; i < 500; ++i)
    rewards.emplace_back(std::min(3u, uint32_t(rng.next_float() * 4)), rng.next_float() * 1e3f,
                         rng.next_float() < 0.3f);
  for (const auto& [k, r, up] : rewards) cut_record(a.store.view(), 0, k, r, up);
  for (auto it = rewards.rbegin(); it != rewards.rend(); ++it)
    cut_record(b.store.view(), 0, std::get<0>(*it), std::get<1>(*it), std::get<2>(*it));
  EXPECT_EQ(cut_refine_gain(a.store.end_view(), 0), cut_refine_gain(b.store.end_view(), 0));
}

TEST(Refine, ANewChildStartsFromItsRefinedParentsValues) {
  // cut_seed_child: a child in its first pass (no cut) of a refined parent with the shared
  // initial cut takes the parent's values, each weighing at most pool_weight rewards, and its
  // table is baked by the end of pass even without a reward of its own; of a parent not
  // refined, nothing.
  Store s;
  s.record(0, 400, true, 3);
  const CutStoreEndView v = s.store.end_view();
  ASSERT_TRUE(cut_refine_test(v, 0));
  s.store.end_pass(0);
  ASSERT_TRUE(s.store.active(0) && s.store.learnt(0));
  cut_seed_child(v, 1, 0);
  ASSERT_TRUE(s.store.active(1));
  s.store.end_pass(1);  // no reward: the bake alone
  const uint32_t K = s.store.size(1);
  for (uint32_t k = 0; k < K; ++k) {
    EXPECT_EQ(s.store.q(1)[k], s.store.q(0)[k]);
    EXPECT_LE(s.store.memory(1)[k], s.store.settings().pool_weight);
  }
  EXPECT_EQ(s.store.cdf(1)[K - 1], 1.0f);
  EXPECT_EQ(s.store.learnt_shares(1), s.store.learnt_shares(0));
  Store t;
  t.record(0, 400, false, 3);
  ASSERT_FALSE(cut_refine_test(t.store.end_view(), 0));
  t.store.end_pass(0);
  cut_seed_child(t.store.end_view(), 1, 0);
  EXPECT_FALSE(t.store.active(1));
}
