// The light tree's structure and bounds: every build keeps the invariants the samplers and RLL's
// cuts rely on (contiguous ranges, children adjacent and after their parent, one light per leaf,
// bounded depth), the sky dome, directional and local lights sit in their own subtrees with
// equal shares for the groups that can contribute, and bounds stay conservative after a refit.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "rll/accel/accel.h"
#include "rll/core/rng.h"
#include "rll/lights/tree_sampler.h"
#include "rll/lighttree/descent.h"
#include "rll/lighttree/light_tree.h"
#include "rll/session/session.h"
#include "rll/scene/builder.h"
#include "rll/scene/builtin.h"
#include "support/sampler_contexts.h"
#include "support/test_support.h"

using namespace rll;

namespace {

Scene builtin(const std::string& name, void (*edit)(Scene&) = nullptr) {
  Scene s = make_builtin_scene(name);
  s.width = 16;
  s.height = 12;
  if (edit) edit(s);
  s.finalize();
  return s;
}

// cornell-boxes-room with a sun: local lamps, the sky dome and a directional light.
void add_sun(Scene& s) {
  s.lights.push_back(make_directional_light(Vec3(0.3f, 1.0f, 0.2f), Rgb(5.0f)));
}

bool is_dome(const Scene& s, const Light& l) {
  return l.type == LightType::Triangle && s.is_sky_triangle(l.triangle);
}

LightGroup group_of(const Scene& s, const Light& l) {
  if (!l.has_position()) return LightGroup::Directional;
  return is_dome(s, l) ? LightGroup::Dome : LightGroup::Local;
}

// Angle between two directions, in double precision.
double angle(const Vec3& a, const Vec3& b) {
  const double ax = a.x, ay = a.y, az = a.z, bx = b.x, by = b.y, bz = b.z;
  const double cx = ay * bz - az * by, cy = az * bx - ax * bz, cz = ax * by - ay * bx;
  return std::atan2(std::sqrt(cx * cx + cy * cy + cz * cz), ax * bx + ay * by + az * bz);
}

// A node's importance bounds as the descents read them (the view's steps) against the node's own
// bounds (distant lights' need the tree's private frame: their flags only).
void expect_importance_of(const LightTreeView& v, const LightTree& tree, uint32_t i) {
  const LightTreeNode& nd = tree.node(i);
  const ImportanceBounds& b = v.bounds(i);
  EXPECT_EQ((b.flags & ImportanceBounds::kGroup) != 0, nd.group) << "node " << i;
  if (nd.bounds.distant) {
    EXPECT_NE(b.flags & ImportanceBounds::kDistant, 0u) << "node " << i;
    return;
  }
  const ImportanceBounds want = importance_bounds(nd.bounds);
  EXPECT_EQ(b.power, want.power) << "node " << i;
  EXPECT_EQ(b.radius2, want.radius2) << "node " << i;
  EXPECT_EQ(b.cos_o, want.cos_o) << "node " << i;
  EXPECT_EQ(b.cos_e, want.cos_e) << "node " << i;
  EXPECT_EQ(b.center.x, want.center.x) << "node " << i;
  EXPECT_EQ(b.center.z, want.center.z) << "node " << i;
  EXPECT_EQ(b.flags & ~(ImportanceBounds::kGroup | TreeStep::kGroupStep), want.flags)
      << "node " << i;
}

// The descents' steps say what the nodes say: each inner node's step holds its children's
// importance bounds, first children and light ranges, and whether it is a group node.
void expect_steps_mirror_nodes(const LightTree& tree) {
  const LightTreeView v = tree.view();
  ASSERT_EQ(v.steps.size, (tree.node_count() + 1) / 2);
  expect_importance_of(v, tree, LightTree::kRoot);
  for (uint32_t i = 0; i < tree.node_count(); ++i) {
    const LightTreeNode& nd = tree.node(i);
    if (nd.is_leaf()) continue;
    const TreeStep& step = v.step(nd.child);
    EXPECT_EQ(step.group(), nd.group) << "node " << i;
    for (uint32_t j = 0; j < 2; ++j) {
      const LightTreeNode& c = tree.node(nd.child + j);
      EXPECT_EQ(step.child[j], c.child) << "node " << i;
      EXPECT_EQ(step.begin[j], c.begin) << "node " << i;
      EXPECT_EQ(step.end[j], c.end) << "node " << i;
      EXPECT_EQ(&step.bounds[j], &v.bounds(nd.child + j)) << "node " << i;
      expect_importance_of(v, tree, nd.child + j);
    }
  }
}

// The structural invariants, for any tree over `lights`.
void expect_tree_invariants(const LightTree& tree, const std::vector<Light>& lights) {
  const uint32_t n = uint32_t(lights.size());
  ASSERT_EQ(tree.light_count(), n);
  ASSERT_EQ(tree.node_count(), size_t(2) * n - 1);
  const LightTreeNode& root = tree.node(LightTree::kRoot);
  EXPECT_EQ(root.begin, 0u);
  EXPECT_EQ(root.end, n);
  EXPECT_EQ(root.parent, LightTree::kNone);
  std::vector<int> depth(tree.node_count(), -1), leaves_of_light(n, 0);
  depth[LightTree::kRoot] = 0;
  int max_depth = 0;
  std::vector<int> reached(tree.node_count(), 0);
  reached[LightTree::kRoot] = 1;
  for (uint32_t i = 0; i < tree.node_count(); ++i) {
    const LightTreeNode& nd = tree.node(i);
    ASSERT_EQ(reached[i], 1) << "node " << i << " is not the child of exactly one node before it";
    ASSERT_LT(nd.begin, nd.end) << "node " << i;
    if (nd.is_leaf()) {
      EXPECT_EQ(nd.light_count(), 1u) << "leaf " << i;
      EXPECT_FALSE(nd.group) << "leaf " << i;
      ++leaves_of_light[nd.begin];
      EXPECT_EQ(tree.leaf_of(nd.begin), i);
      max_depth = std::max(max_depth, depth[i]);
      continue;
    }
    // Children adjacent, after their parent, splitting the range into two non-empty parts.
    ASSERT_GT(nd.child, i) << "node " << i;
    ASSERT_LT(nd.child + 1, tree.node_count());
    const LightTreeNode &a = tree.node(nd.child), &b = tree.node(nd.child + 1);
    EXPECT_EQ(a.parent, i);
    EXPECT_EQ(b.parent, i);
    EXPECT_EQ(a.begin, nd.begin) << "node " << i;
    EXPECT_EQ(a.end, b.begin) << "node " << i;
    EXPECT_EQ(b.end, nd.end) << "node " << i;
    ++reached[nd.child];
    ++reached[nd.child + 1];
    depth[nd.child] = depth[nd.child + 1] = depth[i] + 1;
    EXPECT_NEAR(nd.bounds.power, a.bounds.power + b.bounds.power, 1e-4f * nd.bounds.power + 1e-6f);
  }
  for (uint32_t l = 0; l < n; ++l) EXPECT_EQ(leaves_of_light[l], 1) << "light " << l;
  expect_steps_mirror_nodes(tree);
  EXPECT_EQ(int(tree.depth()), max_depth);
  EXPECT_LT(int(tree.depth()), kMaxTreeDepth);
}

// Every node's bounds hold its lights: boxes, power, and the cone of emitter normals (finite
// lights) or of directions towards the lights (directional lights).
void expect_conservative_bounds(const LightTree& tree, const std::vector<Light>& lights) {
  for (uint32_t i = 0; i < tree.node_count(); ++i) {
    const LightTreeNode& nd = tree.node(i);
    double power = 0;
    for (uint32_t l = nd.begin; l < nd.end; ++l) {
      const LightBounds lb = light_bounds(lights[l]);
      power += lb.power;
      if (lb.box.empty()) continue;
      EXPECT_TRUE(nd.bounds.box.contains(lb.box.lo) && nd.bounds.box.contains(lb.box.hi))
          << "node " << i;
      if (nd.bounds.distant || nd.bounds.infinite || lb.power <= 0 ||
          lights[l].type != LightType::Triangle)
        continue;
      EXPECT_LE(angle(nd.bounds.axis, lights[l].n), std::acos(double(nd.bounds.cos_theta_o)) + 1e-6)
          << "node " << i << " light " << l;
    }
    EXPECT_NEAR(nd.bounds.power, power, 1e-4 * power + 1e-6) << "node " << i;
  }
}

// Sum of the tree sampler's pmfs over each group's lights at (p, n).
std::map<LightGroup, double> group_shares(const Scene& s, const TreeLightSampler& sampler,
                                          const Vec3& p, const Vec3& n) {
  LightContext c;
  c.p = p;
  c.n = c.ns = n;
  std::map<LightGroup, double> share;
  for (uint32_t l = 0; l < s.lights.size(); ++l)
    share[group_of(s, s.lights[l])] += light_pmf(sampler.sampler_view(), c, l);
  return share;
}

}  // namespace

