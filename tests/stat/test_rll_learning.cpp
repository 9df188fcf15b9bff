// RLL learns visibility: a light that no point of the floor can see loses its probability down
// to the defensive floor within a few passes; learning gives the same state, to the bit,
// whatever the thread count; and a trained sampler still renders the same image as the
// visibility-blind samplers (tests/render/test_sampler_agreement.cpp covers the rest).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <map>

#include "rll/accel/accel.h"
#include "rll/core/binary_io.h"
#include "rll/core/parallel.h"
#include "rll/core/params.h"
#include "rll/core/rng.h"
#include "rll/lights/rll_sampler.h"
#include "rll/lights/tree_sampler.h"
#include "rll/lighttree/light_tree.h"
#include "rll/render/render.h"
#include "rll/scene/builder.h"
#include "rll/scene/builtin.h"
#include "support/power.h"
#include "support/sampler_contexts.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;

namespace {

// A next-event record with only the estimate (what rll's default reward reads).
NeeRecord nee(float estimate) {
  NeeRecord r;
  r.estimate = r.unoccluded = r.max_rgb = estimate;
  return r;
}

// A floor under two small lamps facing down. Lamp B sits inside a closed box: it lights the
// box's inside only, though a visibility-blind sampler rates it as highly as lamp A.
Scene two_lamps() {
  Scene s;
  s.source = "test:two-lamps";
  s.width = 32;
  s.height = 32;
  SceneBuilder b(s);
  uint32_t floor = b.diffuse(Rgb(0.5f)), wall = b.diffuse(Rgb(0.5f)), lamp = b.emitter(Rgb(5.0f));
  b.quad(Vec3(0, 0, 0), Vec3(0, 0, 4), Vec3(4, 0, 0), floor);
  b.quad(Vec3(1.0f, 1.5f, 1.0f), Vec3(0.4f, 0, 0), Vec3(0, 0, 0.4f),
         lamp);                                                 // A: x cross z = -y, faces down
  b.box(Vec3(2.3f, 1.2f, 2.3f), Vec3(3.1f, 1.8f, 3.1f), wall);  // B's closed box
  b.quad(Vec3(2.5f, 1.5f, 2.5f), Vec3(0.4f, 0, 0), Vec3(0, 0, 0.4f), lamp);  // B, inside it
  s.camera.position = Vec3(2, 6, 2.01f);
  s.camera.target = Vec3(2, 0, 2);
  s.camera.fov = 40;
  s.has_camera = true;
  s.finalize();
  return s;
}

struct Trained {
  std::unique_ptr<Accel> accel;
  std::unique_ptr<RllLightSampler> sampler;
};

Trained train(const Scene& scene, const LightTree& tree, int passes, int threads, std::vector<std::string> extra = {}) {
  ThreadLimit limit(threads);
  Trained t;
  t.accel = std::make_unique<Accel>(scene.mesh);
  std::vector<std::string> set = {"rll.cut_size=2", "rll.splits=0"};
  set.insert(set.end(), extra.begin(), extra.end());
  Params p = Params::parse(set);
  t.sampler = std::make_unique<RllLightSampler>(scene, tree, rll_settings_from(p));
  IntegratorSettings is;
  is.type = IntegratorType::Direct;
  Integrator integrator(scene, *t.accel, *t.sampler, is);
  Film film(scene.width, scene.height);
  RenderSettings rs;
  rs.spp = passes;
  rs.max_pass_spp = 1;  // one pass per sample per pixel
  render(scene, integrator, *t.sampler, film, rs);
  return t;
}

// Floor point k of 40 in view (an 8 x 5 grid), prepared: in its cell.
LightContext floor_point(const Scene& scene, const RllLightSampler& sampler, int k) {
  LightContext c;
  c.p = Vec3(0.5f + 3.0f * float(k % 8) / 7, 0, 0.5f + 3.0f * float(k / 8) / 4);
  c.n = c.ns = Vec3(0, 1, 0);
  c.footprint = 6 * scene.camera.pixel_angle();
  prepare_point(sampler.sampler_view(), c, 0.5f);
  return c;
}

}  // namespace

