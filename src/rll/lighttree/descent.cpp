#include "rll/lighttree/descent.h"

#include <algorithm>

#include "rll/core/math.h"

namespace rll {

namespace {
constexpr int kMaxDepth = kMaxTreeDepth;

// The smallest probability of a step towards a child with positive importance: i0 / (i0 + i1)
// rounds to exactly 1 where i1 < 2^-24 i0, which would give the lights under the second child
// pmf 0 although they can contribute.
constexpr float kMinStep = 0x1p-24f;

}  // namespace

// Probability of the first child of an inner node. A group node splits by the number of groups
// under each child that can contribute at the point (equal shares, as pbrt-v4 gives its infinite
// lights and its BVH: shares by importance had 20% more error on cornell-boxes-room, the same on
// arch-interior); any other node in proportion to importance. Each child's share is scaled by its
// factor (1 for the plain tree; rll's learnt factors for its guided descent), which is positive,
// so that a child is chosen with positive probability exactly where the plain tree would.
// Where both children have zero importance (the parent's looser bounds admitted a subtree whose
// own bounds exclude the point, so none of its lights can contribute) the choice falls back to
// power, then to light count, so that the pmfs over all lights always sum to one.
float first_child_probability(const LightTree& tree, const LightTreeNode& node, const Vec3& p,
                              const Vec3& n, float g0, float g1, float* importance0,
                              float* importance1) {
  if (node.group) {
    int c0 = tree.contributing_groups(node.child, p, n),
        c1 = tree.contributing_groups(node.child + 1, p, n);
    if (c0 + c1 > 0) {
      if (c0 == 0 || c1 == 0) return c0 > 0 ? 1.0f : 0.0f;
      const double w0 = double(c0) * g0, w1 = double(c1) * g1;
      return clamp(float(w0 / (w0 + w1)), kMinStep, 1 - kMinStep);
    }
  } else {
    float i0 = tree.importance(node.child, p, n);
    float i1 = tree.importance(node.child + 1, p, n);
    if (importance0) *importance0 = i0;
    if (importance1) *importance1 = i1;
    if (i0 > 0 && i1 > 0) {
      const double w0 = double(i0) * g0, w1 = double(i1) * g1;
      return clamp(float(w0 / (w0 + w1)), kMinStep, 1 - kMinStep);
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

namespace {
inline float first_child_probability(const LightTree& tree, const LightTreeNode& node,
                                     const Vec3& p, const Vec3& n) {
  return first_child_probability(tree, node, p, n, 1.0f, 1.0f, nullptr, nullptr);
}
}  // namespace

TreeSample tree_descend(const LightTree& tree, uint32_t from, const Vec3& p, const Vec3& n,
                        double u, DescentPath* path) {
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
    float p0 = first_child_probability(tree, node, p, n);
    float step;
    if (u < p0) {
      u = std::min(u / p0, 0x1.fffffffffffffp-1);
      step = p0;
      index = node.child;
    } else {
      u = std::min((u - p0) / (1 - p0), 0x1.fffffffffffffp-1);
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

namespace {
// Probability that a descent from `from` reaches `to`, a node under it: the steps' products
// top-down from 1, exactly as tree_descend multiplies them.
float path_pmf(const LightTree& tree, uint32_t from, uint32_t to, const Vec3& p, const Vec3& n) {
  uint32_t path[kMaxDepth];
  int k = 0;
  for (uint32_t i = to; i != from; i = tree.node(i).parent) path[k++] = i;
  float pmf = 1;
  uint32_t parent = from;
  while (k-- > 0) {
    const LightTreeNode& node = tree.node(parent);
    float p0 = first_child_probability(tree, node, p, n);
    pmf *= path[k] == node.child ? p0 : 1 - p0;
    if (pmf == 0) return 0;
    parent = path[k];
  }
  return pmf;
}
}  // namespace

float tree_descend_pmf(const LightTree& tree, uint32_t from, uint32_t light, const Vec3& p,
                       const Vec3& n) {
  if (light >= tree.light_count()) return 0;
  const LightTreeNode& top = tree.node(from);
  if (light < top.begin || light >= top.end) return 0;
  return path_pmf(tree, from, tree.leaf_of(light), p, n);
}

float tree_reach_pmf(const LightTree& tree, uint32_t node, const Vec3& p, const Vec3& n) {
  return path_pmf(tree, LightTree::kRoot, node, p, n);
}

}  // namespace rll