TEST(LightTree, InvariantsHoldForEveryBuildAndScene) {
  for (const char* name :
       {"cornell-box", "cornell-boxes-room", "arch-interior", "many-lights-open", "furnace"})
    for (TreeBuild method : {TreeBuild::Saoh, TreeBuild::Lbvh}) {
      SCOPED_TRACE(std::string(name) + (method == TreeBuild::Saoh ? " saoh" : " lbvh"));
      Scene s = builtin(name);
      LightTree tree = LightTree::build(s, method);
      EXPECT_EQ(tree.method(), method);
      expect_tree_invariants(tree, s.lights);
      expect_conservative_bounds(tree, s.lights);
      // The scene's triangle -> light map follows the reordering.
      for (uint32_t l = 0; l < s.lights.size(); ++l) {
        if (s.lights[l].type == LightType::Triangle) {
          EXPECT_EQ(s.light_of_triangle(s.lights[l].triangle), int32_t(l));
        }
      }
    }
}

TEST(LightTree, DegenerateLayoutsStayShallow) {
  // Point lights on a geometric progression (a SAOH peels a few off at a time), and many
  // lights in one place (no split plane separates them).
  for (int layout = 0; layout < 2; ++layout) {
    Scene s;
    s.source = "test:degenerate";
    s.width = s.height = 8;
    for (int i = 0; i < 600; ++i) {
      Vec3 p = layout == 0 ? Vec3(std::pow(1.05f, float(i)), 0, 0) : Vec3(1, 2, 3);
      s.lights.push_back(make_point_light(p, Rgb(1.0f + float(i % 7))));
    }
    s.finalize();
    const LightTree tree = build_light_tree(s);
    SCOPED_TRACE(layout);
    expect_tree_invariants(tree, s.lights);
    EXPECT_LE(int(tree.depth()), layout == 0 ? 200 : 11);
  }
}