TEST(RllLearning, OccludedLampFallsToTheDefensiveFloor) {
  Scene scene = two_lamps();
  const LightTree tree = build_light_tree(scene);
  // The root's two children are the two lamps (their two triangles each).
  ASSERT_EQ(tree.light_count(), 4u);
  const uint32_t a = tree.node(LightTree::kRoot).child, b = a + 1;
  // Which child is lamp B (the one at x > 2)?
  const bool b_is_second = scene.lights[tree.node(b).begin].centroid().x > 2;
  const uint32_t node_b = b_is_second ? b : a;

  float previous_eps = 1.0f;
  for (int passes : {1, 4, 8, 16}) {
    Trained t = train(scene, tree, passes, 1);
    // Points of the floor in view, each in its cell.
    int checked = 0;
    float max_reach = 0, eps_sum = 0, max_ratio = 0;
    std::vector<float> ratios;
    for (int k = 0; k < 40; ++k) {
      LightContext c = floor_point(scene, *t.sampler, k);
      if (c.cell == kNoCell || !t.sampler->cuts().active(c.cell) ||
          !t.sampler->cuts().learnt(c.cell))
        continue;
      float p_b = 0;
      for (uint32_t l = tree.node(node_b).begin; l < tree.node(node_b).end; ++l)
        p_b += light_pmf(t.sampler->sampler_view(), c, l);
      const float reach_b = tree_reach_pmf(tree, node_b, c.p, c.n);
      const float eps = t.sampler->cuts().defensive_weight(c.cell);
      max_reach = std::max(max_reach, reach_b);
      // P(B) = (1 - eps) q_B + eps prior_B: q_B is what the cell learnt for the hidden lamp.
      std::vector<double> shares = t.sampler->cuts().learnt_shares(c.cell);
      ASSERT_EQ(shares.size(), 2u);
      const float q_b = float(shares[t.sampler->cuts().nodes(c.cell)[0] == node_b ? 0 : 1]);
      // The defensive floor keeps the hidden lamp's probability positive.
      EXPECT_GE(p_b, 0.99f * eps * 0.01f);
      // Relative to the tree's own probability of the lamp (what a visibility-blind sampler
      // gives it), the learnt share must fall far below.
      max_ratio = std::max(max_ratio, q_b / reach_b);
      ratios.push_back(q_b / reach_b);
      eps_sum += eps;
      ++checked;
    }
    if (passes > 1) {
      EXPECT_GT(checked, 20) << "too few learnt cells after " << passes << " passes";
      // The test means something only if the tree rates the hidden lamp highly somewhere.
      EXPECT_GT(max_reach, 0.3f);
      std::sort(ratios.begin(), ratios.end());
      const float median = ratios[ratios.size() / 2];
      const float p90 = ratios[ratios.size() * 9 / 10];
      std::printf(
          "%d passes: learnt share / tree share of the hidden lamp: median %.3f, 90%% %.3f, max "
          "%.3f\n",
          passes, median, p90, max_ratio);
      // Measured at the fixed seed (Sobol' points, MIS direct, v2 learning): 90th percentile
      // below 0.001 after 4, 8, 16 passes, the worst cell 0.83, 0.61, 0.43 (a cell at the edge of
      // the lamp's box); a sampler that did not learn stays near 1. The worst single cell rests on
      // a handful of rewards, so it gets a looser bound than the 90th percentile.
      const float limit = passes == 4 ? 0.7f : passes == 8 ? 0.35f : 0.25f;
      EXPECT_LT(p90, limit) << passes << " passes";
      EXPECT_LT(max_ratio, std::min(0.9f, 2 * limit)) << passes << " passes";
      EXPECT_LT(median, 0.5f * limit) << passes << " passes";
      // The defensive weight falls as cells gather rewards.
      const float mean_eps = eps_sum / float(std::max(1, checked));
      EXPECT_LT(mean_eps, previous_eps) << passes << " passes";
      previous_eps = mean_eps;
    }
  }
}

