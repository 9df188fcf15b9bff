// The reference light tree: one binary tree over all lights, one light per leaf. Lights are
// reordered into tree order, so every node covers a contiguous range [begin, end) of the light
// array and a node's two children are adjacent in the node array, after their parent.
//
// The lights fall into up to three groups, each under its own subtree: local lights (every
// light with a position except the sky dome), the sky dome's triangles, and directional lights.
// Above the group roots the tree is root -> [local, distant], distant -> [dome, directional]
// (a missing group takes its parent's place). These few "group nodes" split by the number of
// groups under each child that can contribute at the point, not by importance: a far dome's
// bounds say little next to a room's lamps (pbrt-v4 gives its infinite lights and its BVH equal
// shares for the same reason; with the dome in the lamps' LBVH, cornell-boxes-room had 6x the
// error). Below a group root the descent follows importance; the dome's triangles are bounded
// as distant lights there, by cones of the directions towards them from the scene.
// Both the `tree` sampler and RLL's cuts stand on it.
#pragma once

#include <cstdint>
#include <vector>

#include "rll/core/device.h"
#include "rll/lighttree/light_bounds.h"

namespace rll {

struct Scene;

// Deepest tree the samplers' fixed-size descent paths hold (the root is at depth 0).
inline constexpr int kMaxTreeDepth = 256;

struct LightTreeNode {
  LightBounds bounds;
  uint32_t begin = 0, end = 0;  // lights [begin, end) in tree order
  uint32_t child = 0;           // first of the two adjacent children; 0 for a leaf
  uint32_t parent = ~0u;        // ~0u for the root
  bool group = false;           // above the group roots: children chosen by contributing groups
  RLL_HD bool is_leaf() const { return child == 0; }
  RLL_HD uint32_t light_count() const { return end - begin; }
};

// How the subtrees of the local lights and of the sky dome are built (the group structure above
// them is the same for both).
enum class TreeBuild : uint8_t {
  // Top-down, binned surface-area-orientation heuristic (Conty & Kulla 2018, as pbrt-v4's light
  // BVH): 16% less error than the LBVH on cornell-boxes-room at equal samples; 1M lights in
  // about 0.8 s on 2 cores (the LBVH: 0.3 s).
  Saoh,
  // Linear BVH: Morton order of centroids, split at the highest differing bit (the paper's).
  Lbvh,
};

enum class LightGroup : uint8_t { Local, Dome, Directional };
inline constexpr int kLightGroups = 3;

// One inner node's step of a descent, packed for it: the importance bounds of its two children
// (nodes c and c + 1, c its first child) and, for each, its first child (0: a leaf) and its light
// range. 128 bytes, aligned: a step reads two adjacent cache lines, where the node arrays took
// four to five (the node for its child, then the children's 52-byte bounds, which straddle
// lines). Every inner node's children are made together and the root is node 0, so pairs start
// at odd indices: the step of the node whose first child is c is steps[(c + 1) / 2], and step 0
// holds the root's own bounds (as its second child's). Node i's bounds are then
// steps[(i + 1) / 2].bounds[(i + 1) % 2] for every i.
struct alignas(128) TreeStep {
  // Set on bounds[0].flags where the step's node is a group node (children chosen by their
  // contributing groups; light_importance reads no such bit).
  static constexpr uint32_t kGroupStep = 16;
  ImportanceBounds bounds[2];
  uint32_t child[2] = {0, 0};
  uint32_t begin[2] = {0, 0};
  uint32_t end[2] = {0, 0};
  RLL_HD bool group() const { return (bounds[0].flags & kGroupStep) != 0; }
};
static_assert(sizeof(TreeStep) == 128, "a descent step is two cache lines");

// What the descents read of a LightTree (DESIGN 6): its nodes, their steps (every node's
// importance bounds, the sky dome's frame folded into them) and the leaf of each light, owning
// nothing, so that the same RLL_HD functions descend it on the CPU and, pointing into device
// memory, on the GPU.
struct LightTreeView {
  View<const LightTreeNode> nodes;
  View<const TreeStep> steps;    // one per light: step 0 the root's bounds, then the inner nodes'
  View<const uint32_t> leaf_of;  // per light, tree order
  uint32_t group_root[kLightGroups] = {~0u, ~0u, ~0u};

