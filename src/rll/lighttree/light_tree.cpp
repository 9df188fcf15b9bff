#include "rll/lighttree/light_tree.h"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cmath>

#include "rll/core/error.h"
#include "rll/core/parallel.h"
#include "rll/scene/scene.h"

namespace rll {

namespace {

// Subtrees with more lights than this are built (and fitted) as two parallel tasks.
constexpr uint32_t kParallelLights = 4096;
// SAOH splits stop at this depth; below it, median splits end every subtree within log2(n) more
// levels, so the tree stays within kMaxTreeDepth (2 group levels + 160 + 32 < 256).
constexpr uint32_t kSaohMaxDepth = 160;
constexpr int kBins = 12;

LightGroup group_of(const Scene& scene, const Light& l) {
  if (!l.has_position()) return LightGroup::Directional;
  if (l.type == LightType::Triangle && scene.is_sky_triangle(l.triangle)) return LightGroup::Dome;
  return LightGroup::Local;
}

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

// What the builders need of one light, moved around as the build partitions the lights.
struct Prim {
  Bounds3 box;
  Vec3 centroid;  // of the box (SAOH) or of the light (LBVH)
  Vec3 axis;
  float cos_o = 1, sin_o = 0, cos_e = 0, power = 0;
  uint32_t light = 0;
};

// Cosine of the half-angle of the smallest cone around unit axis w that holds the cone
// (a, theta_a): cos(angle(w, a) + theta_a), or -1 where that exceeds pi.
inline float cone_cos_about(const Vec3& w, const Vec3& a, float cos_a, float sin_a) {
  float cd = clamp(dot(w, a), -1.0f, 1.0f);
  if (cd < -cos_a) return -1;
  return cd * cos_a - safe_sqrt(1 - cd * cd) * sin_a;
}

// Conty & Kulla's orientation measure: the cosine-weighted solid angle reached by emitters whose
// normals lie within theta_o of an axis and emit within theta_e of their normal,
// 2 pi [ integral_0^theta_o sin t dt + integral_theta_o^theta_w cos(t - theta_o) sin t dt ],
// theta_w = min(theta_o + theta_e, pi).
float orientation_measure(float cos_o, float cos_e) {
  const float sin_o = safe_sqrt(1 - cos_o * cos_o);
  if (cos_e == 0 && cos_o >= 0)  // area lights within a hemisphere: theta_w = theta_o + pi/2
    return 2 * kPi * (1 - cos_o) + kPi * cos_o + 0.5f * kPi * kPi * sin_o;
  const float theta_o = safe_acos(cos_o), theta_e = safe_acos(cos_e);
  const float theta_w = std::min(theta_o + theta_e, kPi);
  return 2 * kPi * (1 - cos_o) + 0.5f * kPi * (cos_o - std::cos(2 * theta_w - theta_o)) +
         kPi * (theta_w - theta_o) * sin_o;
}

// Boxes of a node's lights and of their centroids.
struct Extent {
  Bounds3 box, cbox;
};

Extent extent_of(const Prim* prims, uint32_t b, uint32_t e) {
  Extent x;
  for (uint32_t i = b; i < e; ++i) {
    x.box.expand(prims[i].box);
    x.cbox.expand(prims[i].centroid);
  }
  return x;
}

// One SAOH bin: the lights whose centroids fall in a slab of the node's centroid box.
struct Bin {
  Bounds3 box;
  Vec3 axis_sum;  // of the unit axes of the lights with power
  float power = 0;
  float cos_e = 1;
  float cos_o = 1, sin_o = 0;  // cone around normalize(axis_sum) holding the lights' cones
  Vec3 axis{0, 0, 1};
  uint32_t count = 0;
  bool lit = false;  // has a light with power
};

// Surface area of a box whose sides are at least `floor` long: points and segments of lights
// still cost something, so that the heuristic separates them.
inline double surface_area(const Bounds3& b, float floor) {
  if (b.empty()) return 0;
  Vec3 d = max(b.diagonal(), Vec3(floor));
  return 2 * (double(d.x) * d.y + double(d.y) * d.z + double(d.z) * d.x);
}

struct Builder {
  std::vector<LightTreeNode>& nodes;
  std::vector<Prim>& prims;            // in tree order as the build partitions them
  const std::vector<uint64_t>& codes;  // LBVH: Morton codes in tree order (within each group)
  uint32_t group_begin[kLightGroups], group_end[kLightGroups];
  TreeBuild method;
  uint32_t (&group_root)[kLightGroups];
  std::atomic<uint32_t> max_depth{0};