// A tree of one light is one leaf: no inner node, one step (the root's bounds), and the
// descents and pmfs give the light with probability 1.
TEST(LightTree, OneLightIsALeafWithItsBoundsInStepZero) {
  Scene s;
  s.source = "test:one-light";
  s.width = s.height = 8;
  s.lights.push_back(make_point_light(Vec3(1, 2, 3), Rgb(4.0f)));
  s.finalize();
  const LightTree tree = build_light_tree(s);
  expect_tree_invariants(tree, s.lights);
  const LightTreeView v = tree.view();
  ASSERT_EQ(v.steps.size, 1u);
  EXPECT_EQ(&v.bounds(LightTree::kRoot), &v.steps[0].bounds[1]);
  const Vec3 p(0, 0, 0), n(0, 1, 0);
  EXPECT_GT(light_importance(v.bounds(LightTree::kRoot), p, Vec3(0, 0, 0)), 0.0f);
  const TreeSample t = tree_descend(v, LightTree::kRoot, p, n, 0.7);
  EXPECT_EQ(t.light, 0u);
  EXPECT_EQ(t.pmf, 1.0f);
  EXPECT_EQ(tree_descend_pmf(v, LightTree::kRoot, 0, p, n), 1.0f);
  EXPECT_EQ(tree_reach_pmf(v, LightTree::kRoot, p, n), 1.0f);
}

