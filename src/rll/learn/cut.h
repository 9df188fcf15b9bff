// A cut of the light tree: K nodes whose light ranges partition all lights, sorted by range
// (the clusters of a cell). How cuts are made (refine_cut, the shared initial cut), checked, and
// walked by the guided descent (children_boundary).
#pragma once

#include <cstdint>
#include <vector>

#include "rll/core/device.h"
#include "rll/lighttree/light_tree.h"

namespace rll {

// A cut being edited (split-collapse), outside the flat store.
struct Cut {
  std::vector<uint32_t> nodes;  // tree nodes sorted by range
  std::vector<float> q;         // learnt mean; < 0: never visited (the prior estimate applies)
  std::vector<float> m2;        // learnt second moment (meaningful where q >= 0)
  std::vector<float> n;         // shrinkage rule: rewards (and prior) behind q and m2
  std::vector<float> weight;    // prior weight of each cluster (importance or power)
};

// Refinement of the tree from the root, always splitting the node with the largest
// `priority(node)` (ties: the lower node id), until `size` nodes or only leaves; sorted by light
// range.
std::vector<uint32_t> refine_cut(const LightTree& tree, int size,
                                 double (*priority)(const LightTree&, uint32_t));
// The shared initial cut: refine_cut by light count.
std::vector<uint32_t> initial_cut(const LightTree& tree, int size);

// Guided descent: for an inner node above a cut whose clusters [k0, k1) lie under it (`ends` the
// cut's range ends), the cluster j after which its two children meet: ends[j] is the first
// child's end, so clusters [k0, j] lie under the first child and [j + 1, k1) under the second.
RLL_HD inline uint32_t children_boundary(const LightTreeView& tree, const LightTreeNode& node,
                                         const uint32_t* ends, uint32_t k0, uint32_t k1) {
  // The first of ends[k0, k1) not below the first child's end (std::lower_bound, on either device).
  const uint32_t target = tree.node(node.child).end;
  uint32_t lo = k0, n = k1 - k0;
  while (n > 0) {
    const uint32_t half = n / 2;
    if (ends[lo + half] < target) {
      lo += half + 1;
      n -= half + 1;
    } else {
      n = half;
    }
  }
  return lo;
}
inline uint32_t children_boundary(const LightTree& tree, const LightTreeNode& node,
                                  const uint32_t* ends, uint32_t k0, uint32_t k1) {
  return children_boundary(tree.view(), node, ends, k0, k1);
}

// True if the nodes partition [0, light_count) into contiguous ranges in order.
bool is_valid_cut(const LightTree& tree, const std::vector<uint32_t>& nodes);

}  // namespace rll
