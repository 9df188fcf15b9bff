// Descents of the light tree: one stochastic walk from a node to a light, each child chosen in
// proportion to its importance at the shading point (above the group roots, by the groups that
// can contribute there), and the exact probabilities of such walks. The `tree` sampler is one
// descent from the root; rll and ltc descend below their clusters and mix in whole-tree descents.
// RLL_HD over a LightTreeView (DESIGN 6); the `const LightTree&` forms forward to them.
#pragma once

#include <cstdint>

#include "rll/core/device.h"
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
  RLL_HD int index_of(uint32_t n) const {
    for (int i = 0; i < length; ++i)
      if (node[i] == n) return i;
    return -1;
  }
  // Product of the steps after index `a` up to and including `b`.
  RLL_HD float product(int a, int b) const {
    float p = 1;
    for (int i = a + 1; i <= b; ++i) p *= step[i];
    return p;
  }
};

namespace detail {
// The smallest probability of a step towards a child with positive importance: i0 / (i0 + i1)
// rounds to exactly 1 where i1 < 2^-24 i0, which would give the lights under the second child
// pmf 0 although they can contribute.
inline constexpr float kMinStep = 0x1p-24f;
// The largest double below 1: where a rescaled u lands after a step.
inline constexpr double kBelowOne = 0x1.fffffffffffffp-1;
}  // namespace detail

// The probability that a descent at inner node `node` goes to its first child, each child's
// share (by importance, or by contributing groups at a group node) scaled by a positive factor
// g0, g1 (1, 1: the light tree's own step, as tree_descend takes it). The children's importances
// are written to importance0/1 where computed (not at group nodes).
//
// A group node splits by the number of groups under each child that can contribute at the point
// (equal shares, as pbrt-v4 gives its infinite lights and its BVH: shares by importance had 20%
// more error on cornell-boxes-room, the same on arch-interior); any other node in proportion to
// importance. The factors are positive, so that a child is chosen with positive probability
// exactly where the plain tree would. Where both children have zero importance (the parent's
// looser bounds admitted a subtree whose own bounds exclude the point, so none of its lights can
// contribute) the choice falls back to power, then to light count, so that the pmfs over all
// lights always sum to one.
RLL_HD inline float first_child_probability(const LightTreeView& tree, const LightTreeNode& node,
                                            const Vec3& p, const Vec3& n, float g0, float g1,
                                            float* importance0, float* importance1) {
  if (node.group) {
    int c0 = contributing_groups(tree, node.child, p, n),
        c1 = contributing_groups(tree, node.child + 1, p, n);
    if (c0 + c1 > 0) {
      if (c0 == 0 || c1 == 0) return c0 > 0 ? 1.0f : 0.0f;
      const double w0 = double(c0) * g0, w1 = double(c1) * g1;
      return clamp(float(w0 / (w0 + w1)), detail::kMinStep, 1 - detail::kMinStep);
    }
  } else {
    // The children of a node that is not a group node are not group nodes either: their own
    // bounds (tree_importance would unroll the group case into device code for nothing).
    float i0 = light_importance(tree.importance[node.child], p, n);
    float i1 = light_importance(tree.importance[node.child + 1], p, n);
    if (importance0) *importance0 = i0;
    if (importance1) *importance1 = i1;
    if (i0 > 0 && i1 > 0) {
      const double w0 = double(i0) * g0, w1 = double(i1) * g1;
      return clamp(float(w0 / (w0 + w1)), detail::kMinStep, 1 - detail::kMinStep);
    }
    if (i0 > 0 || i1 > 0) return i0 > 0 ? 1.0f : 0.0f;
  }
  const LightTreeNode &a = tree.node(node.child), &b = tree.node(node.child + 1);
  float w0 = a.bounds.power, w1 = b.bounds.power;
  if (!(w0 + w1 > 0)) {
    w0 = float(a.light_count());
    w1 = float(b.light_count());
  }
  return w0 / (w0 + w1);
}

