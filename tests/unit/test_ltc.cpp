// Wang et al. 2021's sampler (ltc): the spatial clusters partition space and their points; the
// global cut and every grown cut partition the lights; learning moves probability onto the
// lights that contribute; the learnt state does not depend on the order rewards arrive in.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>

#include "rll/core/error.h"
#include "rll/core/params.h"
#include "rll/core/rng.h"
#include "rll/learn/cut.h"
#include "rll/lights/light_dispatch.h"
#include "rll/lights/ltc_sampler.h"
#include "rll/scene/builtin.h"
#include "support/test_support.h"

using namespace rll;

namespace {

LtcSettings small_settings() {
  LtcSettings st;
  st.clusters = 256;
  st.capacity = 512;
  return st;
}

// A shading point on the floor of many-lights-open, looking down from above.
LightContext floor_context(const Scene& s) {
  LightContext c;
  c.p = s.bounds.center();
  c.p.y = s.bounds.lo.y + 1e-3f * (s.bounds.hi.y - s.bounds.lo.y);
  c.n = c.ns = Vec3(0, 1, 0);
  c.wo = normalize(Vec3(0.3f, 1, 0.2f));
  return c;
}

// Feeds one pass of rewards: `samples` draws at ctx, reward 1 for lights in [lit_begin, lit_end).
void feed_pass(LtcLightSampler& ltc, const LightContext& ctx, int samples, uint32_t lit_begin,
               uint32_t lit_end, uint64_t seed) {
  Pcg32 rng(seed);
  for (int i = 0; i < samples; ++i) {
    SampledLight s = sample_light(ltc.sampler_view(), ctx, rng.next_double());
    ASSERT_GT(s.pmf, 0);
    NeeRecord r;
    r.estimate = s.light >= lit_begin && s.light < lit_end ? 1.0f : 0.0f;
    r.mis_weight = 1;
    record_nee(ltc.sampler_view(), ctx, s, r);
  }
  ltc.end_pass();
}

}  // namespace

TEST(LtcClusters, PartitionThePointsIntoTheRequestedCount) {
  Pcg32 rng(7);
  std::vector<Vec3> pts;
  for (int i = 0; i < 4000; ++i) {
    // Two slabs and a line of duplicates: medians with ties must still split.
    float x = rng.next_float(), y = i % 3 == 0 ? 0.0f : rng.next_float(),
          z = i < 200 ? 0.5f : rng.next_float();
    pts.push_back(Vec3(x, y, z));
  }
  for (int i = 0; i < 50; ++i) pts.push_back(Vec3(0.25f, 0.25f, 0.25f));
  SpatialClusters sc = SpatialClusters::build(pts, 300);
  ASSERT_EQ(sc.size(), 300u);
  // Each cluster's centre is the mean of exactly the points that find() sends to it.
  std::vector<double> sum(3 * sc.size(), 0.0);
  std::vector<int> count(sc.size(), 0);
  for (const Vec3& p : pts) {
    uint32_t c = sc.find(p);
    ASSERT_LT(c, sc.size());
    ++count[c];
    for (int a = 0; a < 3; ++a) sum[3 * c + a] += p[a];
  }
  for (uint32_t c = 0; c < sc.size(); ++c) {
    ASSERT_GT(count[c], 0) << "cluster " << c;
    for (int a = 0; a < 3; ++a)
      EXPECT_NEAR(sum[3 * c + a] / count[c], sc.centre(c)[a], 1e-5) << "cluster " << c;
  }
  // Largest boxes split first: no cluster holds more than a few times its share of points.
  EXPECT_LT(*std::max_element(count.begin(), count.end()), 8 * int(pts.size() / 300));
}

TEST(LtcClusters, FewerWhenPointsCannotSplit) {
  std::vector<Vec3> pts(10, Vec3(1, 2, 3));
  pts.push_back(Vec3(1, 2, 4));
  SpatialClusters sc = SpatialClusters::build(pts, 64);
  EXPECT_EQ(sc.size(), 2u);
  EXPECT_NE(sc.find(Vec3(1, 2, 3)), sc.find(Vec3(1, 2, 4)));
}