  // Number of groups with lights in [b, e), and the first one.
  int groups_in(uint32_t b, uint32_t e, int& first) const {
    int count = 0;
    first = -1;
    for (int g = 0; g < kLightGroups; ++g)
      if (group_begin[g] < group_end[g] && group_begin[g] < e && group_end[g] > b) {
        if (first < 0) first = g;
        ++count;
      }
    return count;
  }

  uint32_t lbvh_split(uint32_t b, uint32_t e) const {
    uint64_t first = codes[b], last = codes[e - 1];
    if (first == last) return b + (e - b) / 2;
    int bit = 63 - __builtin_clzll(first ^ last);
    uint64_t mask = uint64_t(1) << bit;
    // First index in [b, e) whose code has `bit` set (codes are sorted).
    uint32_t lo = b, hi = e - 1;
    while (lo < hi) {
      uint32_t mid = lo + (hi - lo) / 2;
      if (codes[mid] & mask)
        hi = mid;
      else
        lo = mid + 1;
    }
    return lo;
  }

  // Median split along the widest centroid axis.
  uint32_t median_split(uint32_t b, uint32_t e, const Extent& x, Extent& left, Extent& right) {
    Vec3 d = x.cbox.diagonal();
    int axis = d.x >= d.y && d.x >= d.z ? 0 : (d.y >= d.z ? 1 : 2);
    uint32_t m = b + (e - b) / 2;
    std::nth_element(
        prims.begin() + b, prims.begin() + m, prims.begin() + e,
        [axis](const Prim& p, const Prim& q) { return p.centroid[axis] < q.centroid[axis]; });
    left = extent_of(prims.data(), b, m);
    right = extent_of(prims.data(), m, e);
    return m;
  }

