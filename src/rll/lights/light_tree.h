// The reference light tree: one binary LBVH over all lights (Morton order of centroids, one
// light per leaf). Lights are reordered into tree order, so every node covers a contiguous
// range [begin, end) of the light array and a node's two children are adjacent in the node
// array. Lights without a position hang in their own subtree beside the finite-light root.
// Both the `tree` sampler and RLL's cuts stand on it.
#pragma once

#include <cstdint>
#include <vector>

#include "rll/lights/light_bounds.h"

namespace rll {

struct Scene;

struct LightTreeNode {
  LightBounds bounds;
  uint32_t begin = 0, end = 0;  // lights [begin, end) in tree order
  uint32_t child = 0;           // first of the two adjacent children; 0 for a leaf
  uint32_t parent = ~0u;        // ~0u for the root
  bool is_leaf() const { return child == 0; }
  uint32_t light_count() const { return end - begin; }
};

class LightTree {
 public:
  LightTree() = default;
  // Builds the tree over scene.lights and reorders them into tree order.
  static LightTree build(Scene& scene);

  // Recomputes every node's bounds after lights moved or changed power (topology kept).
  void refit(const std::vector<Light>& lights);

  static constexpr uint32_t kRoot = 0;
  static constexpr uint32_t kNone = ~0u;
  size_t node_count() const { return m_nodes.size(); }
  size_t light_count() const { return m_leaf_of.size(); }
  const LightTreeNode& node(uint32_t i) const { return m_nodes[i]; }
  const std::vector<LightTreeNode>& nodes() const { return m_nodes; }
  uint32_t leaf_of(uint32_t light) const { return m_leaf_of[light]; }
  // Roots of the finite and infinite subtrees (kNone where absent; either may be kRoot).
  uint32_t finite_root() const { return m_finite_root; }
  uint32_t infinite_root() const { return m_infinite_root; }
  float importance(uint32_t node, const Vec3& p, const Vec3& n) const { return light_importance(m_fast[node], p, n); }
  uint32_t depth() const { return m_depth; }
  size_t bytes() const {
    return m_nodes.size() * (sizeof(LightTreeNode) + sizeof(ImportanceBounds)) + m_leaf_of.size() * sizeof(uint32_t);
  }

 private:
  void prepare_importance();
  std::vector<LightTreeNode> m_nodes;
  std::vector<ImportanceBounds> m_fast;  // per node, for importance()
  std::vector<uint32_t> m_leaf_of;
  uint32_t m_finite_root = kNone, m_infinite_root = kNone;
  uint32_t m_depth = 0;
};

// Builds the scene's light tree (Scene::finalize calls this): reorders scene.lights.
void build_light_tree(Scene& scene);

}  // namespace rll