// The guided descent learns the same visibility as a ratio to the tree's importance: at floor
// points the hidden lamp's probability falls far below the tree's, to about e / (1 + ...) of it,
// and stays positive.
TEST(RllLearning, GuidedDescentLearnsTheOccludedLamp) {
  Scene scene = two_lamps();
  const LightTree tree = build_light_tree(scene);
  const uint32_t a = tree.node(LightTree::kRoot).child, b = a + 1;
  const uint32_t node_b = scene.lights[tree.node(b).begin].centroid().x > 2 ? b : a;
  // A short trust schedule, so that the defensive weight (which bounds how far a factor falls)
  // is near epsilon after 16 passes.
  Trained t = train(scene, tree, 16, 1, {"rll.sampling=guided", "rll.trust=16"});
  int checked = 0;
  std::vector<float> ratios;
  for (int k = 0; k < 40; ++k) {
    LightContext c = floor_point(scene, *t.sampler, k);
    if (c.cell == kNoCell || !t.sampler->cuts().learnt(c.cell)) continue;
    const float reach_b = tree_reach_pmf(tree, node_b, c.p, c.n);
    if (!(reach_b > 0.05f)) continue;
    float p_b = 0, total = 0;
    for (uint32_t l = 0; l < tree.light_count(); ++l) {
      const float p = light_pmf(t.sampler->sampler_view(), c, l);
      total += p;
      if (l >= tree.node(node_b).begin && l < tree.node(node_b).end) p_b += p;
    }
    EXPECT_NEAR(total, 1.0f, 1e-5f);
    // Positive (a factor never falls below the defensive weight), and never above the tree's:
    // the lamp's rewards are all zero, so its learnt ratio only falls from the cell's mean.
    EXPECT_GT(p_b, 0.0f);
    EXPECT_LT(p_b / reach_b, 1.0f) << "cell " << c.cell;
    ratios.push_back(p_b / reach_b);
    ++checked;
  }
  ASSERT_GT(checked, 15);
  std::sort(ratios.begin(), ratios.end());
  std::printf("guided: hidden lamp's probability / the tree's: median %.3f, max %.3f\n",
              ratios[ratios.size() / 2], ratios.back());
  // The plain tree (every factor 1) gives exactly 1 here.
  EXPECT_LT(ratios[ratios.size() / 2], 0.25f);
  EXPECT_LT(ratios[ratios.size() * 9 / 10], 0.5f);
}

namespace {
// Trains rll with `settings` on two_lamps() and checks that every learnt floor cell has its coarse
// cell's shares, and that they give the hidden lamp (node_b) nothing where the tree rates it
// highly.
void check_pooled_hidden_lamp(const Scene& scene, const LightTree& tree, uint32_t node_b,
                              const std::vector<std::string>& settings) {
  Trained t = train(scene, tree, 8, 1, settings);
  const nlohmann::json d = t.sampler->describe();
  const uint64_t cells = d["cells_used"].get<uint64_t>(), pooled = d["pool_cells"].get<uint64_t>();
  std::printf("%llu cells pooled into %llu coarse cells\n", (unsigned long long)cells,
              (unsigned long long)pooled);
  EXPECT_GT(pooled, 0u);
  EXPECT_LT(pooled, cells) << "a coarse cell holds the cells of a region twice as wide";
  int checked = 0;
  std::vector<float> shares_b;
  for (int k = 0; k < 40; ++k) {
    LightContext c = floor_point(scene, *t.sampler, k);
    if (c.cell == kNoCell || !t.sampler->cuts().learnt(c.cell)) continue;
    const float* pool = t.sampler->cuts().pool_shares(c.cell);
    ASSERT_NE(pool, nullptr) << "a learnt cell without its coarse cell's shares";
    const uint32_t kb = t.sampler->cuts().nodes(c.cell)[0] == node_b ? 0 : 1;
    EXPECT_NEAR(pool[0] + pool[1], 1.0f, 1e-5f);
    if (tree_reach_pmf(tree, node_b, c.p, c.n) > 0.3f) shares_b.push_back(pool[kb]);
    ++checked;
  }
  ASSERT_GT(checked, 20);
  ASSERT_GT(shares_b.size(), 5u)
      << "the test needs cells where the tree rates the hidden lamp highly";
  std::sort(shares_b.begin(), shares_b.end());
  std::printf("coarse share of the hidden lamp: median %.4f, max %.4f\n",
              shares_b[shares_b.size() / 2], shares_b.back());
  // Every reward of lamp B on the floor is zero, so the coarse cells give it nothing.
  EXPECT_LT(shares_b.back(), 0.01f);
}
}  // namespace

// Pooling end to end: the floor's cells pool their rewards into coarse cells, each coarse
// cell holds several cells, and what the coarse cells learnt about the hidden lamp reaches
// every learnt cell as a share near zero, while a visibility-blind prior rates it highly.
TEST(RllLearning, PooledCoarseCellsLearnTheOccludedLamp) {
  Scene scene = two_lamps();
  const LightTree tree = build_light_tree(scene);
  const uint32_t a = tree.node(LightTree::kRoot).child, b = a + 1;
  const uint32_t node_b = scene.lights[tree.node(b).begin].centroid().x > 2 ? b : a;
  // Both guesses (the coarse cell's share of the rewards, its factor on each cell's prior), and
  // two tiers of coarse cells.
  for (const char* guess : {"share", "ratio"}) {
    SCOPED_TRACE(guess);
    check_pooled_hidden_lamp(scene, tree, node_b, {"rll.pool=1", std::string("rll.pool_guess=") + guess});
    check_pooled_hidden_lamp(
        scene, tree, node_b, {"rll.pool=1", "rll.pool_up=1", std::string("rll.pool_guess=") + guess});
  }
  // Without pooling there are no coarse cells.
  Trained alone = train(scene, tree, 2, 1, {"rll.pool=0"});
  EXPECT_EQ(alone.sampler->describe()["pool_cells"].get<uint64_t>(), 0u);
}