  // The binned surface-area-orientation heuristic (Conty & Kulla 2018): over 12 slabs of the
  // centroid box along each axis (fewer for fewer lights), the split minimising, summed over both
  // sides, power x M_Omega(cone) x surface area x the node's aspect along the split axis.
  uint32_t saoh_split(uint32_t b, uint32_t e, const Extent& x, Extent& left, Extent& right) {
    const int nbins = int(std::min<uint32_t>(kBins, e - b));
    const Vec3 lo = x.cbox.lo, cd = x.cbox.diagonal();
    const Vec3 bd = x.box.diagonal();
    const float max_extent = max_component(bd);
    const float floor = 1e-3f * max_extent;
    float scale[3];
    bool usable[3];
    for (int a = 0; a < 3; ++a) {
      scale[a] = float(nbins) / cd[a];
      usable[a] = cd[a] > 0 && std::isfinite(scale[a]);
    }
    auto bin_of = [&](const Prim& p, int a) {
      return std::min(nbins - 1, int((p.centroid[a] - lo[a]) * scale[a]));
    };

    // Scratch reused by every node a thread builds: most nodes hold a few lights, and clearing
    // all bins would cost them more than binning.
    thread_local Bin scratch[3][kBins];
    auto& bins = scratch;
    for (int a = 0; a < 3; ++a)
      for (int k = 0; k < nbins; ++k) bins[a][k] = Bin{};
    float node_power = 0;
    for (uint32_t i = b; i < e; ++i) {
      const Prim& p = prims[i];
      node_power += p.power;
      for (int a = 0; a < 3; ++a) {
        if (!usable[a]) continue;
        Bin& bin = bins[a][bin_of(p, a)];
        bin.box.expand(p.box);
        ++bin.count;
        if (p.power > 0) {
          bin.lit = true;
          bin.power += p.power;
          bin.axis_sum += p.axis;
          bin.cos_e = std::min(bin.cos_e, p.cos_e);
        }
      }
    }
    // Without power anywhere the orientation means nothing: a plain SAH by light count.
    const bool by_count = !(node_power > 0);
    if (!by_count) {
      for (int a = 0; a < 3; ++a)
        for (int k = 0; k < nbins; ++k) {
          Bin& bin = bins[a][k];
          float len = length(bin.axis_sum);
          if (bin.lit && len > 1e-6f) bin.axis = bin.axis_sum / len;
        }
      for (uint32_t i = b; i < e; ++i) {
        const Prim& p = prims[i];
        if (!(p.power > 0)) continue;
        for (int a = 0; a < 3; ++a) {
          if (!usable[a]) continue;
          Bin& bin = bins[a][bin_of(p, a)];
          bin.cos_o = std::min(bin.cos_o, cone_cos_about(bin.axis, p.axis, p.cos_o, p.sin_o));
        }
      }
      for (int a = 0; a < 3; ++a)
        for (int k = 0; k < nbins; ++k) bins[a][k].sin_o = safe_sqrt(1 - sqr(bins[a][k].cos_o));
    }

    // The splits between consecutive non-empty bins, each side's cost from prefix and suffix
    // sums; the cone of a side is the one around the mean of its bins' axes that holds them all.
    struct Side {
      Bounds3 box;
      Vec3 axis_sum;
      float power = 0, cos_e = 1;
      uint32_t count = 0;
      bool lit = false;
      void add(const Bin& bin) {
        box.expand(bin.box);
        count += bin.count;
        if (bin.lit) {
          lit = true;
          power += bin.power;
          axis_sum += bin.axis_sum;
          cos_e = std::min(cos_e, bin.cos_e);
        }
      }
    };
    thread_local Side suffix[kBins];  // suffix[j]: the bins idx[j..nb)
    double best = HUGE_VAL;
    int best_axis = -1, best_k = -1;
    for (int a = 0; a < 3; ++a) {
      if (!usable[a]) continue;
      const Bin* bs = bins[a];
      int idx[kBins], nb = 0;
      for (int k = 0; k < nbins; ++k)
        if (bs[k].count > 0) idx[nb++] = k;
      suffix[nb - 1] = Side{};
      suffix[nb - 1].add(bs[idx[nb - 1]]);
      for (int j = nb - 1; j-- > 0;) {
        suffix[j] = suffix[j + 1];
        suffix[j].add(bs[idx[j]]);
      }
      const double kr = bd[a] > 0 ? double(max_extent) / bd[a] : 1.0;
      auto cost = [&](const Side& side, int j0, int j1) {
        const double area = surface_area(side.box, floor) * kr;
        if (by_count) return side.count * area;
        if (!side.lit) return 0.0;
        float len = length(side.axis_sum);
        Vec3 w = len > 1e-6f ? side.axis_sum / len : Vec3(0, 0, 1);
        float cos_o = 1;
        for (int j = j0; j < j1; ++j) {
          const Bin& bin = bs[idx[j]];
          if (bin.lit) cos_o = std::min(cos_o, cone_cos_about(w, bin.axis, bin.cos_o, bin.sin_o));
        }
        return double(side.power) * orientation_measure(cos_o, side.cos_e) * area;
      };
      Side prefix;  // the bins idx[0..j]
      for (int j = 0; j + 1 < nb; ++j) {
        prefix.add(bs[idx[j]]);
        double c = cost(prefix, 0, j + 1) + cost(suffix[j + 1], j + 1, nb);
        if (c < best) {
          best = c;
          best_axis = a;
          best_k = idx[j];
        }
      }
    }
    if (best_axis < 0) {  // every centroid in one place: any split is as good
      uint32_t m = b + (e - b) / 2;
      left = extent_of(prims.data(), b, m);
      right = extent_of(prims.data(), m, e);
      return m;
    }
    auto mid = std::partition(prims.begin() + b, prims.begin() + e,
                              [&](const Prim& p) { return bin_of(p, best_axis) <= best_k; });
    uint32_t m = uint32_t(mid - prims.begin());
    if (m == b || m == e) return median_split(b, e, x, left, right);  // cannot happen; stay safe
    left = right = Extent{};
    for (int k = 0; k < nbins; ++k) (k <= best_k ? left : right).box.expand(bins[best_axis][k].box);
    for (uint32_t i = b; i < m; ++i) left.cbox.expand(prims[i].centroid);
    for (uint32_t i = m; i < e; ++i) right.cbox.expand(prims[i].centroid);
    return m;
  }

