// Descents of the light tree: one stochastic walk from a node to a light, each child chosen in
// proportion to its importance at the shading point (above the group roots, by the groups that
// can contribute there), and the exact probabilities of such walks. The `tree` sampler is one
// descent from the root; rll and ltc descend below their clusters and mix in whole-tree descents.
#pragma once

#include <cstdint>

#include "rll/lighttree/light_tree.h"

namespace rll {

// A light chosen by a descent and the probability of choosing it (0: nothing was chosen).
struct TreeSample {
  uint32_t light = 0;
  float pmf = 0;
};

// The nodes a descent went through and the probability of each step, so that callers can
// form the probability of any part of the path without evaluating importances again. The
// products are formed top-down from 1, exactly as tree_descend_pmf and tree_reach_pmf do, so
// they agree with them to the bit.
struct DescentPath {
  uint32_t node[kMaxTreeDepth];
  float step[kMaxTreeDepth];  // step[i]: probability of going from node[i-1] to node[i]
  int length = 0;             // node[0] is the start (step[0] = 1), node[length-1] the leaf
  int index_of(uint32_t n) const {
    for (int i = 0; i < length; ++i)
      if (node[i] == n) return i;
    return -1;
  }
  // Product of the steps after index `a` up to and including `b`.
  float product(int a, int b) const {
    float p = 1;
    for (int i = a + 1; i <= b; ++i) p *= step[i];
    return p;
  }
};

// Descends the subtree under `from`, returning a light under it and the probability of that
// choice given that the descent starts at `from`. A child with zero importance is never chosen
// over a sibling with positive importance, and one with positive importance always keeps a
// positive probability; the pmfs of the lights under `from` sum to one.
TreeSample tree_descend(const LightTree& tree, uint32_t from, const Vec3& p, const Vec3& n,
                        double u, DescentPath* path = nullptr);
// The probability that tree_descend(tree, from, p, n, .) returns `light`: the same products in
// the same order, so the two agree exactly. 0 if `light` is not under `from`.
float tree_descend_pmf(const LightTree& tree, uint32_t from, uint32_t light, const Vec3& p,
                       const Vec3& n);

// The probability that a descent at inner node `node` goes to its first child, each child's
// share (by importance, or by contributing groups at a group node) scaled by a positive factor
// g0, g1 (1, 1: the light tree's own step, as tree_descend takes it). The children's importances
// are written to importance0/1 where computed (not at group nodes).
float first_child_probability(const LightTree& tree, const LightTreeNode& node, const Vec3& p,
                              const Vec3& n, float g0, float g1, float* importance0,
                              float* importance1);

// The probability that a descent from the root passes through `node` (1 for the root).
float tree_reach_pmf(const LightTree& tree, uint32_t node, const Vec3& p, const Vec3& n);

}  // namespace rll