TEST(RllLearning, SameStateWhateverTheThreadCount) {
  // Rewards are summed in fixed point, so the learnt state, and every image rendered with it,
  // does not depend on the order in which threads delivered the rewards.
  Scene scene = two_lamps();
  RenderRequest r;
  r.sampler = "rll";
  r.integrator.type = IntegratorType::Path;
  r.integrator.max_depth = 3;
  r.spp = 12;
  r.threads = 1;
  Image one = render_scene(scene, r);
  r.threads = 2;
  Image two = render_scene(scene, r);
  ASSERT_EQ(one.pixel_count(), two.pixel_count());
  size_t differ = 0;
  for (size_t i = 0; i < one.pixel_count(); ++i) differ += !(one[i] == two[i]);
  EXPECT_EQ(differ, 0u);
  r.seed = 2;
  Image other = render_scene(scene, r);
  differ = 0;
  for (size_t i = 0; i < one.pixel_count(); ++i) differ += !(one[i] == other[i]);
  EXPECT_GT(differ, one.pixel_count() / 2) << "a different seed must give a different image";
}

TEST(RllLearning, TrainedStateIsStronglyNonUniform) {
  // The sampler statistics (test_light_samplers.cpp) run on this trained state; they mean
  // something for RLL only if the cells' cluster distributions are far from uniform.
  Scene scene = small_builtin_scene("cornell-boxes-room", 48, 36);
  const LightTree tree = build_light_tree(scene);
  Accel accel(scene.mesh);
  Params params;
  RllLightSampler rll(scene, tree, rll_settings_from(params));
  train_sampler(scene, accel, rll, 32);  // as the statistical suite does
  std::vector<float> concentration;      // K * max cluster probability: 1 for uniform
  for (uint32_t c = 0; c < rll.table().capacity(); ++c) {
    if (!rll.table().in_use(c) || !rll.cuts().active(c) || !rll.cuts().learnt(c)) continue;
    const uint32_t K = rll.cuts().size(c);
    float max_p = 0, prev = 0;
    for (uint32_t k = 0; k < K; ++k) {
      max_p = std::max(max_p, rll.cuts().cdf(c)[k] - prev);
      prev = rll.cuts().cdf(c)[k];
    }
    concentration.push_back(max_p * float(K));
  }
  ASSERT_GT(concentration.size(), 100u);
  std::sort(concentration.begin(), concentration.end());
  const float p75 = concentration[concentration.size() * 3 / 4],
              p90 = concentration[concentration.size() * 9 / 10];
  std::printf("K x max cluster probability: median %.1f, 75th percentile %.1f, 90th %.1f\n",
              concentration[concentration.size() / 2], p75, p90);
  // A quarter of the cells give one cluster over 10 times its uniform share (measured 55; cells
  // that see the sky through a window spread theirs over many clusters, rightly). A uniform
  // distribution gives 1.
  EXPECT_GT(p75, 10.0f);
  EXPECT_GT(p90, 25.0f);
}