  // Node `index` covers [b, e); its descendants occupy slots from `desc`: the two children at
  // desc and desc+1, then the left child's descendants, then the right child's. `x` is the
  // extent of [b, e) where the node lies inside a SAOH-built group.
  void build(uint32_t index, uint32_t parent, uint32_t desc, uint32_t b, uint32_t e, uint32_t depth,
             const Extent& x) {
    LightTreeNode& n = nodes[index];
    n.begin = b;
    n.end = e;
    n.parent = parent;
    int g = -1;
    const int groups = groups_in(b, e, g);
    if (groups == 1 && b == group_begin[g] && e == group_end[g]) group_root[g] = index;
    if (e - b == 1) {
      n.child = 0;
      uint32_t d = max_depth.load();
      while (depth > d && !max_depth.compare_exchange_weak(d, depth)) {
      }
      return;
    }
    uint32_t m;
    Extent left, right;
    if (groups > 1) {  // a group node: split after the first group in it
      n.group = true;
      m = group_end[g];
      if (method == TreeBuild::Saoh) {
        left = extent_of(prims.data(), b, m);
        right = extent_of(prims.data(), m, e);
      }
    } else if (g == int(LightGroup::Directional)) {
      m = b + (e - b) / 2;
    } else if (method == TreeBuild::Lbvh) {
      m = lbvh_split(b, e);
    } else if (e - b == 2) {  // nothing to choose
      m = b + 1;
    } else if (depth >= kSaohMaxDepth) {
      m = median_split(b, e, x, left, right);
    } else {
      m = saoh_split(b, e, x, left, right);
    }
    n.child = desc;
    uint32_t left_desc = desc + 2, right_desc = left_desc + 2 * (m - b) - 2;
    auto build_left = [&] { build(desc, index, left_desc, b, m, depth + 1, left); };
    auto build_right = [&] { build(desc + 1, index, right_desc, m, e, depth + 1, right); };
    if (e - b > kParallelLights)
      parallel_invoke(build_left, build_right);
    else {
      build_left();
      build_right();
    }
  }
};

// Fits the bounds of the inner nodes under `index` to their leaves, children first.
void fit(std::vector<LightTreeNode>& nodes, uint32_t index) {
  LightTreeNode& n = nodes[index];
  if (n.is_leaf()) return;
  auto left = [&] { fit(nodes, n.child); };
  auto right = [&] { fit(nodes, n.child + 1); };
  if (n.light_count() > kParallelLights)
    parallel_invoke(left, right);
  else {
    left();
    right();
  }
  n.bounds = merge(nodes[n.child].bounds, nodes[n.child + 1].bounds);
}

}  // namespace

LightTree LightTree::build(Scene& scene, TreeBuild method) {
  const size_t n = scene.lights.size();
  if (n == 0) fail("{}: cannot build a light tree without lights", scene.source);
  if (n >= (size_t(1) << 31)) fail("{}: too many lights ({})", scene.source, n);

  // Lights in group order (local, dome, directional), each group keeping the scene's order.
  std::vector<Prim> prims(n);
  uint32_t group_size[kLightGroups] = {0, 0, 0};
  for (const Light& l : scene.lights) ++group_size[int(group_of(scene, l))];
  uint32_t group_begin[kLightGroups], group_end[kLightGroups], next[kLightGroups];
  for (int g = 0, at = 0; g < kLightGroups; ++g) {
    group_begin[g] = next[g] = uint32_t(at);
    at += int(group_size[g]);
    group_end[g] = uint32_t(at);
  }
  std::vector<uint32_t> slot(n);
  for (size_t i = 0; i < n; ++i) slot[i] = next[int(group_of(scene, scene.lights[i]))]++;
  parallel_for(n, 4096, [&](size_t b, size_t e) {
    for (size_t i = b; i < e; ++i) {
      const Light& l = scene.lights[i];
      const LightBounds lb = light_bounds(l);
      Prim& p = prims[slot[i]];
      p.box = lb.box;
      p.centroid =
          method == TreeBuild::Lbvh ? l.centroid() : (lb.box.empty() ? Vec3(0) : lb.box.center());
      p.axis = lb.axis;
      p.cos_o = lb.cos_theta_o;
      p.sin_o = safe_sqrt(1 - lb.cos_theta_o * lb.cos_theta_o);
      p.cos_e = lb.cos_theta_e;
      p.power = lb.power;
      p.light = uint32_t(i);
    }
  });
  slot = {};

  // LBVH: each finite group sorted by the Morton code of its centroids within the group's box.
  std::vector<uint64_t> codes;
  if (method == TreeBuild::Lbvh) {
    codes.assign(n, 0);
    for (int g : {int(LightGroup::Local), int(LightGroup::Dome)}) {
      const uint32_t b = group_begin[g], e = group_end[g];
      if (b == e) continue;
      Bounds3 cb;
      for (uint32_t i = b; i < e; ++i) cb.expand(prims[i].centroid);
      const Vec3 extent = max(cb.diagonal(), Vec3(1e-20f));
      std::vector<std::pair<uint64_t, uint32_t>> keys(e - b);
      parallel_for(e - b, 4096, [&](size_t kb, size_t ke) {
        for (size_t k = kb; k < ke; ++k)
          keys[k] = {morton3((prims[b + k].centroid - cb.lo) / extent), uint32_t(k)};
      });
      parallel_sort(keys);
      std::vector<Prim> sorted(e - b);
      for (size_t k = 0; k < keys.size(); ++k) {
        sorted[k] = prims[b + keys[k].second];
        codes[b + k] = keys[k].first;
      }
      std::copy(sorted.begin(), sorted.end(), prims.begin() + b);
    }
  }

  LightTree tree;
  tree.m_method = method;
  tree.m_nodes.resize(2 * n - 1);
  Builder builder{tree.m_nodes, prims, codes, {}, {}, method, tree.m_group_root};
  std::copy(group_begin, group_begin + kLightGroups, builder.group_begin);
  std::copy(group_end, group_end + kLightGroups, builder.group_end);
  const Extent root_extent =
      method == TreeBuild::Saoh ? extent_of(prims.data(), 0, uint32_t(n)) : Extent{};
  builder.build(kRoot, kNone, 1, 0, uint32_t(n), 0, root_extent);
  tree.m_depth = builder.max_depth.load();

  std::vector<uint32_t> order(n);
  for (size_t i = 0; i < n; ++i) order[i] = prims[i].light;
  prims = {};
  scene.reorder_lights(order);

  // The dome's triangles are bounded as distant lights: from the scene, each is a narrow cone of
  // directions, which tells a cluster of them from another far better than boxes around p
  // (11% less error on arch-interior without pixels with fireflies). Shading points lie on the
  // scene's geometry, within its bounding sphere (the dome excluded).
  tree.m_dome_begin = group_begin[int(LightGroup::Dome)];
  tree.m_dome_end = group_end[int(LightGroup::Dome)];
  tree.m_dome_frame.center = scene.bounds.center();
  tree.m_dome_frame.reach = scene.radius * (1 + 1e-3f);

  tree.m_leaf_of.assign(n, kNone);
  parallel_for(tree.m_nodes.size(), 4096, [&](size_t b, size_t e) {
    for (size_t i = b; i < e; ++i)
      if (tree.m_nodes[i].is_leaf()) tree.m_leaf_of[tree.m_nodes[i].begin] = uint32_t(i);
  });
  tree.refit(scene.lights);
  return tree;
}

LightBounds LightTree::leaf_bounds(const Light& light, uint32_t index) const {
  if (index >= m_dome_begin && index < m_dome_end) return distant_light_bounds(light, m_dome_frame);
  return light_bounds(light);
}

void LightTree::refit(const std::vector<Light>& lights) {
  if (lights.size() != m_leaf_of.size()) fail("light tree refit: light count changed");
  if (m_dome_begin < m_dome_end) {
    // The least distance from the centre to a dome triangle's plane.
    float distance = kInf;
    for (uint32_t i = m_dome_begin; i < m_dome_end; ++i)
      distance = std::min(distance, std::abs(dot(lights[i].p0 - m_dome_frame.center, lights[i].n)));
    m_dome_frame.distance = distance;
  }
  parallel_for(lights.size(), 4096, [&](size_t b, size_t e) {
    for (size_t i = b; i < e; ++i)
      m_nodes[m_leaf_of[i]].bounds = leaf_bounds(lights[i], uint32_t(i));
  });
  fit(m_nodes, kRoot);
  prepare_importance();
}

namespace {

// Writes the steps of a tree (LightTreeView::steps) with node i's importance bounds
// bounds_of(i). Every node owns one slot of them, steps[(i + 1) / 2] side (i + 1) % 2 (its
// bounds, first child and range: the root's is step 0's second side), so the nodes fill their
// slots in parallel and check the layout as they go; then the group nodes, all above the group
// roots, mark their steps.
template <typename BoundsOf>
void write_steps(View<const LightTreeNode> nodes, View<TreeStep> steps, const BoundsOf& bounds_of) {
  if (steps.size != (nodes.size + 1) / 2)
    fail("light tree steps: {} steps for {} nodes", steps.size, nodes.size);
  if (nodes.size == 0) return;
  if (nodes.size % 2 == 0)
    fail("light tree steps: {} nodes (a tree of one light per leaf has an odd count)", nodes.size);
  // Step 0's first side belongs to no node.
  steps[0].bounds[0] = ImportanceBounds{};
  steps[0].child[0] = steps[0].begin[0] = steps[0].end[0] = 0;
  std::atomic<size_t> bad{nodes.size};  // the first node whose children break the layout
  parallel_for(nodes.size, 4096, [&](size_t b, size_t e) {
    for (size_t i = b; i < e; ++i) {
      const LightTreeNode& n = nodes[i];
      if (!n.is_leaf() && (n.child % 2 != 1 || n.child + 1 >= nodes.size)) {
        size_t first = bad.load();
        while (i < first && !bad.compare_exchange_weak(first, i)) {
        }
      }
      TreeStep& s = steps[(i + 1) >> 1];
      const size_t side = (i + 1) & 1;
      s.bounds[side] = bounds_of(i);
      s.child[side] = n.child;
      s.begin[side] = n.begin;
      s.end[side] = n.end;
    }
  });
  if (const size_t i = bad.load(); i < nodes.size)
    fail("light tree steps: node {} has its children at {} (an odd index is needed)", i,
         nodes[i].child);
  const auto mark = [&](const auto& self, size_t i) -> void {
    if (!nodes[i].group) return;
    steps[(nodes[i].child + 1) >> 1].bounds[0].flags |= TreeStep::kGroupStep;
    self(self, nodes[i].child);
    self(self, nodes[i].child + 1);
  };
  mark(mark, LightTree::kRoot);
}

}  // namespace

void LightTree::prepare_importance() {
  // In place: views taken before a refit stay valid.
  m_steps.resize((m_nodes.size() + 1) / 2);
  write_steps(view_of(m_nodes), view_of(m_steps), [&](size_t i) {
    ImportanceBounds b = importance_bounds(m_nodes[i].bounds, &m_dome_frame);
    if (m_nodes[i].group) b.flags |= ImportanceBounds::kGroup;
    return b;
  });
}

void tree_steps(View<const LightTreeNode> nodes, View<const ImportanceBounds> bounds,
                View<TreeStep> steps) {
  if (bounds.size != nodes.size)
    fail("light tree steps: {} bounds for {} nodes", bounds.size, nodes.size);
  write_steps(nodes, steps, [&](size_t i) { return bounds[i]; });
}

LightTree build_light_tree(Scene& scene) {
  LightTree tree = LightTree::build(scene);
  // Said once, as the load's warnings are (the scene layer below cannot weigh lights).
  if (std::string w = capped_power_warning(scene);
      !w.empty() &&
      std::find(scene.warnings.begin(), scene.warnings.end(), w) == scene.warnings.end()) {
    fmt::print(stderr, "rll: warning: {}\n", w);
    scene.warnings.push_back(std::move(w));
  }
  return tree;
}

}  // namespace rll
