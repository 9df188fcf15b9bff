// The binned SAH builder and the refit of rll's BVH.
#include "rll/bvh/bvh.h"

#include <algorithm>
#include <atomic>
#include <chrono>

#include "rll/core/error.h"
#include "rll/core/parallel.h"

namespace rll {

Bounds3 BvhNode::bounds(int side) const {
  const float* xy = side == 0 ? left_xy : right_xy;
  Bounds3 b;
  b.lo = Vec3(xy[0], xy[2], z[2 * side]);
  b.hi = Vec3(xy[1], xy[3], z[2 * side + 1]);
  return b;
}

void BvhNode::set_bounds(int side, const Bounds3& b) {
  float* xy = side == 0 ? left_xy : right_xy;
  xy[0] = b.lo.x;
  xy[1] = b.hi.x;
  xy[2] = b.lo.y;
  xy[3] = b.hi.y;
  z[2 * side] = b.lo.z;
  z[2 * side + 1] = b.hi.z;
}

namespace {

constexpr int kBins = 16;
constexpr uint32_t kMaxLeaf = 8;
// The cost of visiting a node relative to one triangle test, in the surface area heuristic.
constexpr float kNodeCost = 1.0f;
// Below this many triangles the two halves are built on one thread (a task would cost more).
constexpr uint32_t kParallelGrain = 4096;

float half_area(const Bounds3& b) {
  if (b.empty()) return 0;
  Vec3 d = b.diagonal();
  return d.x * d.y + d.y * d.z + d.z * d.x;
}

BvhTriangle make_triangle(const Mesh& mesh, uint32_t t) {
  BvhTriangle r{};
  r.p0 = mesh.vertex(t, 0);
  r.p1 = mesh.vertex(t, 1);
  r.p2 = mesh.vertex(t, 2);
  r.tri = t;
  return r;
}

Bounds3 triangle_bounds(const BvhTriangle& t) {
  Bounds3 b;
  b.expand(t.p0);
  b.expand(t.p1);
  b.expand(t.p2);
  return b;
}

struct Builder {
  std::vector<Bounds3> boxes;   // per mesh triangle
  std::vector<Vec3> centroids;  // per mesh triangle
  std::vector<uint32_t> order;  // mesh triangles, partitioned into leaf order as the build goes
  std::vector<BvhNode>& nodes;
  std::atomic<uint32_t> node_count{0};
  std::atomic<int> depth{0};

  explicit Builder(std::vector<BvhNode>& n) : nodes(n) {}

  // Builds order[begin, mid) and order[mid, end) as the two children of node k.
  void build_children(uint32_t k, uint32_t begin, uint32_t mid, uint32_t end, int d) {
    auto left = [&] { build_child(k, 0, begin, mid, d + 1); };
    auto right = [&] { build_child(k, 1, mid, end, d + 1); };
    if (end - begin > kParallelGrain) {
      parallel_invoke(left, right);
    } else {
      left();
      right();
    }
  }

  // Makes order[begin, end) side `side` of node k: a leaf, or a new inner node.
  void build_child(uint32_t k, int side, uint32_t begin, uint32_t end, int d) {
    Bounds3 box, centroid_box;
    for (uint32_t i = begin; i < end; ++i) {
      box.expand(boxes[order[i]]);
      centroid_box.expand(centroids[order[i]]);
    }
    if (begin == end) box = Bounds3{Vec3(0), Vec3(0)};  // an empty side: no triangles behind it
    nodes[k].set_bounds(side, box);
    uint32_t n = end - begin;
    uint32_t mid = partition(begin, end, centroid_box, d, /*may_be_leaf=*/n <= kMaxLeaf);
    if (mid == begin) {
      nodes[k].child[side] = kBvhLeaf | begin;
      nodes[k].count[side] = n;
      int seen = depth.load();
      while (seen < d && !depth.compare_exchange_weak(seen, d)) {
      }
      return;
    }
    uint32_t c = node_count.fetch_add(1);
    nodes[k].child[side] = c;
    nodes[k].count[side] = 0;
    build_children(c, begin, mid, end, d);
  }