TEST(RllLearning, RewardsOfANewCellReachTheClustersOfTheirLights) {
  // Defect of the first version: a cell created after the coarser cell around it had learnt
  // inherited that cell's refined cut, while its own first rewards, recorded under the initial
  // cut's cluster indices, were folded in under the inherited cut's indices: onto the wrong
  // clusters. Inheritance is gone (bench/RESULTS.md: it almost never fired); a new cell's
  // rewards must land on the clusters of the lights that earned them. Without pooling: the two
  // cells disagree by construction, and pooling (tested on its own below) would rightly pull
  // each toward what the other saw (with two tiers the fine cell's upper coarse cell is the
  // coarse cell's first). Stochastic level rounding gives the same point a coarse and a fine
  // cell (u picks one); nearest rounding would give it only one.
  Scene scene = small_builtin_scene("many-lights-open", 32, 24);
  const LightTree tree = build_light_tree(scene);
  RllLightSampler rll(
      scene, tree, rll_settings_from(Params::parse({"rll.pool=0", "rll.level_rounding=stochastic"})));
  const uint32_t L = uint32_t(scene.lights.size()), half = L / 2;
  LightContext coarse;
  coarse.p = scene.bounds.center();
  coarse.p.y = scene.bounds.lo.y;
  coarse.n = coarse.ns = Vec3(0, 1, 0);
  coarse.footprint = 0.013f * scene.radius;  // a fractional level: u picks the coarser or finer
  LightContext fine = coarse;
  Pcg32 rng(5);
  // The coarse cell learns that only the first half of the lights matters, and refines there.
  for (int pass = 0; pass < 8; ++pass) {
    prepare_point(rll.sampler_view(), coarse, 0.0f);
    ASSERT_NE(coarse.cell, kNoCell);
    for (int i = 0; i < 2000; ++i) {
      SampledLight s = sample_light(rll.sampler_view(), coarse, rng.next_double());
      if (s.pmf > 0) record_nee(rll.sampler_view(), coarse, s, nee(s.light < half ? 1.0f : 0.0f));
    }
    rll.end_pass();
  }
  // A finer cell inside it sees only the second half.
  prepare_point(rll.sampler_view(), fine, 0.9999f);
  ASSERT_NE(fine.cell, kNoCell);
  ASSERT_NE(fine.cell, coarse.cell);
  ASSERT_FALSE(rll.cuts().active(fine.cell));
  for (int i = 0; i < 4000; ++i) {
    SampledLight s = sample_light(rll.sampler_view(), fine, rng.next_double());
    if (s.pmf > 0) record_nee(rll.sampler_view(), fine, s, nee(s.light >= half ? 1.0f : 0.0f));
  }
  rll.end_pass();
  prepare_point(rll.sampler_view(), coarse, 0.0f);
  prepare_point(rll.sampler_view(), fine, 0.9999f);
  std::vector<double> shares = rll.cuts().learnt_shares(fine.cell);
  ASSERT_FALSE(shares.empty());
  double second_half = 0, first_half = 0;
  for (size_t k = 0; k < shares.size(); ++k) {
    const LightTreeNode& nd = tree.node(rll.cuts().nodes(fine.cell)[k]);
    (nd.end > half ? second_half : first_half) += shares[k];  // holds lights of the second half
  }
  EXPECT_GT(second_half, 0.95) << "first half " << first_half;
  // And the coarse cell keeps what it learnt.
  std::vector<double> coarse_shares = rll.cuts().learnt_shares(coarse.cell);
  double coarse_first = 0;
  for (size_t k = 0; k < coarse_shares.size(); ++k)
    if (tree.node(rll.cuts().nodes(coarse.cell)[k]).end <= half)
      coarse_first += coarse_shares[k];
  EXPECT_GT(coarse_first, 0.95);
}

TEST(RllLearning, FullTableEvictsAndStaysCorrect) {
  // A table far too small for the scene: inserts fail (those points sample like the tree),
  // least recently used cells are evicted between passes, and the sampler stays a valid,
  // unbiased distribution throughout.
  Scene scene = small_builtin_scene("cornell-boxes-room", 32, 24);
  const LightTree tree = build_light_tree(scene);
  Accel accel(scene.mesh);
  Params params = Params::parse({"rll.capacity=40"});
  RllLightSampler rll(scene, tree, rll_settings_from(params));
  train_sampler(scene, accel, rll, 12);
  nlohmann::json d = rll.describe();
  EXPECT_GT(d["evictions"].get<uint64_t>(), 0u);
  EXPECT_GT(d["failed_inserts"].get<uint64_t>(), 0u);
  EXPECT_LE(d["cells_used"].get<uint32_t>(), 40u);
  auto contexts = make_contexts(scene, accel, 60, 5);
  Pcg32 rng(8);
  for (auto& c : contexts) {
    prepare_point(rll.sampler_view(), c, rng.next_float());
    double sum = 0;
    for (uint32_t l = 0; l < scene.lights.size(); ++l) sum += light_pmf(rll.sampler_view(), c, l);
    EXPECT_NEAR(sum, 1.0, 1e-4);
    for (int k = 0; k < 16; ++k) {
      SampledLight s = sample_light(rll.sampler_view(), c, rng.next_double());
      ASSERT_GT(s.pmf, 0);
      EXPECT_EQ(s.pmf, light_pmf(rll.sampler_view(), c, s.light));
    }
  }
  RenderRequest a;
  a.sampler = "tree";
  a.integrator.type = IntegratorType::Direct;
  a.spp = 512;
  RenderRequest b = a;
  b.sampler = "rll";
  b.set = {"rll.capacity=40"};
  b.seed = 7;
  const Image ib = render_scene(scene, tree, b), ia = render_scene(scene, tree, a);
  Estimate diff = difference_estimate(ib, ia);
  EXPECT_LE(std::abs(diff.mean), 4.5 * diff.stderr_) << diff.mean << " +- " << diff.stderr_;
  expect_bound_sees(ib, ia, "rll with a full table vs tree", 0.05);  // sees 1.5%
}

