// A descent of the light tree split at a cut (DescentSplit, lighttree/descent.h), which replaced
// the record of its whole path (2 KB of every GPU thread's stack): the cluster it reports is the
// light's, and its two products equal to the bit what tree_reach_pmf and tree_descend_pmf compute
// for that cluster's node, as the earlier record's products did; on the built-in scenes' trees
// and on one deeper than the samplers' kMaxTreeDepth (a bit trail of one 64-bit word would hold
// 64 levels; the builders' trees stay within 2 + 160 + 32).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "rll/core/rng.h"
#include "rll/learn/cut.h"
#include "rll/lighttree/descent.h"
#include "support/test_support.h"

using namespace rll;

namespace {

// Each cut's descents from the root at random points, checked against the products the pmfs of
// rll and ltc form without a descent. Adds to *below the descents that went on below their
// cluster's node.
void expect_split_descents_agree(const LightTree& tree, const std::vector<uint32_t>& cut,
                                 const Bounds3& box, int count, uint64_t seed, int* below) {
  std::vector<uint32_t> ends;
  for (uint32_t node : cut) ends.push_back(tree.node(node).end);
  const LightTreeView v = tree.view();
  Pcg32 rng(seed);
  for (int i = 0; i < count; ++i) {
    const Vec3 r(rng.next_float(), rng.next_float(), rng.next_float());
    const Vec3 p = box.lo + (box.hi - box.lo) * r;
    Vec3 n(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() - 0.5f);
    n = length_sq(n) > 1e-6f ? normalize(n) : Vec3(0, 1, 0);
    const double u = rng.next_float();
    DescentSplit split;
    split.ends = ends.data();
    split.nodes = cut.data();
    split.size = uint32_t(cut.size());
    const TreeSample t = tree_descend(v, LightTree::kRoot, p, n, u, &split);
    const TreeSample plain = tree_descend(v, LightTree::kRoot, p, n, u);
    ASSERT_EQ(t.light, plain.light);
    ASSERT_EQ(t.pmf, plain.pmf);
    if (!(t.pmf > 0)) continue;
    EXPECT_EQ(t.pmf, tree_descend_pmf(v, LightTree::kRoot, t.light, p, n));
    const uint32_t k = uint32_t(std::upper_bound(ends.begin(), ends.end(), t.light) - ends.begin());
    ASSERT_EQ(split.cluster, k) << "descent " << i;
    EXPECT_EQ(split.reach, tree_reach_pmf(v, cut[k], p, n)) << "descent " << i;
    EXPECT_EQ(split.below, tree_descend_pmf(v, cut[k], t.light, p, n)) << "descent " << i;
    *below += tree.node(cut[k]).light_count() > 1;
  }
}

}  // namespace

TEST(DescentSplit, ProductsEqualTheReachAndTheDescentBelowTheCluster) {
  for (const char* name : {"cornell-boxes-room", "arch-interior", "many-lights-open"}) {
    SCOPED_TRACE(name);
    Scene scene = test::small_builtin_scene(name, 16, 12);
    const LightTree tree = build_light_tree(scene);
    const Bounds3 box = scene.bounds;
    // The root alone, a small and a large initial cut, and every leaf.
    int below = 0;
    for (int size : {1, 8, 64})
      expect_split_descents_agree(tree, initial_cut(tree, size), box, 300, size, &below);
    std::vector<uint32_t> leaves;
    for (uint32_t l = 0; l < tree.light_count(); ++l) leaves.push_back(tree.leaf_of(l));
    expect_split_descents_agree(tree, leaves, box, 100, 7, &below);
    EXPECT_GT(below, 300);  // clusters of many lights: the split is inside the path
  }
}