// Descends the subtree under `from`, returning a light under it and the probability of that
// choice given that the descent starts at `from`. A child with zero importance is never chosen
// over a sibling with positive importance, and one with positive importance always keeps a
// positive probability; the pmfs of the lights under `from` sum to one.
RLL_HD inline TreeSample tree_descend(const LightTreeView& tree, uint32_t from, const Vec3& p,
                                      const Vec3& n, double u, DescentPath* path = nullptr) {
  uint32_t index = from;
  float pmf = 1;
  if (path) {
    path->length = 1;
    path->node[0] = from;
    path->step[0] = 1;
  }
  for (;;) {
    const LightTreeNode& node = tree.node(index);
    if (node.is_leaf()) return {node.begin, pmf};
    float p0 = first_child_probability(tree, node, p, n, 1.0f, 1.0f, nullptr, nullptr);
    float step;
    if (u < p0) {
      u = std::min(u / p0, double(detail::kBelowOne));
      step = p0;
      index = node.child;
    } else {
      u = std::min((u - p0) / (1 - p0), double(detail::kBelowOne));
      step = 1 - p0;
      index = node.child + 1;
    }
    pmf *= step;
    if (path) {
      path->node[path->length] = index;
      path->step[path->length++] = step;
    }
  }
}

namespace detail {
// Probability that a descent from `from` reaches `to`, a node under it: the steps' products
// top-down from 1, exactly as tree_descend multiplies them.
RLL_HD inline float path_pmf(const LightTreeView& tree, uint32_t from, uint32_t to, const Vec3& p,
                             const Vec3& n) {
  uint32_t path[kMaxTreeDepth];
  int k = 0;
  for (uint32_t i = to; i != from; i = tree.node(i).parent) path[k++] = i;
  float pmf = 1;
  uint32_t parent = from;
  while (k-- > 0) {
    const LightTreeNode& node = tree.node(parent);
    float p0 = first_child_probability(tree, node, p, n, 1.0f, 1.0f, nullptr, nullptr);
    pmf *= path[k] == node.child ? p0 : 1 - p0;
    if (pmf == 0) return 0;
    parent = path[k];
  }
  return pmf;
}
}  // namespace detail

// The probability that tree_descend(tree, from, p, n, .) returns `light`: the same products in
// the same order, so the two agree exactly. 0 if `light` is not under `from`.
RLL_HD inline float tree_descend_pmf(const LightTreeView& tree, uint32_t from, uint32_t light,
                                     const Vec3& p, const Vec3& n) {
  if (light >= tree.light_count()) return 0;
  const LightTreeNode& top = tree.node(from);
  if (light < top.begin || light >= top.end) return 0;
  return detail::path_pmf(tree, from, tree.leaf_of[light], p, n);
}

// The probability that a descent from the root passes through `node` (1 for the root).
RLL_HD inline float tree_reach_pmf(const LightTreeView& tree, uint32_t node, const Vec3& p,
                                   const Vec3& n) {
  return detail::path_pmf(tree, LightTree::kRoot, node, p, n);
}

// The same over a LightTree (host callers).
inline float first_child_probability(const LightTree& tree, const LightTreeNode& node,
                                     const Vec3& p, const Vec3& n, float g0, float g1,
                                     float* importance0, float* importance1) {
  return first_child_probability(tree.view(), node, p, n, g0, g1, importance0, importance1);
}
inline TreeSample tree_descend(const LightTree& tree, uint32_t from, const Vec3& p, const Vec3& n,
                               double u, DescentPath* path = nullptr) {
  return tree_descend(tree.view(), from, p, n, u, path);
}
inline float tree_descend_pmf(const LightTree& tree, uint32_t from, uint32_t light, const Vec3& p,
                              const Vec3& n) {
  return tree_descend_pmf(tree.view(), from, light, p, n);
}
inline float tree_reach_pmf(const LightTree& tree, uint32_t node, const Vec3& p, const Vec3& n) {
  return tree_reach_pmf(tree.view(), node, p, n);
}

}  // namespace rll
