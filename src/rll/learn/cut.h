// A cut of the light tree: K nodes whose light ranges partition all lights, sorted by range
// (the clusters of a cell). How cuts are made (refine_cut, the shared initial cut), checked, and
// walked by the guided descent (children_boundary).
#pragma once

#include <cstdint>
#include <vector>

#include "rll/core/device.h"
#include "rll/lighttree/descent.h"
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

// children_boundary (the cluster after which an inner node's children meet): lighttree/descent.h.

// True if the nodes partition [0, light_count) into contiguous ranges in order.
bool is_valid_cut(const LightTree& tree, const std::vector<uint32_t>& nodes);

}  // namespace rll
