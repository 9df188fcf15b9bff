// The resampled hierarchical tree (Conty Estevez, Hellmuth & Lecocq 2024; docs/rht.md): the split
// descent of the light tree, which yields several candidate lights per draw, each with the
// probability that a draw yields it, and the replay of that probability for any light (what the
// BSDF strategy's MIS weight needs). RLL_HD over a LightTreeView, so that a device renderer could
// run the functions the CPU runs; the resampling of the candidates is render/rht_nee.h.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "rll/core/device.h"
#include "rll/core/hash.h"
#include "rll/lighttree/descent.h"

namespace rll {

// Bounds of rht.reservoirs (first stage, "heuristic H") and rht.samples (second stage, "heuristic
// F": shadow rays per vertex); fixed-size arrays of these sizes live on the stack of a vertex.
inline constexpr int kRhtMaxReservoirs = 32;
inline constexpr int kRhtMaxSamples = 8;

struct RhtView {
  LightTreeView tree;
  float gamma = 0.05f;  // width of the split probability's Cauchy bell
  int reservoirs = 8;
  int samples = 4;
  // The directional lights [dir_begin, dir_begin + dir_count) in tree order: chosen first, with
  // probability dir_count / (dir_count + 1) where other lights exist, as the public code chooses
  // its infinite lights; everything else (local lights and sky-dome triangles) is descended.
  uint32_t dir_begin = 0, dir_count = 0;
  bool has_tree_lights = false;
};

// Probability that a draw takes a directional light instead of descending the tree.
RLL_HD inline float rht_directional_probability(const RhtView& v) {
  if (v.dir_count == 0) return 0;
  return float(v.dir_count) / float(v.dir_count + (v.has_tree_lights ? 1u : 0u));
}

RLL_HD inline bool rht_is_directional(const RhtView& v, uint32_t light) {
  return light >= v.dir_begin && light - v.dir_begin < v.dir_count;
}

// The probability that a node splits into both children at p: a Cauchy bell of the distance from
// p to the sphere around the node's lights' box, in radii, t = max(0, d - r) / r:
// 1 / (1 + t^2 / gamma^2) (1 inside the sphere), the public code's over its spherical bounds.
RLL_HD inline float rht_split_probability(const Bounds3& box, const Vec3& p, float gamma) {
  const float r = 0.5f * length(box.hi - box.lo);
  if (!(r > 0)) return 0;
  const float t = std::max(0.0f, length(p - 0.5f * (box.lo + box.hi)) - r) / r;
  return 1 / (1 + (t * t) / (gamma * gamma));
}

// What the split descent does at an inner node entered with the state (t, ps_parent): t is the
// probability of reaching the node given that its parent did not split, ps_parent the parent's
// split probability (a draw splits a node iff its number u_split <= the node's ps, and ps never
// grows downwards, so the split nodes are a top part of the tree and every node below the first
// that does not split is reached by single choices).
struct RhtStep {
  float ps = 0;       // the node's split probability (at most its parent's)
  float t = 0;        // P(reach the node | it does not split): its children's t before the choice
  float p0 = 0;       // probability of the first child where the node does not split
  bool drop = false;  // neither child can contribute at p: nothing below is a candidate
  int only = -1;      // a group node whose other child holds the directional lights: this child
};

RLL_HD inline RhtStep rht_step(const RhtView& v, uint32_t index, float t, float ps_parent,
                               const Vec3& p, const Vec3& n) {
  const LightTreeNode& node = v.tree.node(index);
  RhtStep s;
  if (node.group) {
    const uint32_t dir = v.tree.group_root[int(LightGroup::Directional)];
    if (node.child == dir || node.child + 1 == dir) {  // passed through: the state carries on
      s.only = node.child == dir ? 1 : 0;
      s.ps = ps_parent;
      s.t = t;
      return s;
    }
    // Local lights against the sky dome: both sides whenever the parent splits (the root always
    // does), as the public code's root, whose bounding sphere holds the point.
    s.ps = ps_parent;
    s.drop = contributing_groups(v.tree, index, p, n) == 0;
  } else {
    s.ps = std::min(rht_split_probability(node.bounds.box, p, v.gamma), ps_parent);
  }
  float i0 = 1, i1 = 1;
  s.p0 = first_child_probability(v.tree, node, p, n, 1.0f, 1.0f, &i0, &i1);
  if (!node.group) s.drop = !(i0 > 0) && !(i1 > 0);
  // P(the parent split | this node did not) = (ps_parent - ps) / (1 - ps).
  const float pns = s.ps < 1 ? (ps_parent - s.ps) / (1 - s.ps) : 0.0f;
  s.t = pns + (1 - pns) * t;
  return s;
}

// A leaf's probability of being a candidate, times `scale` (the share of draws that descend),
// and its importance (the first stage's weight); 0 where the light cannot contribute at p.
RLL_HD inline float rht_leaf_pdf(const RhtView& v, uint32_t index, float t, float ps_parent,
                                 const Vec3& p, const Vec3& n, float scale, float* importance) {
  const float imp = light_importance(v.tree.bounds(index), p, n);
  if (importance) *importance = imp;
  if (!(imp > 0)) return 0;
  return (ps_parent + (1 - ps_parent) * t) * scale;
}

namespace detail {
// A number in [0, 1) from a key and a node: the public code moves the descent's number by it
// after each single choice, so that the branches of a split do not make the same choices.
RLL_HD inline double rht_scramble(uint64_t key, uint32_t node) {
  return double(mix64(key ^ (uint64_t(node) * 0x9e3779b97f4a7c15ull)) >> 11) * 0x1p-53;
}
}  // namespace detail

// The state (t, ps) with which the descent enters node `target` (an inner node it reached),
// replayed from the root along the light ranges with the descent's arithmetic, so that it equals
// what the descent carried to the bit.
RLL_HD inline void rht_enter(const RhtView& v, uint32_t target, const Vec3& p, const Vec3& n,
                             float& t, float& ps) {
  const uint32_t light = v.tree.node(target).begin;
  t = 1;
  ps = 1;
  for (uint32_t index = LightTree::kRoot; index != target;) {
    const LightTreeNode& node = v.tree.node(index);
    const RhtStep s = rht_step(v, index, t, ps, p, n);
    const bool first = light < v.tree.step(node.child).end[0];
    index = node.child + (first ? 0u : 1u);
    if (s.only >= 0) continue;
    t = s.t * (first ? s.p0 : 1 - s.p0);
    ps = s.ps;
  }
}

// The split descent from the root (directional lights excluded): calls add(light, pdf,
// importance) for each candidate, pdf being the probability that a draw yields it times
// `scale`. u chooses children where a node does not split, u_split decides the splits, `key`
// scrambles u after each choice. Depth first, the first child first; where a node splits, the
// second child waits. On the host the waiting children are a stack bounded by the tree's depth;
// on a device (a thread's stack is small) a bit trail of the split nodes above, each waiting
// child's state made again by rht_enter when its turn comes: the same candidates in the same
// order.
template <class Add>
RLL_HD inline void rht_descend(const RhtView& v, const Vec3& p, const Vec3& n, double u,
                               float u_split, uint64_t key, float scale, Add&& add) {
#if RLL_DEVICE_CODE
  uint32_t trail[kMaxTreeDepth / 32] = {};  // bit d: the node at depth d split, its second waits
  int depth = 0;
#else
  struct Entry {
    uint32_t node;
    float t, ps;
  };
  Entry stack[kMaxTreeDepth];
  int top = 0;
#endif
  uint32_t index = LightTree::kRoot;
  float t = 1, ps = 1;
  for (;;) {
    const LightTreeNode& node = v.tree.node(index);
    if (!node.is_leaf()) {
      const RhtStep s = rht_step(v, index, t, ps, p, n);
      if (s.only >= 0) {
        index = node.child + uint32_t(s.only);
#if RLL_DEVICE_CODE
        ++depth;
#endif
        continue;
      }
      if (!s.drop) {
        if (u_split <= s.ps) {  // both children: the second waits
#if RLL_DEVICE_CODE
          trail[depth / 32] |= 1u << (depth % 32);
#else
          stack[top++] = Entry{node.child + 1, s.t * (1 - s.p0), s.ps};
#endif
          index = node.child;
          t = s.t * s.p0;
        } else if (u < s.p0) {
          u = std::min(u / s.p0, double(detail::kBelowOne));
          index = node.child;
          t = s.t * s.p0;
        } else {
          u = std::min((u - s.p0) / (1 - s.p0), double(detail::kBelowOne));
          index = node.child + 1;
          t = s.t * (1 - s.p0);
        }
        ps = s.ps;
        if (u_split > s.ps) {
          u += detail::rht_scramble(key, index);
          if (u >= 1) u -= 1;
        }
#if RLL_DEVICE_CODE
        ++depth;
#endif
        continue;
      }
    } else {
      float importance = 0;
      const float pdf = rht_leaf_pdf(v, index, t, ps, p, n, scale, &importance);
      if (pdf > 0) add(node.begin, pdf, importance);
    }
#if RLL_DEVICE_CODE
    // The deepest split node above: its second child is next.
    int d = depth - 1;
    while (d >= 0 && !(trail[d / 32] >> (d % 32) & 1u)) --d;
    if (d < 0) return;
    trail[d / 32] &= ~(1u << (d % 32));
    uint32_t a = index;
    for (int k = depth; k > d; --k) a = v.tree.node(a).parent;
    rht_enter(v, a, p, n, t, ps);
    const RhtStep s = rht_step(v, a, t, ps, p, n);
    index = v.tree.node(a).child + 1;
    t = s.t * (1 - s.p0);
    ps = s.ps;
    depth = d + 1;
#else
    if (top == 0) return;
    --top;
    index = stack[top].node;
    t = stack[top].t;
    ps = stack[top].ps;
#endif
  }
}

// The probability that a draw yields `light` as a candidate (a directional light: that it is
// the one chosen), replaying the descent's steps along the light's path with the same
// arithmetic, so that it equals the pdf the descent gives the light to the bit. These sum to the
// expected number of candidates, not to one: it is the light strategy's density for MIS.
RLL_HD inline float rht_pmf(const RhtView& v, const Vec3& p, const Vec3& n, uint32_t light) {
  if (light >= v.tree.light_count()) return 0;
  const float p_dir = rht_directional_probability(v);
  if (rht_is_directional(v, light)) return p_dir / float(v.dir_count);
  float t = 1, ps = 1;
  uint32_t index = LightTree::kRoot;
  while (!v.tree.node(index).is_leaf()) {  // down the light's path, by the light ranges
    const LightTreeNode& node = v.tree.node(index);
    const RhtStep s = rht_step(v, index, t, ps, p, n);
    const bool first = light < v.tree.step(node.child).end[0];
    index = node.child + (first ? 0u : 1u);
    if (s.only >= 0) continue;
    if (s.drop) return 0;
    t = s.t * (first ? s.p0 : 1 - s.p0);
    ps = s.ps;
  }
  return rht_leaf_pdf(v, index, t, ps, p, n, 1 - p_dir, nullptr);
}

}  // namespace rll