TEST(RllLearning, AnimatedFramesRefitAndStayUnbiased) {
  // Lamps switch off and slide between frames: the light tree is refitted (bounds and power of
  // every node consistent with its children and lights), and rll, carrying what it learnt
  // from the earlier frames, renders the last frame as the tree sampler does.
  Scene scene = small_builtin_scene("cornell-boxes-dynamic", 32, 24);
  LightTree tree = build_light_tree(scene);
  Accel accel(scene.mesh);
  Params params;
  RllLightSampler rll(scene, tree, rll_settings_from(params));
  for (int f = 0; f < 3; ++f) {
    scene.animate(scene, f);
    scene.refresh_lights_from_mesh();
    tree.refit(scene.lights);
    accel.update_vertices(scene.mesh);
    rll.lights_changed(scene);
    train_sampler(scene, accel, rll, 8);
  }
  size_t dark = 0;
  for (uint32_t l = 0; l < scene.lights.size(); ++l) {
    const LightBounds& leaf = tree.node(tree.leaf_of(l)).bounds;
    EXPECT_EQ(leaf.power, light_bounds(scene.lights[l]).power);
    dark += leaf.power == 0;
  }
  EXPECT_GT(dark, 0u) << "frame 2 must have switched some lamps off";
  for (uint32_t i = 0; i < tree.node_count(); ++i) {
    const LightTreeNode& n = tree.node(i);
    if (n.is_leaf()) continue;
    const LightBounds &a = tree.node(n.child).bounds, &b = tree.node(n.child + 1).bounds;
    EXPECT_NEAR(n.bounds.power, a.power + b.power, 1e-3f * (a.power + b.power) + 1e-6f);
    if (!n.bounds.infinite) {
      EXPECT_TRUE(n.bounds.box.contains(a.box.lo) && n.bounds.box.contains(a.box.hi));
      EXPECT_TRUE(n.bounds.box.contains(b.box.lo) && n.bounds.box.contains(b.box.hi));
    }
  }
  // The last frame, rendered with the sampler that learnt the earlier ones, against tree.
  IntegratorSettings is;
  is.type = IntegratorType::Direct;
  Integrator with_rll(scene, accel, rll, is);
  Film film(scene.width, scene.height);
  RenderSettings rs;
  rs.spp = 512;
  rs.seed = 5;
  rs.frame = 2;
  render(scene, with_rll, rll, film, rs);
  RenderRequest t;
  t.sampler = "tree";
  t.integrator = is;
  t.spp = 512;
  const Image last = film.resolve(), ref = render_scene(scene, tree, t);
  Estimate diff = difference_estimate(last, ref);
  EXPECT_LE(std::abs(diff.mean), 4.5 * diff.stderr_) << diff.mean << " +- " << diff.stderr_;
  expect_bound_sees(last, ref, "rll's last animated frame vs tree", 0.05);  // sees 1.5%
}

TEST(RllLearning, PoolSharesFollowTheLampsThatSwitchOff) {
  // With pool_guess=ratio a cell's pool shares are its coarse cell's factors times the cell's own
  // prior. When lamps switch off or move between frames the priors change, and the shares must
  // follow at once (as a sampler loaded from the state would compute them), not keep the old
  // priors' weights until the next pass ends.
  Scene scene = small_builtin_scene("cornell-boxes-dynamic", 32, 24);
  LightTree tree = build_light_tree(scene);
  Accel accel(scene.mesh);
  Params params;
  const RllSettings settings = rll_settings_from(params);
  ASSERT_GT(settings.cut.pool_levels, 0);
  ASSERT_TRUE(settings.cut.pool_ratio);
  RllLightSampler rll(scene, tree, settings);
  scene.animate(scene, 0);
  train_sampler(scene, accel, rll, 6);
  auto shares_of = [](const RllLightSampler& s) {
    std::map<uint64_t, std::vector<float>> out;  // by cell key
    for (uint32_t c = 0; c < s.table().capacity(); ++c)
      if (const float* p = s.cuts().pool_shares(c); s.table().in_use(c) && p)
        out[s.table().key_of(c)].assign(p, p + s.cuts().initial_size());
    return out;
  };
  const auto before = shares_of(rll);
  scene.animate(scene, 1);
  scene.refresh_lights_from_mesh();
  tree.refit(scene.lights);
  accel.update_vertices(scene.mesh);
  rll.lights_changed(scene);
  const auto after = shares_of(rll);
  BinaryWriter w;
  rll.save_state(w);
  RllLightSampler loaded(scene, tree, settings);
  BinaryReader r(w.bytes(), "state");
  loaded.load_state(r);
  ASSERT_EQ(shares_of(loaded).size(), after.size());
  EXPECT_GT(after.size(), 10u);
  size_t moved = 0;
  for (const auto& [key, shares] : shares_of(loaded)) {
    ASSERT_EQ(after.count(key), 1u);
    const std::vector<float>& mine = after.at(key);
    double sum = 0;
    for (size_t k = 0; k < shares.size(); ++k) {
      EXPECT_NEAR(mine[k], shares[k], 1e-6f * (1 + shares[k]))
          << "cell " << key << ", cluster " << k;
      sum += mine[k];
    }
    EXPECT_NEAR(sum, 1.0, 1e-4);
    moved += before.count(key) && before.at(key) != mine;
  }
  EXPECT_GT(moved, 0u) << "no cell's shares changed with the lamps: the test checks nothing";
}

