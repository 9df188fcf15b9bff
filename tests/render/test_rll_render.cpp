// RLL (and the oracle) converge to the same image as the visibility-blind samplers: the mean
// per-pixel difference of independent renders is zero within a confidence bound, on the
// paper's scene, with direct lighting and with paths. And the oracle's discovery finds the cells
// that a `path` render meets.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>

#include "rll/accel/accel.h"
#include "rll/core/params.h"
#include "rll/lights/light_dispatch.h"
#include "rll/lights/oracle_sampler.h"
#include "rll/render/film.h"
#include "rll/render/render.h"
#include "rll/scene/builtin.h"
#include "rll/wavefront/wavefront.h"
#include "support/power.h"
#include "support/sampler_contexts.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;

namespace {

Scene room(int w, int h) {
  return small_builtin_scene("cornell-boxes-room", w, h);
}

void expect_same_mean(const Scene& scene, IntegratorType type, int spp, const std::string& a,
                      const std::string& b, std::vector<std::string> set_b = {}) {
  RenderRequest ra;
  ra.sampler = a;
  ra.integrator.type = type;
  ra.integrator.max_depth = 3;
  ra.spp = spp;
  ra.seed = 11;
  RenderRequest rb = ra;
  rb.sampler = b;
  rb.seed = 23;
  rb.set = std::move(set_b);
  Image ia = render_scene(scene, ra), ib = render_scene(scene, rb);
  Estimate d = difference_estimate(ib, ia);
  EXPECT_LE(std::abs(d.mean), 4.5 * d.stderr_)
      << b << " vs " << a << ": mean difference " << d.mean << " +- " << d.stderr_ << " (means "
      << image_mean(ib) << ", " << image_mean(ia) << ")";
  // The bound must be tight enough to catch a bias of 8% of the image mean.
  EXPECT_LT(4.5 * d.stderr_, 0.08 * image_mean(ia)) << "test too noisy to mean anything";
  // Sees 1-2% (rll, oracle): the 5% the issue asks for.
  expect_bound_sees(ib, ia, b + " vs " + a, 0.05);
}

}  // namespace

// Against tree, not power: on this scene power's estimator has practically unbounded variance
// (each lamp inside a box has a pmf near 1e-7 next to the sky dome), so independent power
// renders at test budgets undershoot their mean by ~40% and no confidence bound holds; power
// and RLL are compared on tamer scenes in test_sampler_agreement.cpp.
TEST(RllUnbiased, CornellBoxesRoomDirect) {
  expect_same_mean(room(32, 24), IntegratorType::Direct, 1024, "tree", "rll");
}

TEST(RllUnbiased, CornellBoxesRoomPath) {
  expect_same_mean(room(24, 18), IntegratorType::Path, 768, "tree", "rll");
}

TEST(RllUnbiased, UniformWithinAndFullPdfReward) {
  expect_same_mean(room(32, 24), IntegratorType::Direct, 1024, "tree", "rll",
                   {"rll.within=uniform", "rll.reward=fullpdf", "rll.learning=exponential"});
}

TEST(OracleUnbiased, CornellBoxesRoomDirect) {
  expect_same_mean(room(32, 24), IntegratorType::Direct, 1024, "tree", "oracle",
                   {"oracle.points=4", "oracle.rays=2"});
}

namespace {

// The oracle, counting the vertices of a render whose cell its discovery did not find: those get
// the shared initial cut's power prior instead of knowledge, and in `path` they made fireflies.
class OracleCoverage final : public LightSampler {
 public:
  explicit OracleCoverage(const OracleLightSampler& oracle)
      : LightSampler("oracle-coverage"), m_oracle(oracle), m_view(oracle.sampler_view()) {
    set_host_calls(*this);
  }
  SamplerView sampler_view() const override { return host_view(true, false); }
  void prepare(LightContext& ctx, float u) const {
    prepare_point(m_view, ctx, u);
    ++m_vertices;
    if (ctx.cell == kNoCell || !m_oracle.rll().cuts().active(ctx.cell)) ++m_missed;
  }
  SampledLight sample(const LightContext& ctx, double u) const {
    return sample_light(m_view, ctx, u);
  }
  float pmf(const LightContext& ctx, uint32_t light) const { return light_pmf(m_view, ctx, light); }
  double missed_share() const {
    return double(m_missed) / double(std::max<uint64_t>(m_vertices, 1));
  }

 private:
  const OracleLightSampler& m_oracle;
  const SamplerView m_view;  // the oracle's
  mutable std::atomic<uint64_t> m_vertices{0}, m_missed{0};
};

// The share of a `path` render's vertices whose cell the oracle (with `set` over its defaults)
// has no knowledge of. Few points and rays and no refinement: the cells it finds do not depend
// on them.
double oracle_missed_share(Scene scene, int spp, std::vector<std::string> set) {
  const LightTree tree = build_light_tree(scene);
  for (const char* fast : {"oracle.points=1", "oracle.rays=1", "oracle.refine=0"})
    set.push_back(fast);
  Params params = Params::parse(set);
  Accel accel(scene.mesh);
  auto sampler = make_light_sampler("oracle", scene, tree, params, &accel);
  params.check_all_used();
  OracleCoverage coverage(dynamic_cast<const OracleLightSampler&>(*sampler));
  render_path_passes(scene, accel, coverage, spp);
  return coverage.missed_share();
}

}  // namespace