TEST(LightTree, GroupsHaveTheirOwnSubtrees) {
  Scene s = builtin("cornell-boxes-room", add_sun);
  const LightTree tree = build_light_tree(s);
  expect_tree_invariants(tree, s.lights);
  const uint32_t local = tree.group_root(LightGroup::Local),
                 dome = tree.group_root(LightGroup::Dome),
                 sun = tree.group_root(LightGroup::Directional);
  ASSERT_NE(local, LightTree::kNone);
  ASSERT_NE(dome, LightTree::kNone);
  ASSERT_NE(sun, LightTree::kNone);
  // root -> [local, distant], distant -> [dome, directional]
  const LightTreeNode& root = tree.node(LightTree::kRoot);
  EXPECT_TRUE(root.group);
  EXPECT_EQ(root.child, local);
  const uint32_t distant = root.child + 1;
  EXPECT_TRUE(tree.node(distant).group);
  EXPECT_EQ(tree.node(distant).child, dome);
  EXPECT_EQ(tree.node(distant).child + 1, sun);
  for (uint32_t i = 0; i < tree.node_count(); ++i)
    EXPECT_EQ(tree.node(i).group, i == LightTree::kRoot || i == distant) << "node " << i;
  // Every light under its group's root, and only there.
  size_t count[kLightGroups] = {0, 0, 0};
  for (uint32_t l = 0; l < s.lights.size(); ++l) {
    const LightGroup g = group_of(s, s.lights[l]);
    const LightTreeNode& r = tree.node(tree.group_root(g));
    EXPECT_TRUE(l >= r.begin && l < r.end) << "light " << l;
    ++count[int(g)];
  }
  EXPECT_EQ(count[int(LightGroup::Dome)], s.sky_triangle_count);
  EXPECT_EQ(count[int(LightGroup::Directional)], 1u);
  EXPECT_EQ(count[int(LightGroup::Local)], 84u);
  for (int g = 0; g < kLightGroups; ++g)
    EXPECT_EQ(tree.node(tree.group_root(LightGroup(g))).light_count(), count[g]);

  // Missing groups take their parent's place: arch-interior has a dome and a sun, no lamps.
  Scene arch = builtin("arch-interior");
  const LightTree arch_tree = build_light_tree(arch);
  EXPECT_EQ(arch_tree.group_root(LightGroup::Local), LightTree::kNone);
  EXPECT_TRUE(arch_tree.node(LightTree::kRoot).group);
  EXPECT_EQ(arch_tree.group_root(LightGroup::Dome), arch_tree.node(LightTree::kRoot).child);
  // A lone group is the whole tree.
  Scene open = builtin("many-lights-open");
  const LightTree open_tree = build_light_tree(open);
  EXPECT_EQ(open_tree.group_root(LightGroup::Local), LightTree::kRoot);
  EXPECT_FALSE(open_tree.node(LightTree::kRoot).group);
}

TEST(LightTree, EachContributingGroupGetsAnEqualShare) {
  Scene s = builtin("cornell-boxes-room", add_sun);
  const LightTree tree = build_light_tree(s);
  TreeLightSampler sampler(s, tree);
  // On the floor facing up: lamps, sky and sun can all reach it.
  auto all = group_shares(s, sampler, Vec3(7, 0, 6), Vec3(0, 1, 0));
  for (LightGroup g : {LightGroup::Local, LightGroup::Dome, LightGroup::Directional})
    EXPECT_NEAR(all[g], 1.0 / 3, 1e-5) << "group " << int(g);
  // On the right wall facing -x: the sun (from +x) is behind it, so it gets nothing.
  auto two = group_shares(s, sampler, Vec3(14, 0.5f, 0.6f), Vec3(-1, 0, 0));
  EXPECT_NEAR(two[LightGroup::Local], 0.5, 1e-5);
  EXPECT_NEAR(two[LightGroup::Dome], 0.5, 1e-5);
  EXPECT_EQ(two[LightGroup::Directional], 0.0);
  // sample() agrees with pmf() to the bit along the way, group nodes included.
  LightContext c;
  c.p = Vec3(7, 0, 6);
  c.n = c.ns = Vec3(0, 1, 0);
  for (int k = 0; k < 1000; ++k) {
    SampledLight sl = sample_light(sampler.sampler_view(), c, (k + 0.5) / 1000);
    ASSERT_GT(sl.pmf, 0.0f);
    EXPECT_EQ(sl.pmf, light_pmf(sampler.sampler_view(), c, sl.light));
  }
}

