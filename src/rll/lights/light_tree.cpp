#include "rll/lights/light_tree.h"

#include <algorithm>
#include <atomic>

#include "rll/core/error.h"
#include "rll/core/parallel.h"
#include "rll/scene/scene.h"

namespace rll {

namespace {

// Spreads the low 21 bits of v so that two zero bits separate each.
uint64_t spread_bits(uint64_t v) {
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffull;
  v = (v | v << 16) & 0x1f0000ff0000ffull;
  v = (v | v << 8) & 0x100f00f00f00f00full;
  v = (v | v << 4) & 0x10c30c30c30c30c3ull;
  v = (v | v << 2) & 0x1249249249249249ull;
  return v;
}

uint64_t morton3(const Vec3& unit) {
  auto q = [](float x) { return uint64_t(clamp(x, 0.0f, 1.0f) * 2097151.0f); };
  return spread_bits(q(unit.x)) << 2 | spread_bits(q(unit.y)) << 1 | spread_bits(q(unit.z));
}

struct Builder {
  std::vector<LightTreeNode>& nodes;
  const std::vector<LightBounds>& leaf_bounds;  // in tree order
  const std::vector<uint64_t>& codes;           // Morton codes of finite lights, tree order
  uint32_t finite_count;
  std::atomic<uint32_t> max_depth{0};

  // Split point of [b, e): finite/infinite boundary at the top, then the highest differing
  // Morton bit, or the middle where codes are equal (or lights are infinite).
  uint32_t split(uint32_t b, uint32_t e) const {
    if (b < finite_count && e > finite_count) return finite_count;
    if (b >= finite_count) return b + (e - b) / 2;
    uint64_t first = codes[b], last = codes[e - 1];
    if (first == last) return b + (e - b) / 2;
    int bit = 63 - __builtin_clzll(first ^ last);
    uint64_t mask = uint64_t(1) << bit;
    // First index in [b, e) whose code has `bit` set (codes are sorted).
    uint32_t lo = b, hi = e - 1;
    while (lo < hi) {
      uint32_t mid = lo + (hi - lo) / 2;
      if (codes[mid] & mask) hi = mid;
      else lo = mid + 1;
    }
    return lo;
  }

  // Node `index` covers [b, e); its descendants occupy slots from `desc`: the two children at
  // desc and desc+1, then the left child's descendants, then the right child's.
  void build(uint32_t index, uint32_t parent, uint32_t desc, uint32_t b, uint32_t e, uint32_t depth) {
    LightTreeNode& n = nodes[index];
    n.begin = b;
    n.end = e;
    n.parent = parent;
    if (e - b == 1) {
      n.child = 0;
      n.bounds = leaf_bounds[b];
      uint32_t d = max_depth.load();
      while (depth > d && !max_depth.compare_exchange_weak(d, depth)) {}
      return;
    }
    uint32_t m = split(b, e);
    n.child = desc;
    uint32_t left_desc = desc + 2, right_desc = left_desc + 2 * (m - b) - 2;
    auto left = [&] { build(desc, index, left_desc, b, m, depth + 1); };
    auto right = [&] { build(desc + 1, index, right_desc, m, e, depth + 1); };
    if (e - b > 8192) parallel_invoke(left, right);
    else {
      left();
      right();
    }
    n.bounds = merge(nodes[desc].bounds, nodes[desc + 1].bounds);
  }
};

}  // namespace

LightTree LightTree::build(Scene& scene) {
  const size_t n = scene.lights.size();
  if (n == 0) fail("{}: cannot build a light tree without lights", scene.source);
  if (n >= (size_t(1) << 31)) fail("{}: too many lights ({})", scene.source, n);

  // Order: finite lights by Morton code of their centroid, then lights without position.
  Bounds3 centroids;
  for (const auto& l : scene.lights)
    if (l.has_position()) centroids.expand(l.centroid());
  Vec3 extent = max(centroids.diagonal(), Vec3(1e-20f));
  std::vector<std::pair<uint64_t, uint32_t>> keys(n);
  parallel_for(n, 4096, [&](size_t b, size_t e) {
    for (size_t i = b; i < e; ++i) {
      const Light& l = scene.lights[i];
      uint64_t code = l.has_position() ? morton3((l.centroid() - centroids.lo) / extent)
                                       : ~uint64_t(0);  // after every finite light
      keys[i] = {code, uint32_t(i)};
    }
  });
  parallel_sort(keys);
  std::vector<uint32_t> order(n);
  std::vector<uint64_t> codes(n);
  uint32_t finite = 0;
  for (size_t i = 0; i < n; ++i) {
    order[i] = keys[i].second;
    codes[i] = keys[i].first;
    if (scene.lights[order[i]].has_position()) ++finite;
  }
  keys = {};
  scene.reorder_lights(order);

  std::vector<LightBounds> leaf_bounds(n);
  parallel_for(n, 4096, [&](size_t b, size_t e) {
    for (size_t i = b; i < e; ++i) leaf_bounds[i] = light_bounds(scene.lights[i]);
  });

  LightTree tree;
  tree.m_nodes.resize(2 * n - 1);
  Builder builder{tree.m_nodes, leaf_bounds, codes, finite};
  builder.build(kRoot, kNone, 1, 0, uint32_t(n), 0);
  tree.m_depth = builder.max_depth.load();

  tree.m_leaf_of.assign(n, kNone);
  parallel_for(tree.m_nodes.size(), 4096, [&](size_t b, size_t e) {
    for (size_t i = b; i < e; ++i)
      if (tree.m_nodes[i].is_leaf()) tree.m_leaf_of[tree.m_nodes[i].begin] = uint32_t(i);
  });
  tree.prepare_importance();
  if (finite == n) tree.m_finite_root = kRoot;
  else if (finite == 0) tree.m_infinite_root = kRoot;
  else {
    tree.m_finite_root = tree.m_nodes[kRoot].child;
    tree.m_infinite_root = tree.m_nodes[kRoot].child + 1;
  }
  return tree;
}

void LightTree::refit(const std::vector<Light>& lights) {
  if (lights.size() != m_leaf_of.size()) fail("light tree refit: light count changed");
  parallel_for(lights.size(), 4096, [&](size_t b, size_t e) {
    for (size_t i = b; i < e; ++i) m_nodes[m_leaf_of[i]].bounds = light_bounds(lights[i]);
  });
  // Children always follow their parent in the array: a reverse sweep sees children first.
  for (size_t i = m_nodes.size(); i-- > 0;) {
    LightTreeNode& nd = m_nodes[i];
    if (!nd.is_leaf()) nd.bounds = merge(m_nodes[nd.child].bounds, m_nodes[nd.child + 1].bounds);
  }
  prepare_importance();
}

void LightTree::prepare_importance() {
  m_fast.resize(m_nodes.size());
  parallel_for(m_nodes.size(), 4096, [&](size_t b, size_t e) {
    for (size_t i = b; i < e; ++i) m_fast[i] = importance_bounds(m_nodes[i].bounds);
  });
}

void build_light_tree(Scene& scene) {
  scene.light_tree = std::make_shared<LightTree>(LightTree::build(scene));
}

}  // namespace rll