// The oracle's default discovery finds the cells of the vertices that `path` meets, bounces
// included (docs/rll.md, "The oracle"): with 4 discovery paths per pixel it missed ~5x as many
// vertices' cells, and in `path` it had fireflies. Renders and discovery are deterministic.
TEST(OracleDiscovery, FindsTheCellsOfPathVertices) {
  const Scene scene = small_builtin_scene("cornell-boxes-room", 160, 120);
  const double bound = 1.5e-4;
  const double by_default = oracle_missed_share(scene, 8, {});
  const double four = oracle_missed_share(scene, 8, {"oracle.discovery_spp=4"});
  EXPECT_LE(by_default, bound) << "with 4 discovery paths: " << four;
  // The bound tells the old default apart (0.000061 against 0.000331 when this was written).
  EXPECT_GT(four, bound) << "test cannot tell 4 discovery paths from the default (" << by_default
                         << ")";
}

// The visible-sample ratio (the share of light samples whose shadow ray reaches the light): on a
// scene of lamps inside boxes, `tree` (blind to visibility) beats `power`, and rll, which learns
// visibility, beats `tree`. Counted by the megakernel and the wavefront alike.
TEST(VisibleSampleRatio, RllLearnsVisibilityThatTreeCannotSee) {
  Scene scene = small_builtin_scene("cornell-boxes-room", 64, 48);
  const LightTree light_tree = build_light_tree(scene);
  const Accel accel(scene.mesh);
  IntegratorSettings is;
  is.type = IntegratorType::Direct;
  RenderSettings rs;
  rs.spp = 32;
  auto ratio = [&](const char* name, bool wavefront) {
    auto sampler = make_light_sampler(name, scene, light_tree, Params{}, &accel);
    Film film(scene.width, scene.height);
    RenderProgress p;
    if (wavefront) {
      p = render_wavefront(scene, accel, *sampler, is, film, rs);
    } else {
      Integrator integrator(scene, accel, *sampler, is);
      p = render(scene, integrator, *sampler, film, rs);
    }
    EXPECT_GT(p.rays.shadow, 0u);
    EXPECT_LE(p.rays.shadow_visible, p.rays.shadow);
    return p.rays.visible_ratio();
  };
  const double power = ratio("power", false), tree = ratio("tree", false),
               rll = ratio("rll", false);
  RecordProperty("visible ratios",
                 fmt::format("power {:.3f}, tree {:.3f}, rll {:.3f}", power, tree, rll));
  EXPECT_GT(tree, 2 * power);
  EXPECT_GT(rll, 1.1 * tree);
  EXPECT_EQ(ratio("rll", true), rll);  // the wavefront counts the same rays
}

// rll.refine (docs/rll.md, "Finer cells where the light changes"): rll with refined cells, two
// levels down and a low gain so that many cells refine, converges to the image of rll without,
// over the image and in each of 4 x 4 regions (independent seeds); the render must have refined
// cells. Sees 5% (the power line prints the bias it sees).
TEST(RllUnbiased, RefinedCellsConvergeToTheSameImageByRegion) {
  Scene scene = room(32, 24);
  const LightTree tree = build_light_tree(scene);
  const std::vector<std::string> refine = {"rll.refine=2", "rll.refine_gain=0.1",
                                           "rll.refine_min=32"};
  Params params = Params::parse(refine);
  Accel accel(scene.mesh);
  auto sampler = make_light_sampler("rll", scene, tree, params, &accel);
  IntegratorSettings is;
  is.type = IntegratorType::Direct;
  Integrator integrator(scene, accel, *sampler, is);
  Film film(scene.width, scene.height);
  RenderSettings rs;
  rs.spp = 1024;
  rs.seed = 23;
  render(scene, integrator, *sampler, film, rs);
  const Image refined = film.resolve();
  const nlohmann::json d = sampler->describe();
  std::printf("[ refine   ] %u of %u cells refined\n", d["cells_refined"].get<uint32_t>(),
              d["cells_used"].get<uint32_t>());
  ASSERT_GT(d["cells_refined"].get<uint32_t>(), 10u);

  RenderRequest base;
  base.sampler = "rll";
  base.integrator.type = IntegratorType::Direct;
  base.spp = 1024;
  base.seed = 11;
  const Image reference = render_scene(scene, tree, base);
  EXPECT_EQ(region_disagreement(refined, reference), "")
      << "means " << image_mean(refined) << " vs " << image_mean(reference);
  expect_bound_sees(refined, reference, "rll refined vs rll", 0.05);
}