TEST(LightTree, TinyImportanceNextToAHugeOneKeepsAPositivePmf) {
  // Two lamps under one node: a bright one close by and a dim one far away, both facing the
  // point. Their importances differ by far more than 2^24, so i0 / (i0 + i1) rounds to 1 in
  // float and the dim lamp got pmf 0 although it lights the point.
  Scene s;
  s.source = "test:tiny-importance";
  s.width = s.height = 8;
  SceneBuilder b(s);
  b.triangle(Vec3(-1, 1, -1), Vec3(1, 1, -1), Vec3(0, 1, 1), b.emitter(Rgb(1e6f)));
  b.triangle(Vec3(-0.01f, 100, 0), Vec3(0.01f, 100, 0), Vec3(0, 100, 0.01f), b.emitter(Rgb(1e-3f)));
  s.finalize();
  const LightTree tree = build_light_tree(s);
  ASSERT_EQ(s.lights.size(), 2u);
  ASSERT_EQ(tree.node_count(), 3u);
  TreeLightSampler sampler(s, tree);
  LightContext c;
  c.n = c.ns = Vec3(0, 1, 0);
  const uint32_t dim = s.lights[0].p0.y > 50 ? 0 : 1;
  ASSERT_TRUE(test::light_can_contribute(s.lights[dim], c.p, c.n));
  const float p_dim = light_pmf(sampler.sampler_view(), c, dim),
              p_bright = light_pmf(sampler.sampler_view(), c, 1 - dim);
  EXPECT_GT(p_dim, 0.0f);
  EXPECT_GE(p_dim, 0x1p-25f);
  EXPECT_EQ(double(p_dim) + double(p_bright), 1.0);
  // The top of [0, 1) draws it, with the same probability pmf() gives.
  SampledLight sl = sample_light(sampler.sampler_view(), c, dim == 1 ? 1 - 0x1p-30 : 0x1p-30);
  EXPECT_EQ(sl.light, dim);
  EXPECT_EQ(sl.pmf, p_dim);
}

TEST(LightTree, RefitAfterLightsMoveKeepsBoundsConservative) {
  Scene s = builtin("cornell-boxes-dynamic");
  LightTree tree = build_light_tree(s);
  // A view taken before the refits (as the samplers hold theirs) reads the refit bounds.
  const LightTreeView before = tree.view();
  Accel accel(s.mesh);
  for (int frame : {1, 2, 5}) {
    SCOPED_TRACE(frame);
    s.animate(s, frame);
    s.refresh_lights_from_mesh();
    tree.refit(s.lights);
    accel.update_vertices(s.mesh);
    expect_tree_invariants(tree, s.lights);
    expect_conservative_bounds(tree, s.lights);
    ASSERT_EQ(before.steps.data, tree.view().steps.data);
    for (uint32_t i = 0; i < tree.node_count(); ++i)
      if (!tree.node(i).bounds.distant)
        ASSERT_EQ(before.bounds(i).center.x, importance_bounds(tree.node(i).bounds).center.x)
            << "node " << i;
    // Every light that can contribute somewhere keeps a positive probability there.
    TreeLightSampler sampler(s, tree);
    for (const LightContext& c : test::make_contexts(s, accel, 40, 7 + frame))
      for (uint32_t l = 0; l < s.lights.size(); ++l) {
        if (test::light_can_contribute(s.lights[l], c.p, c.n)) {
          ASSERT_GT(light_pmf(sampler.sampler_view(), c, l), 0.0f) << "light " << l;
        }
      }
  }
}