  RLL_HD const LightTreeNode& node(uint32_t i) const { return nodes[i]; }
  RLL_HD uint32_t light_count() const { return uint32_t(leaf_of.size); }
  // The step of the inner node whose first child is `first_child`.
  RLL_HD const TreeStep& step(uint32_t first_child) const { return steps[(first_child + 1) >> 1]; }
  // Node i's importance bounds.
  RLL_HD const ImportanceBounds& bounds(uint32_t i) const {
    return steps[(i + 1) >> 1].bounds[(i + 1) & 1];
  }
};

// Writes the steps of a tree whose nodes are `nodes` and their importance bounds `bounds` (per
// node) to `steps` ((nodes.size + 1) / 2 of them); fails unless every inner node's first child
// is odd (the layout above).
void tree_steps(View<const LightTreeNode> nodes, View<const ImportanceBounds> bounds,
                View<TreeStep> steps);

namespace detail {
// Importance of `node`; at a group node the sum of its children's, left then right, nested as
// the group nodes are. Unrolled by a depth bound instead of recursing (device code): group nodes
// nest at most kGroupDepth deep (below).
template <int Depth>
RLL_HD inline float tree_importance_at(const LightTreeView& t, uint32_t node, const Vec3& p,
                                       const Vec3& n) {
  const ImportanceBounds& b = t.bounds(node);
  if constexpr (Depth > 0) {
    if (b.flags & ImportanceBounds::kGroup) {
      const uint32_t c = t.nodes[node].child;
      return tree_importance_at<Depth - 1>(t, c, p, n) +
             tree_importance_at<Depth - 1>(t, c + 1, p, n);
    }
  }
  return light_importance(b, p, n);
}
template <int Depth>
RLL_HD inline int contributing_groups_at(const LightTreeView& t, uint32_t node, const Vec3& p,
                                         const Vec3& n) {
  const LightTreeNode& nd = t.nodes[node];
  if constexpr (Depth > 0) {
    if (nd.group)
      return contributing_groups_at<Depth - 1>(t, nd.child, p, n) +
             contributing_groups_at<Depth - 1>(t, nd.child + 1, p, n);
  }
  // Not a group node (below its groups or past the deepest group node): its own bounds.
  return light_importance(t.bounds(node), p, n) > 0 ? 1 : 0;
}
// Group nodes nest at most this deep (root -> distant -> [dome, directional]): the unrolling's
// bound. Deeper unrolling would only copy the importance into device code to no effect (each
// copy is inlined: at kLightGroups, a descent step held 144 of them).
inline constexpr int kGroupDepth = kLightGroups - 1;
}  // namespace detail

// Importance of the lights under `node` at p with normal n; for a group node, the sum of its
// children's (their bounds are of different kinds and do not merge usefully).
RLL_HD inline float tree_importance(const LightTreeView& t, uint32_t node, const Vec3& p,
                                    const Vec3& n) {
  return detail::tree_importance_at<detail::kGroupDepth>(t, node, p, n);
}
// How many groups under `node` can contribute at p (importance > 0 at their roots); for a node
// inside a group, 1 or 0.
RLL_HD inline int contributing_groups(const LightTreeView& t, uint32_t node, const Vec3& p,
                                      const Vec3& n) {
  return detail::contributing_groups_at<detail::kGroupDepth>(t, node, p, n);
}

class LightTree {
 public:
  LightTree() = default;
  // Builds the tree over scene.lights and reorders them into tree order.
  static LightTree build(Scene& scene, TreeBuild method = TreeBuild::Saoh);

  // Recomputes every node's bounds after lights moved or changed power (topology kept).
  void refit(const std::vector<Light>& lights);

  static constexpr uint32_t kRoot = 0;
  static constexpr uint32_t kNone = ~0u;
  size_t node_count() const { return m_nodes.size(); }
  size_t light_count() const { return m_leaf_of.size(); }
  const LightTreeNode& node(uint32_t i) const { return m_nodes[i]; }
  const std::vector<LightTreeNode>& nodes() const { return m_nodes; }
  uint32_t leaf_of(uint32_t light) const { return m_leaf_of[light]; }
  // Root of a group's subtree (kNone where the scene has no such light; kRoot for a lone group).
  uint32_t group_root(LightGroup g) const { return m_group_root[int(g)]; }
  // The flat view the descents read; valid while the tree lives (refit keeps its arrays).
  LightTreeView view() const {
    LightTreeView v{view_of(m_nodes), view_of(m_steps), view_of(m_leaf_of)};
    for (int g = 0; g < kLightGroups; ++g) v.group_root[g] = m_group_root[g];
    return v;
  }
  // tree_importance and contributing_groups (above) over this tree.
  float importance(uint32_t node, const Vec3& p, const Vec3& n) const {
    return tree_importance(view(), node, p, n);
  }
  int contributing_groups(uint32_t node, const Vec3& p, const Vec3& n) const {
    return rll::contributing_groups(view(), node, p, n);
  }
  uint32_t depth() const { return m_depth; }
  TreeBuild method() const { return m_method; }
  size_t bytes() const {
    return m_nodes.size() * sizeof(LightTreeNode) + m_steps.size() * sizeof(TreeStep) +
           m_leaf_of.size() * sizeof(uint32_t);
  }

 private:
  LightBounds leaf_bounds(const Light& light, uint32_t index) const;
  void prepare_importance();
  std::vector<LightTreeNode> m_nodes;
  std::vector<TreeStep> m_steps;  // LightTreeView::steps
  std::vector<uint32_t> m_leaf_of;
  uint32_t m_group_root[kLightGroups] = {kNone, kNone, kNone};
  uint32_t m_depth = 0;
  // The sky dome's lights [m_dome_begin, m_dome_end) are bounded as distant lights in this frame.
  uint32_t m_dome_begin = 0, m_dome_end = 0;
  DistantFrame m_dome_frame;
  TreeBuild m_method = TreeBuild::Saoh;
};

// Builds the light tree of a finalized scene and reorders scene.lights (and the mesh's triangle
// -> light ids) into tree order, warning once (into scene.warnings) of lights whose power was
// capped. Whoever renders owns the tree, next to the scene: the render session
// (session/session.h) builds it once, right after loading, and lends it to every sampler it
// makes; tests and benchmarks hold their own. Build once per scene: a build over lights already
// in tree order can order ties otherwise. Scene::fingerprint, and with it reference keys, render
// shares and learnt states, is taken after it: the light order it hashes is the tree's. After
// animate() and Scene::refresh_lights_from_mesh() move lights, the owner calls refit().
LightTree build_light_tree(Scene& scene);

}  // namespace rll