TEST(LtcCut, GlobalCutByPowerPartitionsLights) {
  Scene s = test::small_builtin_scene("many-lights-open", 16, 12);
  const LightTree tree = build_light_tree(s);
  for (int m : {1, 2, 8, 64}) {
    auto cut = power_cut(tree, m);
    EXPECT_TRUE(is_valid_cut(tree, cut)) << m;
    EXPECT_EQ(int(cut.size()), std::min<int>(m, int(tree.light_count()))) << m;
  }
}

TEST(LtcSampler, DirectionBinsCoverTheSphere) {
  Scene s = test::small_builtin_scene("many-lights-open", 16, 12);
  const LightTree tree = build_light_tree(s);
  LtcLightSampler ltc(s, tree, small_settings());
  std::vector<int> hits(64, 0);
  Pcg32 rng(3);
  for (int i = 0; i < 20000; ++i) {
    float z = 2 * rng.next_float() - 1, phi = 2 * kPi * rng.next_float(),
          r = std::sqrt(std::max(0.0f, 1 - z * z));
    uint32_t b = ltc.direction_bin(Vec3(r * std::cos(phi), r * std::sin(phi), z));
    ASSERT_LT(b, 64u);
    ++hits[b];
  }
  for (int b = 0; b < 64; ++b) EXPECT_GT(hits[b], 0) << b;
  EXPECT_EQ(ltc.direction_bin(Vec3(0)), 0u);
}

TEST(LtcSampler, LearningMovesProbabilityOntoTheLitLights) {
  Scene s = test::small_builtin_scene("many-lights-open", 16, 12);
  const LightTree tree = build_light_tree(s);
  ASSERT_GT(tree.light_count(), 64u);
  LtcLightSampler ltc(s, tree, small_settings());
  LightContext ctx = floor_context(s);
  prepare_point(ltc.sampler_view(), ctx, 0.5f);
  ASSERT_NE(ctx.cell, kNoCell);
  // The lit lights: a subtree two levels below a node of the global cut, the one whose lights
  // the tree at this point likes least among those it gives at least 1% to, so that learning must
  // move probability there (and split the cut node to isolate it).
  uint32_t lit_node = LightTree::kNone;
  double before = 2;
  for (uint32_t top : ltc.initial_cut()) {
    uint32_t n = top;
    for (int d = 0; d < 2 && !tree.node(n).is_leaf(); ++d) n = tree.node(n).child + 1;
    double mass = 0;
    for (uint32_t l = tree.node(n).begin; l < tree.node(n).end; ++l)
      mass += light_pmf(ltc.sampler_view(), ctx, l);
    if (n != top && mass > 0.01 && mass < before) {
      before = mass;
      lit_node = n;
    }
  }
  ASSERT_NE(lit_node, LightTree::kNone);
  const uint32_t lit_begin = tree.node(lit_node).begin, lit_end = tree.node(lit_node).end;
  for (int pass = 0; pass < 12; ++pass) feed_pass(ltc, ctx, 4000, lit_begin, lit_end, 100 + pass);
  ASSERT_TRUE(ltc.has_cut(ctx.cell));
  const uint32_t K = ltc.cut_size(ctx.cell);
  EXPECT_GT(K, 8u) << "variance-driven splits grow the cut";
  EXPECT_LE(K, 64u);
  std::vector<uint32_t> nodes(ltc.cut_nodes(ctx.cell), ltc.cut_nodes(ctx.cell) + K);
  EXPECT_TRUE(is_valid_cut(tree, nodes));
  double after = 0;
  for (uint32_t l = lit_begin; l < lit_end; ++l) after += light_pmf(ltc.sampler_view(), ctx, l);
  EXPECT_GT(after, 0.8) << "before " << before;
  EXPECT_GT(after, 4 * before);
  // pmfs still sum to one and every light keeps some probability (the defensive mix).
  double sum = 0;
  for (uint32_t l = 0; l < tree.light_count(); ++l) sum += light_pmf(ltc.sampler_view(), ctx, l);
  EXPECT_NEAR(sum, 1.0, 1e-5);
}