// The steps' layout needs every inner node's children at an odd index (children made in pairs
// after the root): anything else is refused, not read wrongly.
TEST(LightTree, StepsRefuseChildrenAtAnEvenIndex) {
  std::vector<LightTreeNode> nodes(5);
  std::vector<ImportanceBounds> bounds(5);
  std::vector<TreeStep> steps(3);
  nodes[0] = {.begin = 0, .end = 3, .child = 1};
  nodes[1] = {.begin = 0, .end = 1};
  nodes[2] = {.begin = 1, .end = 3, .child = 3};
  nodes[3] = {.begin = 1, .end = 2};
  nodes[4] = {.begin = 2, .end = 3};
  tree_steps(view_of(nodes), view_of(bounds), view_of(steps));
  EXPECT_EQ(steps[2].begin[1], 2u);
  nodes[0].child = 2;  // pairs (2, 3): not the layout
  EXPECT_THROW(tree_steps(view_of(nodes), view_of(bounds), view_of(steps)), Error);
  std::vector<TreeStep> short_steps(2);
  nodes[0].child = 1;
  EXPECT_THROW(tree_steps(view_of(nodes), view_of(bounds), view_of(short_steps)), Error);
  // An even number of nodes is no tree of one light per leaf (its last node would have no slot).
  const std::vector<LightTreeNode> four(nodes.begin(), nodes.begin() + 4);
  const std::vector<ImportanceBounds> four_bounds(4);
  std::vector<TreeStep> two(2);
  EXPECT_THROW(tree_steps(view_of(four), view_of(four_bounds), view_of(two)), Error);
}

TEST(LightBounds, DistantDomeConesHoldEveryDirectionFromTheScene) {
  // A dome triangle's bounds are the cone of directions towards it from anywhere within the
  // scene's bounding sphere: check it against random points of both.
  Scene s = builtin("arch-interior");
  DistantFrame frame;
  frame.center = s.bounds.center();
  frame.reach = s.radius;
  frame.distance = 1;
  Pcg32 rng(5);
  int checked = 0;
  for (uint32_t l = 0; l < s.lights.size(); ++l) {
    if (!is_dome(s, s.lights[l]) || l % 7 != 0) continue;
    const Light& light = s.lights[l];
    const LightBounds b = distant_light_bounds(light, frame);
    ASSERT_TRUE(b.distant && b.infinite);
    EXPECT_EQ(b.power, light_bounds(light).power);
    EXPECT_GT(b.cos_theta_o, 0.99f) << "a dome triangle seen from the scene is a narrow cone";
    for (int k = 0; k < 20; ++k) {
      Vec3 d(rng.next_float() * 2 - 1, rng.next_float() * 2 - 1, rng.next_float() * 2 - 1);
      const Vec3 p = frame.center + d * (s.radius / std::sqrt(3.0f));
      const float u = rng.next_float(), v = rng.next_float() * (1 - u);
      const Vec3 y = light.p0 * (1 - u - v) + light.p1 * u + light.p2 * v;
      EXPECT_LE(angle(b.axis, y - p), std::acos(double(b.cos_theta_o))) << "light " << l;
      ++checked;
    }
  }
  EXPECT_GT(checked, 1000);
}

TEST(LightBounds, MergedConesHoldNearlyParallelAxes) {
  // Two normals 1e-4 rad apart: acos of their dot product rounds to 0 in float, which made the
  // merged cone a single direction that missed one of them.
  const Vec3 a = normalize(Vec3(0, 0, 1)), b = normalize(Vec3(1e-4f, 0, 1));
  Vec3 w;
  float cos_o = 0;
  merge_cones(a, 1.0f, b, 1.0f, w, cos_o);
  EXPECT_GT(cos_o, 0.999f);
  EXPECT_LE(angle(w, a), std::acos(double(cos_o)));
  EXPECT_LE(angle(w, b), std::acos(double(cos_o)));
  // Opposite axes: a hemisphere-wide cone around some axis across them.
  merge_cones(a, 1.0f, -a, 1.0f, w, cos_o);
  EXPECT_LE(angle(w, a), std::acos(double(cos_o)) + 1e-6);
  EXPECT_LE(angle(w, -a), std::acos(double(cos_o)) + 1e-6);
}

