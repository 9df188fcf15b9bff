// Split-collapse and the per-cell cut store keep their invariants whatever the rewards: every
// cut partitions all lights into contiguous ranges in order, K <= M, stored range ends match
// the nodes, and the CDF rises to exactly one.
#include <gtest/gtest.h>

#include "rll/core/rng.h"
#include "rll/learn/cuts.h"
#include "rll/scene/builtin.h"

using namespace rll;

namespace {

Scene many_lights() {
  Scene s = make_builtin_scene("many-lights-open");
  s.width = 16;
  s.height = 12;
  s.finalize();
  return s;
}

void expect_cell_invariants(const LightTree& tree, const CutStore& store, uint32_t cell, int max_size) {
  ASSERT_TRUE(store.active(cell));
  const uint32_t K = store.size(cell);
  ASSERT_GE(K, 1u);
  ASSERT_LE(int(K), max_size);
  std::vector<uint32_t> nodes(store.nodes(cell), store.nodes(cell) + K);
  ASSERT_TRUE(is_valid_cut(tree, nodes));
  float prev = 0;
  for (uint32_t k = 0; k < K; ++k) {
    EXPECT_EQ(store.ends(cell)[k], tree.node(nodes[k]).end) << "cluster " << k;
    EXPECT_GE(store.cdf(cell)[k], prev) << "cluster " << k;
    prev = store.cdf(cell)[k];
  }
  EXPECT_EQ(store.cdf(cell)[K - 1], 1.0f);
}

}  // namespace

TEST(InitialCut, PartitionsAllLightsWithMNodes) {
  Scene s = many_lights();
  const LightTree& tree = *s.light_tree;
  for (int m : {1, 2, 7, 64, 128, 1000}) {
    auto cut = initial_cut(tree, m);
    EXPECT_TRUE(is_valid_cut(tree, cut)) << "M = " << m;
    EXPECT_EQ(int(cut.size()), std::min<int>(m, int(tree.light_count()))) << "M = " << m;
  }
}

TEST(SplitCollapse, InvariantsAfterManyRandomPasses) {
  Scene s = many_lights();
  const LightTree& tree = *s.light_tree;
  CutSettings cs;
  cs.cut_size = 24;  // small, so that collapses happen constantly
  cs.splits = 6;
  cs.threshold = 1.1f;
  const uint32_t cells = 16;
  CutStore store(tree, cells, cs, 1.0);
  Pcg32 rng(2024);
  for (uint32_t c = 0; c < cells; ++c)
    store.set_anchor(c, {Vec3(rng.next_float() * 20 - 10, 0, rng.next_float() * 20 - 10), Vec3(0, 1, 0), -4});
  uint64_t splits = 0, collapses = 0;
  for (int pass = 0; pass < 300; ++pass) {
    for (uint32_t c = 0; c < cells; ++c) {
      const uint32_t K = store.active(c) ? store.size(c) : store.initial_size();
      // Rewards concentrated on a few clusters that change over time, zeros included.
      for (int i = 0; i < 40; ++i) {
        uint32_t k = rng.next_bounded(K);
        float r = (k + pass / 50) % 5 == 0 ? 10 * rng.next_float() : (rng.next_float() < 0.7f ? 0.0f : rng.next_float());
        store.record(c, k, r, r);
      }
      CutStore::PassStats st = store.end_pass(c);
      splits += st.splits;
      collapses += st.collapses;
      expect_cell_invariants(tree, store, c, cs.cut_size);
    }
  }
  // The test must exercise both operations a lot.
  EXPECT_GT(splits, 500u);
  EXPECT_GT(collapses, 200u);
}

TEST(SplitCollapse, SplitsTheLargestAndCollapsesTheSmallest) {
  Scene s = many_lights();
  const LightTree& tree = *s.light_tree;
  Cut cut;
  cut.nodes = initial_cut(tree, 8);
  const size_t K = cut.nodes.size();
  cut.q.assign(K, 1.0f);
  cut.weight.assign(K, 1.0f);
  cut.n.assign(K, 1.0f);
  // Find a sibling pair to be the smallest, and a splittable cluster elsewhere to be the largest.
  size_t pair = K, big = K;
  for (size_t k = 0; k + 1 < K && pair == K; ++k)
    if (tree.node(cut.nodes[k]).parent == tree.node(cut.nodes[k + 1]).parent) pair = k;
  ASSERT_LT(pair, K);
  for (size_t k = 0; k < K && big == K; ++k)
    if (k != pair && k != pair + 1 && !tree.node(cut.nodes[k]).is_leaf()) big = k;
  ASSERT_LT(big, K);
  cut.q[pair] = cut.q[pair + 1] = 0.01f;
  cut.q[big] = 100;
  const uint32_t parent = tree.node(cut.nodes[pair]).parent, split = cut.nodes[big];
  std::vector<float> qe = cut.q;
  SplitCollapse sc(tree, int(K), 2.0f);
  EXPECT_EQ(sc.step(cut, qe, [](uint32_t) { return 1.0f; }, [](uint32_t) { return 1.0f; }), 1);
  EXPECT_TRUE(is_valid_cut(tree, cut.nodes));
  EXPECT_EQ(cut.nodes.size(), K);
  EXPECT_NE(std::find(cut.nodes.begin(), cut.nodes.end(), parent), cut.nodes.end());
  EXPECT_EQ(std::find(cut.nodes.begin(), cut.nodes.end(), split), cut.nodes.end());
  EXPECT_NE(std::find(cut.nodes.begin(), cut.nodes.end(), tree.node(split).child), cut.nodes.end());
  // Below the threshold nothing changes: 1 > 2 * (0.5 + 0.5) is false.
  Cut flat;
  flat.nodes = initial_cut(tree, 8);
  flat.q.assign(flat.nodes.size(), 1.0f);
  flat.weight.assign(flat.nodes.size(), 1.0f);
  flat.n.assign(flat.nodes.size(), 1.0f);
  std::vector<float> qf = flat.q;
  EXPECT_EQ(sc.step(flat, qf, [](uint32_t) { return 1.0f; }, [](uint32_t) { return 1.0f; }), 0);
}