namespace {
// What every learnt cell of rll, trained on `scene` over `spp` samples per pixel (direct, seed
// `seed`, default passes), learnt: its clusters' shares V / sum V, by cell key.
std::map<uint64_t, std::vector<double>> learnt_after(const Scene& scene, const LightTree& tree,
                                                     const Accel& accel,
                                                     int spp, uint64_t seed,
                                                     const std::vector<std::string>& set) {
  RllLightSampler rll(scene, tree, rll_settings_from(Params::parse(set)));
  IntegratorSettings is;
  is.type = IntegratorType::Direct;
  Integrator integrator(scene, accel, rll, is);
  Film film(scene.width, scene.height);
  RenderSettings rs;
  rs.spp = spp;
  rs.seed = seed;
  render(scene, integrator, rll, film, rs);
  std::map<uint64_t, std::vector<double>> out;
  for (uint32_t c = 0; c < rll.table().capacity(); ++c)
    if (rll.table().in_use(c) && rll.cuts().learnt(c))
      out[rll.table().key_of(c)] = rll.cuts().learnt_shares(c);
  return out;
}

// The median over cells of how far the learnt shares of a cell spread across renders with other
// seeds: sqrt(sum over clusters of their variance across the renders), over the cells every
// render learnt.
double median_spread(const std::vector<std::map<uint64_t, std::vector<double>>>& runs) {
  std::vector<double> spread;
  for (const auto& [key, first] : runs[0]) {
    bool everywhere = true;
    for (const auto& run : runs) everywhere = everywhere && run.count(key) > 0;
    if (!everywhere) continue;
    double var = 0;
    for (size_t k = 0; k < first.size(); ++k) {
      double s = 0, s2 = 0;
      for (const auto& run : runs) {
        s += run.at(key)[k];
        s2 += run.at(key)[k] * run.at(key)[k];
      }
      const double n = double(runs.size());
      var += std::max(0.0, (s2 - s * s / n) / (n - 1));
    }
    spread.push_back(std::sqrt(var));
  }
  if (spread.size() < 20) return -1;
  std::sort(spread.begin(), spread.end());
  return spread[spread.size() / 2];
}
}  // namespace

TEST(RllLearning, LearntDistributionKeepsSharpeningOverALongRender) {
  // DESIGN 2b.3: in a static scene the learnt distribution keeps sharpening as rewards arrive. A
  // cell's shares are means of its rewards; with the rate at 1/n (forget=changes, the default)
  // 16 times the rewards give about a quarter of their spread across seeds. With a fixed floor
  // (forget=floor: every cluster's memory capped at the last 1/alpha = 50 rewards, v2's rule) the
  // spread stops falling once the clusters have seen 50 rewards; the test runs that rule too and
  // checks that it would fail it. An 8-cluster cut, so that every cluster passes 50 rewards
  // before 16 spp; 4 seeds.
  Scene scene = small_builtin_scene("cornell-boxes-room", 40, 30);
  const LightTree tree = build_light_tree(scene);
  Accel accel(scene.mesh);
  double ratio[2];
  for (int rule = 0; rule < 2; ++rule) {
    const std::vector<std::string> set = {"rll.cut_size=8",
                                          rule == 0 ? "rll.forget=changes" : "rll.forget=floor"};
    double spread[2];
    for (int i = 0; i < 2; ++i) {
      std::vector<std::map<uint64_t, std::vector<double>>> runs;
      for (uint64_t seed = 1; seed <= 4; ++seed)
        runs.push_back(learnt_after(scene, tree, accel, i == 0 ? 16 : 256, seed, set));
      spread[i] = median_spread(runs);
      ASSERT_GT(spread[i], 0) << "too few cells learnt in every render";
    }
    ratio[rule] = spread[1] / spread[0];
    std::printf("%s: median spread of the learnt shares across 4 seeds: %.4f at 16 spp, %.4f at "
                "256 spp (ratio %.3f)\n",
                set[1].c_str(), spread[0], spread[1], ratio[rule]);
  }
  // Measured 0.376 (1/sqrt(16) = 0.25 for a mean of 16 times the rewards; the pooled guess and
  // clusters below 50 rewards at 16 spp weigh in), and 0.608 under forget=floor: the bound tells
  // the two rules apart.
  EXPECT_LT(ratio[0], 0.5) << "the learnt shares do not sharpen with spp";
  EXPECT_GT(ratio[1], 0.5) << "the fixed floor passes too: the test has no power";
}