TEST(LightBounds, ImportanceStopsGrowingAtTheLightsArea) {
  // A 1 x 1 lamp of radiance 1: no point receives more than pi of irradiance from it, so its
  // importance, power / d^2 at heart, stops growing at d^2 = area = 1, however close the point.
  Light l = make_triangle_light(Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 0, 1), Rgb(1.0f), false, 0);
  l.n = Vec3(0, -1, 0);  // faces down
  const LightBounds b = light_bounds(l);
  ASSERT_NEAR(b.side_power, kPi, 1e-5f);
  const float near = light_importance(b, Vec3(0.5f, -0.01f, 0.3f), Vec3(0, 1, 0));
  EXPECT_LE(near, kPi * 1.0001f);
  EXPECT_GT(near, 0.5f * kPi);
  // Two-sided: a point sees one side, so it counts the power of one.
  l.two_sided = true;
  const LightBounds b2 = light_bounds(l);
  EXPECT_EQ(b2.power, 2 * b.power);
  EXPECT_EQ(b2.side_power, b.side_power);
  EXPECT_NEAR(light_importance(b2, Vec3(0.5f, -3, 0.3f), Vec3(0, 1, 0)),
              light_importance(b, Vec3(0.5f, -3, 0.3f), Vec3(0, 1, 0)), 1e-6f);
}

// The tree is the render session's, not the scene's: it builds it once and every sampler it
// makes reads that tree itself (its nodes where the session keeps them), not a copy of its own.
TEST(LightTree, TheSessionOwnsTheTreeItsSamplersRead) {
  SessionSettings ss;
  ss.scene = "builtin:cornell-boxes-room";
  ss.resolution = "16x12";
  RenderSession session(ss);
  const LightTree& tree = session.light_tree();
  expect_tree_invariants(tree, session.scene().lights);
  EXPECT_EQ(session.make_sampler("tree")->sampler_view().tree.nodes.data, tree.view().nodes.data);
}

// Everything keyed by the light order (reference keys, render shares, learnt states) is keyed
// by the order a tree build leaves: every build over a scene as finalize() leaves it (each
// session's, each test's) orders its lights alike. Build once: a build over lights already in
// tree order may order ties otherwise (so the tree is built where the scene is loaded, by its
// owner, and nowhere again).
TEST(LightTree, EveryBuildOverALoadedSceneOrdersItsLightsAlike) {
  for (const char* name : {"cornell-boxes-room", "arch-interior", "many-lights-open"}) {
    SCOPED_TRACE(name);
    const Scene loaded = builtin(name);
    Scene a = loaded, b = loaded;
    build_light_tree(a);
    build_light_tree(b);
    ASSERT_EQ(a.lights.size(), b.lights.size());
    for (size_t l = 0; l < a.lights.size(); ++l) {
      ASSERT_EQ(a.lights[l].type, b.lights[l].type) << "light " << l;
      ASSERT_EQ(a.lights[l].triangle, b.lights[l].triangle) << "light " << l;
    }
    EXPECT_EQ(a.fingerprint(), b.fingerprint());
  }
}

// The session builds the tree after loading, so the fingerprints of its scenes, which learnt
// states and cached references were saved under, are those of the scenes whose finalize() built
// the tree (the values before the tree left Scene). A builtin scene that changes on purpose
// changes its value here too.
TEST(LightTree, SessionScenesKeepTheirFingerprints) {
  const std::pair<const char*, uint64_t> expected[] = {
      {"builtin:cornell-boxes-room", 0xdb061c600378efb3ull},
      {"builtin:arch-interior", 0x7ed099802e51520bull},
  };
  for (const auto& [scene, fingerprint] : expected) {
    SessionSettings ss;
    ss.scene = scene;
    ss.resolution = "64x48";
    RenderSession session(ss);
    EXPECT_EQ(session.scene().fingerprint(), fingerprint) << scene;
  }
}

// Between frames the session refits the tree it built: its bounds stay conservative as the
// lamps of cornell-boxes-dynamic move and switch.
TEST(LightTree, SessionRefitsTheTreeBetweenFrames) {
  SessionSettings ss;
  ss.scene = "builtin:cornell-boxes-dynamic";
  ss.resolution = "16x12";
  RenderSession session(ss);
  for (int frame : {1, 3}) {
    SCOPED_TRACE(frame);
    session.set_frame(frame, nullptr);
    expect_conservative_bounds(session.light_tree(), session.scene().lights);
  }
}
