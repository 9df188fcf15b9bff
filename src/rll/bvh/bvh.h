// rll's own bounding volume hierarchy over the scene mesh: built on the host (binned SAH), laid
// out for the GPU, traversed by the RLL_HD functions of bvh/traverse.h on either device.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "rll/core/device.h"
#include "rll/core/math.h"
#include "rll/scene/mesh.h"

namespace rll {

// An inner node holding the boxes of both its children, as Aila & Laine (2009) lay them out: 64
// bytes that four 16-byte loads fetch, so that one fetch decides which children a ray enters.
struct alignas(16) BvhNode {
  float left_xy[4];   // left child: lo.x, hi.x, lo.y, hi.y
  float right_xy[4];  // right child: the same
  float z[4];         // left lo.z, hi.z, right lo.z, hi.z
  // An inner node's index, or kBvhLeaf | a leaf's first triangle (in BvhView::triangles).
  uint32_t child[2];
  uint32_t count[2];  // a leaf's triangle count (0: an empty side, whose box is a point)

  Bounds3 bounds(int side) const;
  void set_bounds(int side, const Bounds3& b);
};
static_assert(sizeof(BvhNode) == 64);
inline constexpr uint32_t kBvhLeaf = 0x80000000u;

// A triangle in leaf order: its vertices and the mesh triangle it is, three 16-byte loads.
struct alignas(16) BvhTriangle {
  Vec3 p0;
  uint32_t tri;
  Vec3 p1;
  uint32_t pad1;
  Vec3 p2;
  uint32_t pad2;
};
static_assert(sizeof(BvhTriangle) == 48);

// What traversal reads: trivially copyable, so it travels by value into a kernel. Node 0 is
// the root; a hierarchy with no triangles has a root whose two boxes are empty.
struct BvhView {
  View<const BvhNode> nodes;
  View<const BvhTriangle> triangles;
};

// The depth no hierarchy exceeds (the builder splits by count below kBvhMedianDepth), so that
// traversal's fixed stack of kBvhStackSize entries never overflows.
inline constexpr int kBvhStackSize = 64;
inline constexpr int kBvhMedianDepth = 32;

struct Bvh {
  std::vector<BvhNode> nodes;
  std::vector<BvhTriangle> triangles;
  int depth = 0;             // of the deepest leaf, the root's children at depth 1
  double build_seconds = 0;  // the last build or refit's wall time
  size_t vertex_count = 0;   // of the mesh it was built over (refit checks both)
  size_t triangle_count = 0;

  BvhView view() const { return {view_of(nodes), view_of(triangles)}; }
  size_t bytes() const {
    return nodes.size() * sizeof(BvhNode) + triangles.size() * sizeof(BvhTriangle);
  }
  // Re-reads the vertex positions of a mesh with the same triangles (an animated scene's next
  // frame) and recomputes every box bottom-up; the topology stays, so its quality may drop if
  // vertices move far. Throws rll::Error if the mesh's vertex or triangle count changed.
  void refit(const Mesh& mesh);
};

// Builds the hierarchy over the mesh's triangles with the surface area heuristic over binned
// centroids; triangles with a non-finite vertex are left out (Embree leaves them out too).
Bvh build_bvh(const Mesh& mesh);

}  // namespace rll
