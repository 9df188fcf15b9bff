// Descents of the light tree: one stochastic walk from a node to a light, each child chosen in
// proportion to its importance at the shading point (above the group roots, by the groups that
// can contribute there), and the exact probabilities of such walks. The `tree` sampler is one
// descent from the root; rll and ltc descend below their clusters and mix in whole-tree descents.
// RLL_HD over a LightTreeView (DESIGN 6); the `const LightTree&` forms forward to them.
#pragma once

#include <cstdint>

#include "rll/core/device.h"
#include "rll/core/search.h"
#include "rll/lighttree/light_tree.h"

namespace rll {

// A light chosen by a descent and the probability of choosing it (0: nothing was chosen).
struct TreeSample {
  uint32_t light = 0;
  float pmf = 0;
};

// What a descent from the top of a cut records for the pmfs of the cut's clusters (rll and ltc:
// the reward of a sample drawn by the tree goes to its cluster, whose probabilities it needs):
// the cluster whose node the descent went through, the probability of reaching that node and of
// the rest of the path below it. Both products are formed top-down from 1, exactly as
// tree_reach_pmf and tree_descend_pmf form them, so that they agree with them to the bit. It
// replaces a record of the whole path (a node and a step per level, 2 KB of every GPU thread's
// stack): 32 bytes, and no importance evaluated again.
struct DescentSplit {
  static constexpr uint32_t kNone = ~0u;
  // In: the cut, its clusters' nodes and range ends (ascending) under the descent's start.
  const uint32_t* ends = nullptr;
  const uint32_t* nodes = nullptr;
  uint32_t size = 0;
  // Out: the cluster whose node the path passed (kNone: none of them), the product of the steps
  // from the start to that node (1 if it is the start) and of those after it down to the leaf.
  uint32_t cluster = kNone;
  float reach = 0;
  float below = 0;
};

// The cluster j of a cut after which the two children of an inner node above it meet, for the
// cut's clusters [k0, k1) under the node (`ends` the cut's range ends, `first_end` the end of the
// node's first child): ends[j] is the first child's end, so clusters [k0, j] lie under the first
// child and [j + 1, k1) under the second.
RLL_HD inline uint32_t children_boundary(uint32_t first_end, const uint32_t* ends, uint32_t k0,
                                         uint32_t k1) {
  // The first of ends[k0, k1) not below the first child's end.
  return lower_bound_index(ends, k0, k1, first_end);
}
RLL_HD inline uint32_t children_boundary(const LightTreeView& tree, const LightTreeNode& node,
                                         const uint32_t* ends, uint32_t k0, uint32_t k1) {
  return children_boundary(tree.step(node.child).end[0], ends, k0, k1);
}

namespace detail {
// The smallest probability of a step towards a child with positive importance: i0 / (i0 + i1)
// rounds to exactly 1 where i1 < 2^-24 i0, which would give the lights under the second child
// pmf 0 although they can contribute.
inline constexpr float kMinStep = 0x1p-24f;
// The largest double below 1: where a rescaled u lands after a step.
inline constexpr double kBelowOne = 0x1.fffffffffffffp-1;
}  // namespace detail

// The probability that a descent at an inner node (its TreeStep `step`, its first child
// `first_child`) goes to its first child, each child's share (by importance, or by contributing
// groups at a group node) scaled by a positive factor g0, g1 (1, 1: the light tree's own step,
// as tree_descend takes it). The children's importances are written to importance0/1 where
// computed (not at group nodes).
//
// A group node splits by the number of groups under each child that can contribute at the point
// (equal shares, as pbrt-v4 gives its infinite lights and its BVH: shares by importance had 20%
// more error on cornell-boxes-room, the same on arch-interior); any other node in proportion to
// importance. The factors are positive, so that a child is chosen with positive probability
// exactly where the plain tree would. Where both children have zero importance (the parent's
// looser bounds admitted a subtree whose own bounds exclude the point, so none of its lights can
// contribute) the choice falls back to power, then to light count, so that the pmfs over all
// lights always sum to one.
namespace detail {
// Where neither child can contribute: by power, then by light count (the nodes themselves; rare).
RLL_HD inline float first_child_fallback(const LightTreeView& tree, uint32_t first_child) {
  const LightTreeNode &a = tree.node(first_child), &b = tree.node(first_child + 1);
  float w0 = a.bounds.power, w1 = b.bounds.power;
  if (!(w0 + w1 > 0)) {
    w0 = float(a.light_count());
    w1 = float(b.light_count());
  }
  return w0 / (w0 + w1);
}
// A group node's step: by contributing groups.
RLL_HD inline float group_first_child_probability(const LightTreeView& tree, uint32_t first_child,
                                                  const Vec3& p, const Vec3& n, float g0,
                                                  float g1) {
  int c0 = contributing_groups(tree, first_child, p, n),
      c1 = contributing_groups(tree, first_child + 1, p, n);
  if (c0 + c1 > 0) {
    if (c0 == 0 || c1 == 0) return c0 > 0 ? 1.0f : 0.0f;
    const double w0 = double(c0) * g0, w1 = double(c1) * g1;
    return clamp(float(w0 / (w0 + w1)), kMinStep, 1 - kMinStep);
  }
  return first_child_fallback(tree, first_child);
}
}  // namespace detail

RLL_HD inline float first_child_probability(const LightTreeView& tree, const TreeStep& step,
                                            uint32_t first_child, const Vec3& p, const Vec3& n,
                                            float g0, float g1, float* importance0,
                                            float* importance1) {
  // The group nodes (at most kGroupDepth levels at the top) and the fallback out of the way of
  // the common step, which then stays small enough to be inlined into the descents.
  if (step.group()) return detail::group_first_child_probability(tree, first_child, p, n, g0, g1);
  // The children of a node that is not a group node are not group nodes either: their own
  // bounds (tree_importance would unroll the group case into device code for nothing).
  const float i0 = light_importance(step.bounds[0], p, n);
  const float i1 = light_importance(step.bounds[1], p, n);
  if (importance0) *importance0 = i0;
  if (importance1) *importance1 = i1;
  if (i0 > 0 && i1 > 0) {
    const double w0 = double(i0) * g0, w1 = double(i1) * g1;
    return clamp(float(w0 / (w0 + w1)), detail::kMinStep, 1 - detail::kMinStep);
  }
  if (i0 > 0 || i1 > 0) return i0 > 0 ? 1.0f : 0.0f;
  return detail::first_child_fallback(tree, first_child);
}
// The same at an inner node.
RLL_HD inline float first_child_probability(const LightTreeView& tree, const LightTreeNode& node,
                                            const Vec3& p, const Vec3& n, float g0, float g1,
                                            float* importance0, float* importance1) {
  return first_child_probability(tree, tree.step(node.child), node.child, p, n, g0, g1,
                                 importance0, importance1);
}

// Descends the subtree under `from`, returning a light under it and the probability of that
// choice given that the descent starts at `from`. A child with zero importance is never chosen
// over a sibling with positive importance, and one with positive importance always keeps a
// positive probability; the pmfs of the lights under `from` sum to one. With `split`, the cut's
// clusters under `from` are followed down to the one the path enters, as the guided descent
// follows them (a cut is a union of tree nodes: the first node on the path whose range lies in
// one cluster is that cluster's node).
RLL_HD inline TreeSample tree_descend(const LightTreeView& tree, uint32_t from, const Vec3& p,
                                      const Vec3& n, double u, DescentSplit* split = nullptr) {
  float pmf = 1;
  // The clusters [k0, k1) under the current node; `found` once the path is at or below one's node.
  uint32_t k0 = 0, k1 = 0;
  bool found = false;
  if (split) {
    split->cluster = DescentSplit::kNone;
    k1 = split->size;
    if (k1 - k0 == 1 && split->nodes[k0] == from) {
      found = true;
      split->cluster = k0;
      split->reach = pmf;
      split->below = 1;
    }
  }
  const LightTreeNode& top = tree.node(from);
  if (top.is_leaf()) return {top.begin, pmf};
  // Each step reads only its own TreeStep: `c` the current node's first child.
  uint32_t c = top.child;
  for (;;) {
    const TreeStep& s = tree.step(c);
#if !RLL_DEVICE_CODE
    // Both children's steps on their way while this one's importances are computed (a leaf's
    // child index 0 names step 0, which is harmless): half the time per sample at 10^5-10^6
    // lights on the CPU.
    __builtin_prefetch(&tree.step(s.child[0]));
    __builtin_prefetch(&tree.step(s.child[1]));
#endif
    float p0 = first_child_probability(tree, s, c, p, n, 1.0f, 1.0f, nullptr, nullptr);
    // The next step's node is read inside each branch, so that the CPU can run ahead into the
    // predicted child before this step's importances are known (an index computed from `first`
    // would make every step wait for the last one's arithmetic).
    float step;
    uint32_t j, next;
    const bool first = u < p0;
    if (first) {
      u = std::min(u / p0, double(detail::kBelowOne));
      step = p0;
      j = 0;
      next = s.child[0];
    } else {
      u = std::min((u - p0) / (1 - p0), double(detail::kBelowOne));
      step = 1 - p0;
      j = 1;
      next = s.child[1];
    }
    pmf *= step;
    if (split) {
      if (found) {
        split->below *= step;
      } else {
        if (k1 - k0 > 1) {
          const uint32_t b = children_boundary(s.end[0], split->ends, k0, k1);
          if (first)
            k1 = b + 1;
          else
            k0 = b + 1;
        }
        if (k1 - k0 == 1 && split->nodes[k0] == c + j) {
          found = true;
          split->cluster = k0;
          split->reach = pmf;
          split->below = 1;
        }
      }
    }
    if (next == 0) return {s.begin[j], pmf};
    c = next;
  }
}

namespace detail {
// Probability that a descent from `from` reaches `to`, a node under it (0 if it is not under it):
// the steps' products top-down from 1, exactly as tree_descend multiplies them. The path is found
// going down by the light ranges (a child holds `to` where its range holds to's first light; no
// node's range is empty; `first_light` is to's first light), so that no record of it is kept.
RLL_HD inline float path_pmf(const LightTreeView& tree, uint32_t from, uint32_t to, const Vec3& p,
                             const Vec3& n, uint32_t first_light) {
  if (from == to) return 1;
  uint32_t c = tree.node(from).child;  // the current node's first child (0: a leaf)
  float pmf = 1;
  while (c != 0) {
    const TreeStep& s = tree.step(c);
    float p0 = first_child_probability(tree, s, c, p, n, 1.0f, 1.0f, nullptr, nullptr);
    const bool first = first_light < s.end[0];
    pmf *= first ? p0 : 1 - p0;
    if (pmf == 0) return 0;
    const uint32_t j = first ? 0 : 1;
    if (c + j == to) return pmf;
    c = s.child[j];
  }
  return 0;
}
}  // namespace detail

// The probability that tree_descend(tree, from, p, n, .) returns `light`: the same products in
// the same order, so the two agree exactly. 0 if `light` is not under `from`.
RLL_HD inline float tree_descend_pmf(const LightTreeView& tree, uint32_t from, uint32_t light,
                                     const Vec3& p, const Vec3& n) {
  if (light >= tree.light_count()) return 0;
  const LightTreeNode& top = tree.node(from);
  if (light < top.begin || light >= top.end) return 0;
  return detail::path_pmf(tree, from, tree.leaf_of[light], p, n, light);
}

// The probability that a descent from the root passes through `node` (1 for the root).
RLL_HD inline float tree_reach_pmf(const LightTreeView& tree, uint32_t node, const Vec3& p,
                                   const Vec3& n) {
  return detail::path_pmf(tree, LightTree::kRoot, node, p, n, tree.node(node).begin);
}

// The same over a LightTree (host callers).
inline float first_child_probability(const LightTree& tree, const LightTreeNode& node,
                                     const Vec3& p, const Vec3& n, float g0, float g1,
                                     float* importance0, float* importance1) {
  return first_child_probability(tree.view(), node, p, n, g0, g1, importance0, importance1);
}
inline TreeSample tree_descend(const LightTree& tree, uint32_t from, const Vec3& p, const Vec3& n,
                               double u, DescentSplit* split = nullptr) {
  return tree_descend(tree.view(), from, p, n, u, split);
}
inline uint32_t children_boundary(const LightTree& tree, const LightTreeNode& node,
                                  const uint32_t* ends, uint32_t k0, uint32_t k1) {
  return children_boundary(tree.view(), node, ends, k0, k1);
}
inline float tree_descend_pmf(const LightTree& tree, uint32_t from, uint32_t light, const Vec3& p,
                              const Vec3& n) {
  return tree_descend_pmf(tree.view(), from, light, p, n);
}
inline float tree_reach_pmf(const LightTree& tree, uint32_t node, const Vec3& p, const Vec3& n) {
  return tree_reach_pmf(tree.view(), node, p, n);
}

}  // namespace rll