// A caterpillar over n lights, deeper than any builder makes: inner node k (index 2k) has the
// leaf of light k (2k + 1) and the next inner node (2k + 2) as children, the last inner node two
// leaves. Each node's importance bounds are those of a real light's leaf (`from`'s, in turn), an
// inner node's with 1000 times the power, so that descents go deep (each step continues with
// probability about 0.999).
struct Caterpillar {
  std::vector<LightTreeNode> nodes;
  std::vector<ImportanceBounds> importance;
  std::vector<TreeStep> steps;
  std::vector<uint32_t> leaf_of;
  Caterpillar(uint32_t n, const LightTree& from) : nodes(2 * n - 1), importance(2 * n - 1) {
    for (uint32_t k = 0; k + 1 < n; ++k) {
      LightTreeNode& inner = nodes[2 * k];
      inner.begin = k;
      inner.end = n;
      inner.child = 2 * k + 1;
      nodes[2 * k + 1].begin = k;
      nodes[2 * k + 1].end = k + 1;
      nodes[2 * k + 1].parent = nodes[2 * k + 2].parent = 2 * k;
      leaf_of.push_back(2 * k + 1);
    }
    nodes[2 * n - 2].begin = n - 1;
    nodes[2 * n - 2].end = n;
    leaf_of.push_back(2 * n - 2);
    for (uint32_t i = 0; i < 2 * n - 1; ++i) {
      const uint32_t light = i % uint32_t(from.light_count());
      const bool inner = i % 2 == 0 && i != 2 * n - 2;
      importance[i] = from.view().bounds(from.leaf_of(light));
      if (inner) importance[i].power *= 1000;
      nodes[i].bounds.power = importance[i].power;
    }
    steps.resize(n);
    tree_steps(view_of(nodes), view_of(importance), view_of(steps));
  }
  LightTreeView view() const { return {view_of(nodes), view_of(steps), view_of(leaf_of)}; }
};

TEST(DescentSplit, PathsDeeperThan64LevelsKeepTheirProducts) {
  Scene scene = test::small_builtin_scene("many-lights-open", 16, 12);
  const uint32_t n = 300;  // paths up to 299 steps, past kMaxTreeDepth (256)
  const Caterpillar tree(n, build_light_tree(scene));
  const LightTreeView v = tree.view();
  // A cut of the first m leaves and the inner node m above the rest, m = 100: the clusters of
  // the first lights are reached after k + 1 steps, the last one after 100, with up to 199
  // below it.
  const uint32_t m = 100;
  std::vector<uint32_t> cut, ends;
  for (uint32_t k = 0; k < m; ++k) cut.push_back(2 * k + 1);
  cut.push_back(2 * m);
  for (uint32_t node : cut) ends.push_back(tree.nodes[node].end);
  Pcg32 rng(11);
  int deep = 0, below = 0;
  for (int i = 0; i < 2000; ++i) {
    const Vec3 r(rng.next_float(), rng.next_float(), rng.next_float());
    const Vec3 p = scene.bounds.lo + (scene.bounds.hi - scene.bounds.lo) * r;
    const Vec3 nrm = normalize(Vec3(r.y - 0.5f, 1, r.x - 0.5f));
    const double u = rng.next_float();
    DescentSplit split;
    split.ends = ends.data();
    split.nodes = cut.data();
    split.size = uint32_t(cut.size());
    const TreeSample t = tree_descend(v, LightTree::kRoot, p, nrm, u, &split);
    if (!(t.pmf > 0)) continue;
    ASSERT_EQ(t.pmf, tree_descend_pmf(v, LightTree::kRoot, t.light, p, nrm)) << "light " << t.light;
    const uint32_t k = std::min(t.light, m);
    ASSERT_EQ(split.cluster, k) << "light " << t.light;
    EXPECT_EQ(split.reach, tree_reach_pmf(v, cut[k], p, nrm)) << "light " << t.light;
    EXPECT_EQ(split.below, tree_descend_pmf(v, cut[k], t.light, p, nrm)) << "light " << t.light;
    deep += t.light >= 64;
    below += t.light > m + 64;
  }
  EXPECT_GT(deep, 50);   // paths longer than a 64-bit trail holds
  EXPECT_GT(below, 10);  // and more than 64 steps below the cluster
  // Every light's pmf from the root is a product over its whole path: they sum to one.
  const Vec3 p = 0.5f * (scene.bounds.lo + scene.bounds.hi), nrm(0, 1, 0);
  double sum = 0;
  for (uint32_t l = 0; l < n; ++l) sum += tree_descend_pmf(v, LightTree::kRoot, l, p, nrm);
  EXPECT_NEAR(sum, 1.0, 1e-4);
}