  // Reorders order[begin, end) into two non-empty halves and returns where the second starts, or
  // `begin` when `may_be_leaf` and one leaf is cheaper than any split (then nothing moves).
  uint32_t partition(uint32_t begin, uint32_t end, const Bounds3& centroid_box, int d,
                     bool may_be_leaf) {
    uint32_t n = end - begin;
    auto* first = order.data() + begin;
    auto* last = order.data() + end;
    Vec3 extent = centroid_box.diagonal();
    int widest = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
    auto median_split = [&] {
      uint32_t mid = begin + n / 2;
      if (extent[widest] > 0)
        std::nth_element(first, order.data() + mid, last, [&](uint32_t a, uint32_t b) {
          return centroids[a][widest] < centroids[b][widest];
        });
      return mid;
    };
    if (n < 2) return may_be_leaf ? begin : end;
    if (!(extent[widest] > 0)) return may_be_leaf && n <= kMaxLeaf ? begin : median_split();
    // Deep down the tree is degenerate (long thin runs of triangles): halving by count bounds
    // the depth, so that traversal's fixed stack suffices.
    if (d >= kBvhMedianDepth) return may_be_leaf && n <= kMaxLeaf ? begin : median_split();

    float best_cost = kInf;
    int best_axis = -1, best_bin = 0;
    for (int axis = 0; axis < 3; ++axis) {
      float lo = centroid_box.lo[axis], ext = extent[axis];
      if (!(ext > 0)) continue;
      float scale = kBins / ext;
      Bounds3 bin_box[kBins];
      uint32_t bin_count[kBins] = {};
      for (uint32_t i = begin; i < end; ++i) {
        uint32_t t = order[i];
        int b = std::min(kBins - 1, int((centroids[t][axis] - lo) * scale));
        bin_count[b]++;
        bin_box[b].expand(boxes[t]);
      }
      // Sweep from the right, then evaluate each plane between bins b and b + 1 from the left.
      float right_area[kBins];
      uint32_t right_count[kBins];
      Bounds3 acc;
      uint32_t cnt = 0;
      for (int b = kBins - 1; b > 0; --b) {
        acc.expand(bin_box[b]);
        cnt += bin_count[b];
        right_area[b] = half_area(acc);
        right_count[b] = cnt;
      }
      acc = Bounds3{};
      cnt = 0;
      for (int b = 0; b < kBins - 1; ++b) {
        acc.expand(bin_box[b]);
        cnt += bin_count[b];
        if (cnt == 0 || right_count[b + 1] == 0) continue;
        float cost = half_area(acc) * float(cnt) + right_area[b + 1] * float(right_count[b + 1]);
        if (cost < best_cost) {
          best_cost = cost;
          best_axis = axis;
          best_bin = b;
        }
      }
    }
    if (best_axis < 0) return may_be_leaf && n <= kMaxLeaf ? begin : median_split();
    Bounds3 box;
    for (uint32_t i = begin; i < end; ++i) box.expand(boxes[order[i]]);
    float area = half_area(box);
    if (may_be_leaf && area > 0 && kNodeCost + best_cost / area >= float(n)) return begin;
    float lo = centroid_box.lo[best_axis], scale = kBins / extent[best_axis];
    auto* mid = std::partition(first, last, [&](uint32_t t) {
      return std::min(kBins - 1, int((centroids[t][best_axis] - lo) * scale)) <= best_bin;
    });
    return uint32_t(mid - order.data());
  }
};

}  // namespace

Bvh build_bvh(const Mesh& mesh) {
  auto start = std::chrono::steady_clock::now();
  Bvh bvh;
  bvh.vertex_count = mesh.positions.size();
  bvh.triangle_count = mesh.triangles.size();
  size_t n = mesh.triangles.size();
  if (n >= kBvhLeaf) fail("BVH: {} triangles, more than a BVH holds ({})", n, kBvhLeaf - 1);
  bvh.nodes.resize(std::max<size_t>(1, n));
  Builder b(bvh.nodes);
  b.boxes.resize(n);
  b.centroids.resize(n);
  std::vector<uint8_t> finite(n);
  parallel_for(n, 4096, [&](size_t begin, size_t end) {
    for (size_t t = begin; t < end; ++t) {
      BvhTriangle tri = make_triangle(mesh, uint32_t(t));
      finite[t] = is_finite(tri.p0) && is_finite(tri.p1) && is_finite(tri.p2);
      b.boxes[t] = triangle_bounds(tri);
      b.centroids[t] = b.boxes[t].center();
    }
  });
  b.order.reserve(n);
  for (size_t t = 0; t < n; ++t)
    if (finite[t]) b.order.push_back(uint32_t(t));
  Bounds3 centroid_box;
  for (uint32_t t : b.order) centroid_box.expand(b.centroids[t]);

  b.node_count = 1;
  // The root always splits (one leaf under it at most), so that node 0 exists for traversal.
  uint32_t count = uint32_t(b.order.size());
  b.build_children(0, 0, b.partition(0, count, centroid_box, 0, false), count, 0);
  bvh.nodes.resize(b.node_count.load());
  bvh.depth = b.depth.load();
  if (bvh.depth >= kBvhStackSize)
    fail("BVH: depth {} exceeds the traversal stack ({})", bvh.depth, kBvhStackSize);
  bvh.triangles.resize(b.order.size());
  parallel_for(b.order.size(), 4096, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) bvh.triangles[i] = make_triangle(mesh, b.order[i]);
  });
  bvh.build_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return bvh;
}

void Bvh::refit(const Mesh& mesh) {
  auto start = std::chrono::steady_clock::now();
  if (mesh.positions.size() != vertex_count || mesh.triangles.size() != triangle_count)
    fail("BVH refit: the mesh has {} vertices and {} triangles, the BVH was built over {} and {}",
         mesh.positions.size(), mesh.triangles.size(), vertex_count, triangle_count);
  parallel_for(triangles.size(), 4096, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) triangles[i] = make_triangle(mesh, triangles[i].tri);
  });
  // Children come after their parents (a node's index is taken before its subtrees are built),
  // so one pass from the last node to the root sees every child's box before its parent's.
  for (size_t k = nodes.size(); k-- > 0;) {
    BvhNode& node = nodes[k];
    for (int side = 0; side < 2; ++side) {
      Bounds3 box;
      if (node.child[side] & kBvhLeaf) {
        uint32_t first = node.child[side] & ~kBvhLeaf;
        for (uint32_t i = first; i < first + node.count[side]; ++i)
          box.expand(triangle_bounds(triangles[i]));
        if (node.count[side] == 0) box = Bounds3{Vec3(0), Vec3(0)};
      } else {
        const BvhNode& c = nodes[node.child[side]];
        box = merge(c.bounds(0), c.bounds(1));
      }
      node.set_bounds(side, box);
    }
  }
  build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace rll