TEST(LtcSampler, LearntStateIndependentOfRewardOrder) {
  // Two samplers get the same rewards, one in reverse order (as threads might deliver them):
  // every pmf afterwards is identical to the bit.
  Scene s = test::small_builtin_scene("many-lights-open", 16, 12);
  const LightTree tree = build_light_tree(s);
  LtcLightSampler a(s, tree, small_settings()), b(s, tree, small_settings());
  LightContext ctx = floor_context(s), cb = ctx;
  prepare_point(a.sampler_view(), ctx, 0.5f);
  prepare_point(b.sampler_view(), cb, 0.5f);
  const uint32_t lit = uint32_t(s.lights.size() / 2);
  for (int pass = 0; pass < 6; ++pass) {
    std::vector<std::pair<SampledLight, NeeRecord>> recs;
    Pcg32 rng(50 + pass);
    for (int i = 0; i < 3000; ++i) {
      SampledLight sl = sample_light(a.sampler_view(), ctx, rng.next_double());
      NeeRecord r;
      r.estimate =
          sl.light == lit ? 2.0f : (sl.light % 7 == 0 ? 0.01f * float(sl.light % 13) : 0.0f);
      r.mis_weight = 0.9f;
      recs.push_back({sl, r});
    }
    for (const auto& [sl, r] : recs) record_nee(a.sampler_view(), ctx, sl, r);
    for (auto it = recs.rbegin(); it != recs.rend(); ++it)
      record_nee(b.sampler_view(), cb, it->first, it->second);
    a.end_pass();
    b.end_pass();
  }
  for (uint32_t l = 0; l < s.lights.size(); ++l)
    ASSERT_EQ(light_pmf(a.sampler_view(), ctx, l), light_pmf(b.sampler_view(), cb, l))
        << "light " << l;
}

TEST(LtcSampler, BadParametersAreErrors) {
  Scene s = test::small_builtin_scene("many-lights-open", 16, 12);
  for (const char* bad :
       {"ltc.epsilon=0", "ltc.initial_cut=70", "ltc.bins=0", "ltc.capacity=0", "ltc.clusters=0"}) {
    Params p = Params::parse({bad});
    EXPECT_THROW(ltc_settings_from(p), Error) << bad;
  }
}

// ltc's entries and rll's cells keep their cuts in the same arrays (learn/cut_arrays.h), read by
// the same draw: a cell with a cut reads its own slice, any other (kNoCell too) the initial cut.
TEST(CutArrays, ACellReadsItsOwnCutAndOneWithoutReadsTheInitialCut) {
  Scene s = test::small_builtin_scene("many-lights-open", 16, 12);
  const LightTree tree = build_light_tree(s);
  CutArrays a(tree, 3, 8, power_cut(tree, 4));
  ASSERT_EQ(a.initial.size(), 4u);
  for (size_t k = 0; k < 4; ++k) EXPECT_EQ(a.initial_ends[k], tree.node(a.initial[k]).end);
  // Cell 1 gets the root's two children, drawn with 1/4 and 3/4.
  const uint32_t c = tree.node(LightTree::kRoot).child;
  const CutArraysRwView w = a.rw_view();
  const size_t b = w.base(1);
  for (uint32_t k = 0; k < 2; ++k) {
    w.node[b + k] = c + k;
    w.end[b + k] = tree.node(c + k).end;
  }
  w.cdf[b] = 0.25f;
  w.cdf[b + 1] = 1.0f;
  w.size[1] = 2;

  const CutArraysView v = a.view();
  EXPECT_FALSE(v.active(0));
  EXPECT_TRUE(v.active(1));
  EXPECT_EQ(v.base(2), 16u);
  for (uint32_t cell : {0u, 2u, kNoCell}) {
    const detail::RllCut r = detail::rll_cut(v, cell);
    EXPECT_EQ(r.size, 4u) << cell;
    EXPECT_EQ(r.nodes, a.initial.data()) << cell;
    EXPECT_EQ(r.ends, a.initial_ends.data()) << cell;
    EXPECT_EQ(r.cdf, nullptr) << cell;
  }
  const detail::RllCut r = detail::rll_cut(v, 1);
  EXPECT_EQ(r.size, 2u);
  EXPECT_EQ(r.nodes, a.nodes(1));
  EXPECT_EQ(r.ends, a.ends(1));
  EXPECT_EQ(r.cdf, a.cdf_of(1));
  EXPECT_FLOAT_EQ(detail::rll_cdf_width(r, 1), 0.75f);
  EXPECT_EQ(detail::rll_cluster_of(r, tree.node(c).end), 1u);
}
