// The visibility-blind light-tree sampler (Conty & Kulla 2018, as pbrt-v4's BVH light sampler):
// one stochastic descent of the reference tree, each child chosen in proportion to its
// importance at the shading point; above the group roots (local lights, sky dome, directional
// lights), each group that can contribute at the point gets an equal share.
#pragma once

#include "rll/lights/light_sampler.h"
#include "rll/lights/light_tree.h"

namespace rll {

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
SampledLight tree_descend(const LightTree& tree, uint32_t from, const Vec3& p, const Vec3& n,
                          double u, DescentPath* path = nullptr);
// The probability that tree_descend(tree, from, p, n, .) returns `light`: the same products in
// the same order, so the two agree exactly. 0 if `light` is not under `from`.
float tree_descend_pmf(const LightTree& tree, uint32_t from, uint32_t light, const Vec3& p,
                       const Vec3& n);

// The probability that a descent at inner node `node` goes to its first child, each child's
// share (by importance, or by contributing groups at a group node) scaled by a positive factor
// g0, g1 (1, 1: the light tree's own step, as tree_descend takes it). The children's importances
// are written to importance0/1 where computed (not at group nodes).
float first_child_probability(const LightTree& tree, const LightTreeNode& node, const Vec3& p, const Vec3& n,
                              float g0, float g1, float* importance0, float* importance1);

// The probability that a descent from the root passes through `node` (1 for the root).
float tree_reach_pmf(const LightTree& tree, uint32_t node, const Vec3& p, const Vec3& n);

class TreeLightSampler final : public LightSampler {
 public:
  explicit TreeLightSampler(const Scene& scene);
  std::string name() const override { return "tree"; }
  SampledLight sample(const LightContext& ctx, double u) const override;
  float pmf(const LightContext& ctx, uint32_t light) const override;
  nlohmann::json describe() const override;

 private:
  const LightTree& m_tree;
};

}  // namespace rll