// rll.refine (docs/rll.md, "Finer cells where the light changes"): on spot-hall-small, whose
// spots' cones cross the cells, training marks cells refined; a point whose own cell is refined
// is sent to the cell one level finer (the cell a point of half the footprint takes), never more
// than rll.refine levels down; and at those points the sampler keeps its contract (sampled pmf ==
// pmf, pmfs sum to one, chi-square of draws, every light that can contribute has pmf > 0).
TEST(RllLearning, RefinedCellsSendTheirPointsOneLevelFinerAndKeepTheContract) {
  Scene scene = small_builtin_scene("spot-hall-small", 48, 36);
  const LightTree tree = build_light_tree(scene);
  Accel accel(scene.mesh);
  Params params = Params::parse({"rll.refine=1", "rll.refine_gain=0.1", "rll.refine_min=32"});
  RllLightSampler rll(scene, tree, rll_settings_from(params));
  train_sampler(scene, accel, rll, 16);
  const nlohmann::json d = rll.describe();
  ASSERT_GT(d["cells_refined"].get<uint32_t>(), 0u);
  const SamplerView view = rll.sampler_view();
  const RllView& v = *view.rll;
  std::vector<LightContext> refined;
  int own = 0;
  for (const LightContext& c0 : make_contexts(scene, accel, 2000, 77)) {
    LightContext c = c0;
    const float u = 0.37f;
    prepare_point(view, c, u);
    if (c.cell == kNoCell) continue;
    const CellCoord coord = rll_cell_coord(v, c, u);
    const uint32_t parent = cell_find(v.table, v.keyer.key(coord));
    ASSERT_NE(parent, CellTableView::kNone);
    const int level = rll.cuts().anchor(c.cell).level;
    if (!rll.cuts().refined(parent)) {
      EXPECT_EQ(c.cell, parent);
      ++own;
      continue;
    }
    // One level finer, the key of the point at that level, and no further (rll.refine=1).
    EXPECT_EQ(level, coord.level - 1);
    EXPECT_EQ(rll.table().key_of(c.cell), v.keyer.key(rll_cell_coord(v, c, u, true, 1)));
    refined.push_back(c);
  }
  std::printf("[ refine   ] %zu of %d points in refined cells' children (%u cells refined)\n",
              refined.size(), int(refined.size()) + own, d["cells_refined"].get<uint32_t>());
  ASSERT_GE(refined.size(), 20u);
  refined.resize(std::min<size_t>(refined.size(), 60));
  expect_sampler_contract(rll, refined, uint32_t(scene.lights.size()));
}

TEST(RllLearning, RefinedCellsRenderTheSameWhateverTheThreadCount) {
  // The disagreement sums are exact too: with refinement the learnt state, which cells are
  // refined included, and so the image do not depend on the thread count.
  Scene scene = small_builtin_scene("spot-hall-small", 40, 30);
  RenderRequest r;
  r.sampler = "rll";
  r.integrator.type = IntegratorType::Path;
  r.integrator.max_depth = 3;
  r.spp = 32;  // (children sample with their parent's table through their first pass)
  r.set = {"rll.refine=2", "rll.refine_gain=0.1", "rll.refine_min=16"};
  r.threads = 1;
  const Image one = render_scene(scene, r);
  r.threads = 2;
  const Image two = render_scene(scene, r);
  size_t differ = 0;
  for (size_t i = 0; i < one.pixel_count(); ++i) differ += !(one[i] == two[i]);
  EXPECT_EQ(differ, 0u);
  r.set = {};
  const Image off = render_scene(scene, r);
  differ = 0;
  for (size_t i = 0; i < one.pixel_count(); ++i) differ += !(one[i] == off[i]);
  EXPECT_GT(differ, 0u) << "refinement changed nothing: the test would see nothing";
}
