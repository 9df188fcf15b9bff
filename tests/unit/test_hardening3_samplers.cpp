// Hardening III, the samplers' part (issue 42): every pre-render computation is bounded by a cost
// estimate checked first and stops at the cancel flag (a textured emitter tiled a thousand times,
// the oracle's plan of shadow rays); ltc's tables are checked against the memory budget before
// they exist; a light whose power overflows a float is sampled as one of the largest power the
// samplers weigh, so that the other lights still light the image under every sampler; the
// diagnostics that were all NaN (rht's probability) or a stand-in (the oracle's rewards, 1e30)
// measure something.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <ctime>
#include <limits>
#include <thread>

#include "rll/accel/accel.h"
#include "rll/core/long_work.h"
#include "rll/core/params.h"
#include "rll/core/rng.h"
#include "rll/lights/light_sampler.h"
#include "rll/lights/oracle_sampler.h"
#include "rll/lights/simple_samplers.h"
#include "rll/lighttree/light_bounds.h"
#include "rll/lighttree/light_tree.h"
#include "rll/render/aov.h"
#include "rll/render/film.h"
#include "rll/render/render.h"
#include "rll/scene/builder.h"
#include "rll/scene/textured_emitters.h"
#include "support/test_support.h"

using namespace rll;
using rll::test::error_of;
using rll::test::expect_mentions;

namespace {

// The sanitizers run the same work several times slower: their bounds are ten times wider (still
// far below the hours these loops took before their fix).
#if defined(__SANITIZE_ADDRESS__)
constexpr double kSlowdown = 10;
#else
constexpr double kSlowdown = 1;
#endif

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// The process's CPU seconds (all threads): a bound on work that a loaded machine cannot trip.
double cpu_seconds() {
  return double(std::clock()) / CLOCKS_PER_SEC;
}

Image random_texture(int w, int h, uint64_t seed) {
  Image img(w, h);
  Pcg32 rng(seed);
  for (size_t i = 0; i < img.pixel_count(); ++i)
    img[i] = Rgb(rng.next_float(), rng.next_float(), rng.next_float());
  return img;
}

// `quads` side by side, each a textured emitter whose uvs run from 0 to `tiles` (the texture
// repeated tiles x tiles times over it), in front of a diffuse wall.
Scene tiled_emitter_scene(int texture, float tiles, int quads) {
  Scene s;
  s.source = "tiled";
  SceneBuilder b(s);
  s.textures.push_back(random_texture(texture, texture, 5));
  Material m;
  m.name = "tiled";
  m.emission = Rgb(1);
  m.emission_texture = 0;
  const uint32_t mat = b.material(m);
  for (int q = 0; q < quads; ++q) {
    b.quad(Vec3(float(q), 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), mat);
    for (const Vec2& uv : {Vec2{0, 0}, Vec2{tiles, 0}, Vec2{tiles, tiles}, Vec2{0, tiles}})
      s.mesh.uvs.push_back(uv);
  }
  const size_t wall_first = s.mesh.positions.size();
  b.quad(Vec3(-1, -1, -1), Vec3(float(quads) + 2, 0, 0), Vec3(0, 3, 0), b.diffuse(Rgb(0.5f)));
  s.mesh.uvs.resize(s.mesh.positions.size(), Vec2{0, 0});
  EXPECT_EQ(s.mesh.positions.size(), wall_first + 4);
  return s;
}

size_t warnings_with(const Scene& s, const std::string& part) {
  size_t n = 0;
  for (const auto& w : s.warnings) n += w.find(part) != std::string::npos;
  return n;
}

}  // namespace

// The probe's case: one quad tiling a 256^2 texture 1000 x 1000 times covers 6.6e10 texel cells;
// the exact integration walked 2^26 of them for every one of the thousands of pieces its split
// made (hours). Now its cost is known first, and what is beyond the budget comes from points.
TEST(Hardening3Samplers, TexturedEmitterTiledAThousandTimesLoadsInSeconds) {
  Scene s = tiled_emitter_scene(256, 1000, 1);
  const double texture_mean = [&] {
    double sum = 0;
    for (const Rgb& c : s.textures[0].pixels()) sum += luminance(c);
    return sum / double(s.textures[0].pixel_count());
  }();
  const double t0 = cpu_seconds();
  s.finalize();
  EXPECT_LT(cpu_seconds() - t0, 20.0 * kSlowdown);  // about 4 (hours before)
  EXPECT_EQ(warnings_with(s, "64 x 64 points"), 1u) << "said once";
  expect_mentions(s.warnings.back(),
                  {"tiled", "texture tiled many times", "not integrated exactly"});
  // Split into many lights all the same, whose power is the quad's (1 m^2, the texture's mean
  // over a thousand tiles each way) to the accuracy of the points.
  EXPECT_GT(s.lights.size(), 1000u);
  double power = 0;
  for (const Light& l : s.lights) power += light_power(l, s.radius);
  EXPECT_NEAR(power, kPi * texture_mean, 0.02 * kPi * texture_mean);
}

// A variant the probe did not try: many triangles each under the per-triangle bound (1.3e7 cells
// each, exact one by one), 4e8 cells together before the split multiplies them (minutes).
TEST(Hardening3Samplers, ManyLargeTexturedTrianglesShareOneBudget) {
  Scene s = tiled_emitter_scene(1024, 5, 16);
  for (uint32_t t = 0; t < 2; ++t) {
    const double cost = exact_integration_cost(s.textures[0].texel_view(), triangle_uvs(s, t));
    EXPECT_LT(cost, double(kMaxExactTextureCells));
    EXPECT_GT(cost, 1e7);
  }
  const double t0 = cpu_seconds();
  s.finalize();
  EXPECT_LT(cpu_seconds() - t0, 20.0 * kSlowdown);  // about 4 (minutes before)
  EXPECT_EQ(warnings_with(s, "64 x 64 points"), 1u);
}

// Scenes within the budget are integrated exactly as before: the cost estimate bounds the loop's
// trip count from above, so nothing that was exact falls back.
TEST(Hardening3Samplers, ExactIntegrationCostBoundsTheCellsVisited) {
  const Image tex = random_texture(37, 23, 3);
  Pcg32 rng(11);
  for (int k = 0; k < 200; ++k) {
    std::array<Vec2, 3> uv;
    for (Vec2& p : uv) p = Vec2{-3 + 6 * rng.next_float(), -3 + 6 * rng.next_float()};
    const double cost = exact_integration_cost(tex.texel_view(), uv);
    // Exact with room for exactly the estimate; an estimate of the cells cannot be below the
    // area in cells.
    EXPECT_TRUE(integrate_texture(tex.texel_view(), uv, size_t(std::ceil(cost))).exact) << k;
    const double area = 0.5 *
                        std::abs((uv[1].x - uv[0].x) * (uv[2].y - uv[0].y) -
                                 (uv[2].x - uv[0].x) * (uv[1].y - uv[0].y)) *
                        37 * 23;
    EXPECT_GE(cost, area) << k;
  }
}

// oracle.points=4096:rays=4096 are in range, and on a scene of many lights planned 2e10 shadow
// rays even at 32 x 32 (hours with no word): refused after discovery, before the first shadow
// ray, naming the keys.
TEST(Hardening3Samplers, OracleRefusesAPlanBeyondItsBound) {
  Scene s = rll::test::small_builtin_scene("cornell-boxes-room", 32, 32);
  const LightTree tree = build_light_tree(s);
  Accel accel(s.mesh);
  for (const std::vector<std::string>& set :
       {std::vector<std::string>{"oracle.points=4096", "oracle.rays=4096"},
        // A variant: few rays but a refinement of 4096 steps per cell.
        std::vector<std::string>{"oracle.points=4096", "oracle.rays=64", "oracle.refine=4096"}}) {
    const Params p = Params::parse(set);
    const auto t0 = std::chrono::steady_clock::now();
    const std::string msg = error_of([&] { make_light_sampler("oracle", s, tree, p, &accel); });
    EXPECT_LT(seconds_since(t0), 20.0 * kSlowdown) << msg;
    expect_mentions(msg, {"shadow rays", "oracle.points=4096", "oracle.rays=", "oracle.refine=",
                          "lower oracle.points, oracle.rays or oracle.refine"});
  }
}

// The precompute polls the cancel flag the front end's signal handler sets: a plan of minutes
// stops at once, and says it was interrupted.
TEST(Hardening3Samplers, OraclePrecomputeStopsAtTheCancelFlag) {
  Scene s = rll::test::small_builtin_scene("cornell-box", 32, 32);
  const LightTree tree = build_light_tree(s);
  Accel accel(s.mesh);
  // About 4e8 shadow rays planned (under the bound): minutes here, a minute on a large machine.
  const Params p = Params::parse({"oracle.points=4096", "oracle.rays=4096"});
  std::atomic<bool> cancel{false};
  CancelScope scope(&cancel);
  // As a signal handler would, a second into the estimates (discovery at 32 x 32 takes less).
  std::thread signal([&] {
    std::this_thread::sleep_for(std::chrono::seconds(1));
    cancel = true;
  });
  const auto t0 = std::chrono::steady_clock::now();
  auto sampler = make_light_sampler("oracle", s, tree, p, &accel);
  signal.join();
  EXPECT_LT(seconds_since(t0), 20.0 * kSlowdown);
  const auto* oracle = dynamic_cast<const OracleLightSampler*>(sampler.get());
  ASSERT_NE(oracle, nullptr);
  EXPECT_TRUE(oracle->interrupted());
  const nlohmann::json d = oracle->describe()["oracle"];
  EXPECT_TRUE(d["interrupted"].get<bool>());
  EXPECT_LT(d["shadow_rays"].get<double>(), 2e8) << "stopped well before its plan";
}

// ltc.capacity's largest value (2^24 entries of 64 node slots: 99 GB) was allocated unchecked
// while rll.capacity is checked: refused before allocating, with the keys and what to do.
TEST(Hardening3Samplers, LtcTablesBeyondTheBudgetAreRefusedBeforeAllocating) {
  Scene s = rll::test::small_builtin_scene("cornell-box", 8, 8);
  const LightTree tree = build_light_tree(s);
  EXPECT_REFUSED_IN_BOUNDED_MEMORY(
      make_light_sampler("ltc", s, tree, Params::parse({"ltc.capacity=16777216"}), nullptr),
      "ltc.capacity=16777216.*needs .*lower ltc.capacity");
  // A variant: the key table (spatial clusters x direction bins^2: 2^17 x 32^2 keys, 2 GiB)
  // against a small budget.
  {
    rll::test::BudgetScope budget(size_t(1) << 30);
    const std::string msg = error_of([&] {
      make_light_sampler("ltc", s, tree, Params::parse({"ltc.clusters=131072", "ltc.bins=32"}),
                         nullptr);
    });
    expect_mentions(msg, {"ltc.bins=32", "spatial clusters", "more than", "lower ltc.capacity"});
  }
  // Small tables still fit the small budget.
  {
    rll::test::BudgetScope budget(size_t(1) << 30);
    EXPECT_NO_THROW(make_light_sampler(
        "ltc", s, tree, Params::parse({"ltc.clusters=64", "ltc.capacity=4096"}), nullptr));
  }
}

namespace {

// The camera of the wall scenes below, 5 in front of the wall, looking at it; finalizes the scene.
void look_at_wall(Scene& s) {
  s.camera.position = Vec3(0, 0, 5);
  s.camera.target = Vec3(0, 0, 0);
  s.camera.up = Vec3(0, 1, 0);
  s.camera.fov = 45;
  s.has_camera = true;
  s.finalize();
}

// A wall lit by an ordinary area light, and a 1 x 1 area light of radiance `huge` (3e38: a power
// of 4.7e38 per triangle, beyond a float) at its right, facing away from it (+x): it lights
// nothing in view, so the image is the ordinary light's alone (with `huge` 0 the same geometry
// without the light). `facing_wall`: the huge light over the wall's right half, facing it.
Scene huge_light_scene(float huge, bool facing_wall = false) {
  Scene s;
  s.source = "huge";
  s.width = 48;
  s.height = 32;
  SceneBuilder b(s);
  b.quad(Vec3(-2, -1, 0), Vec3(4, 0, 0), Vec3(0, 2, 0), b.diffuse(Rgb(0.5f)));  // faces +z
  // The ordinary light: 0.5 x 0.5 at z = 1 above the left half, facing the wall (-z).
  b.quad(Vec3(-1.5f, -0.25f, 1), Vec3(0, 0.5f, 0), Vec3(0.5f, 0, 0),
         b.emitter(Rgb(40), false, "lamp"));
  const uint32_t big = huge > 0 ? b.emitter(Rgb(huge), false, "sun") : b.diffuse(Rgb(0.5f));
  if (facing_wall)  // at z = 0.5 over the right half, facing the wall (-z)
    b.quad(Vec3(0.5f, -0.5f, 0.5f), Vec3(0, 1, 0), Vec3(1, 0, 0), big);
  else  // at x = 2.5, facing +x: the wall is behind it
    b.quad(Vec3(2.5f, -0.5f, -0.5f), Vec3(0, 1, 0), Vec3(0, 0, 1), big);
  look_at_wall(s);
  return s;
}

const std::vector<std::string>& all_samplers() {
  return light_sampler_names();
}

// Settings that keep each sampler quick on a tiny scene.
std::vector<std::string> quick_settings(const std::string& sampler) {
  if (sampler == "oracle") return {"oracle.discovery_spp=2", "oracle.points=8", "oracle.rays=4"};
  if (sampler == "ltc") return {"ltc.clusters=64", "ltc.capacity=4096"};
  return {};
}

bool finite_image(const Image& img) {
  for (const Rgb& c : img.pixels())
    if (!std::isfinite(c.x) || !std::isfinite(c.y) || !std::isfinite(c.z)) return false;
  return true;
}

}  // namespace

// Before: the power sum overflowed to inf, every pmf was NaN or 0, and under power and tree the
// whole image went black, the other lights' light with it, without a word. Now every sampler
// renders the ordinary light's image as it would without the huge light (a light facing away
// contributes nothing), and the light is named in a warning.
TEST(Hardening3Samplers, HugePowerLightLeavesTheOtherLightsTheirShareUnderEverySampler) {
  const Scene huge = huge_light_scene(3e38f), plain = huge_light_scene(0);
  ASSERT_EQ(huge.lights.size(), plain.lights.size() + 2);  // two triangles
  EXPECT_FALSE(std::isfinite(light_power(huge.lights.back(), huge.radius)));
  // The tree's build (a render session's) says so once, into the scene's warnings.
  Scene lit = huge;
  build_light_tree(lit);
  ASSERT_EQ(warnings_with(lit, "more power than a float holds"), 1u);
  expect_mentions(lit.warnings.back(), {"huge", "material 'sun'", "lower their radiance"});
  for (const std::string& name : all_samplers()) {
    SCOPED_TRACE(name);
    auto req = rll::test::request(name, "direct", 1, "mis", 16, 7);
    req.set = quick_settings(name);
    const Image a = rll::test::render_scene(huge, req), b = rll::test::render_scene(plain, req);
    EXPECT_TRUE(finite_image(a));
    const double ma = rll::test::image_mean(a), mb = rll::test::image_mean(b);
    ASSERT_GT(mb, 0.01);
    EXPECT_NEAR(ma / mb, 1.0, 0.15) << "with the huge light " << ma << ", without " << mb;
  }
}

namespace {
// The wall and lamp of huge_light_scene with four quads of radiance 1e38 facing the wall: each
// triangle's power is finite, their sum is not.
Scene four_huge_lights_scene() {
  Scene s;
  s.source = "four";
  s.width = 48;
  s.height = 32;
  SceneBuilder b(s);
  b.quad(Vec3(-2, -1, 0), Vec3(4, 0, 0), Vec3(0, 2, 0), b.diffuse(Rgb(0.5f)));
  b.quad(Vec3(-1.5f, -0.25f, 1), Vec3(0, 0.5f, 0), Vec3(0.5f, 0, 0), b.emitter(Rgb(40)));
  const uint32_t big = b.emitter(Rgb(1e38f), false, "sun");
  for (int k = 0; k < 4; ++k)  // each 0.2 x 1.5: a power of 4.7e37 per triangle
    b.quad(Vec3(0.5f + 0.3f * float(k), -0.75f, 0.5f), Vec3(0, 1.5f, 0), Vec3(0.2f, 0, 0), big);
  look_at_wall(s);
  return s;
}
}  // namespace

// The probe's case, the huge light lighting the wall, and a variant it did not try: eight lights
// each of a finite power (4.7e37) whose sum overflows. The image is lit (the huge lights' part is
// enormous), finite wherever a float holds it, and never all black or NaN.
TEST(Hardening3Samplers, HugePowerLightsLightingTheSceneGiveALitImage) {
  const Scene one = huge_light_scene(3e38f, true), four = four_huge_lights_scene();
  for (const Scene* scene : {&one, &four}) {
    SCOPED_TRACE(scene->source);
    // Sums of the capped powers are finite.
    Scene lit = *scene;
    const LightTree tree = build_light_tree(lit);
    EXPECT_TRUE(std::isfinite(tree.node(LightTree::kRoot).bounds.power));
    double uniform = 0;  // uniform's, which never looked at power (the list's first)
    for (const std::string& name : all_samplers()) {
      SCOPED_TRACE(name);
      auto req = rll::test::request(name, "direct", 1, "mis", 4, 3);
      req.set = quick_settings(name);
      const Image img = rll::test::render_scene(*scene, req);
      // The wall's left half, lit by the lamp and, far more, by the huge lights (their
      // hemisphere takes it all in): about 1e36 (before: NaN pmfs left it black under power, tree
      // and ltc, and dimmed it under rht, rll and the oracle).
      double left = 0;
      size_t nan = 0;
      for (int y = 0; y < img.height(); ++y)
        for (int x = 0; x < img.width() / 2; ++x) {
          const Rgb& c = img.at(x, y);
          if (std::isnan(c.x))
            ++nan;
          else
            left += c.x / (img.height() * (img.width() / 2));
        }
      EXPECT_EQ(nan, 0u);
      if (name == "uniform") uniform = left;
      EXPECT_GT(uniform, 1e34);
      // 4 spp: the learning samplers are within 40% of uniform's here, all within 1% at 64 spp.
      EXPECT_GT(left, 0.5 * uniform);
      EXPECT_LT(left, 2 * uniform);
    }
  }
}

// light_powers (the power sampler) and light_bounds (the tree, rll, ltc, rht, the oracle) cap the
// same lights, and nothing else: an ordinary light's power is what it was, to the bit.
TEST(Hardening3Samplers, PowerCapActsOnlyBeyondIt) {
  const Light ordinary =
      make_triangle_light(Vec3(0), Vec3(1, 0, 0), Vec3(0, 1, 0), Rgb(1e20f), true, 0);
  EXPECT_EQ(light_bounds(ordinary).power, light_bounds_uncapped(ordinary).power);
  EXPECT_EQ(light_bounds(ordinary).power, light_power(ordinary, 1));
  const Light huge =
      make_triangle_light(Vec3(0), Vec3(10, 0, 0), Vec3(0, 10, 0), Rgb(3e38f), true, 0);
  EXPECT_FALSE(std::isfinite(light_bounds_uncapped(huge).power));
  const LightBounds b = light_bounds(huge);
  EXPECT_EQ(b.power, kMaxSamplingPower);
  EXPECT_EQ(b.side_power, kMaxSamplingPower / 2);  // two-sided
  // The near-field bound stays the light's area.
  const ImportanceBounds f = importance_bounds(b);
  EXPECT_NEAR(f.min_dist2, 50.0f, 0.01f);
  // Importance never overflows, even a hair away.
  const float near = light_importance(b, Vec3(1, 1, 1e-30f), Vec3(0, 0, -1));
  EXPECT_TRUE(std::isfinite(near));
  EXPECT_GT(near, 0);
}

namespace {

// Renders with the diagnostics measured and returns them.
std::vector<std::pair<std::string, std::vector<float>>> render_aovs(const Scene& given,
                                                                    const std::string& name,
                                                                    const std::vector<Aov>& aovs) {
  Params params = Params::parse(quick_settings(name));
  Scene scene = given;  // in the order of a light tree of its own, as a render session's
  const LightTree tree = build_light_tree(scene);
  Accel accel(scene.mesh);
  auto sampler = make_light_sampler(name, scene, tree, params, &accel);
  IntegratorSettings is;
  is.max_depth = 1;
  Integrator integrator(scene, accel, *sampler, is);
  Film film(scene.width, scene.height);
  film.track_camera_vertex();
  RenderSettings rs;
  rs.spp = 4;
  render(scene, integrator, *sampler, film, rs);
  return resolve_aovs(film, *sampler, aovs);
}

}  // namespace

// rht's `probability` was NaN at every pixel (its samples have no one pmf): now the mean of its
// samples' rht pmfs. The oracle's `rewards` were its stand-in 1e30: now the shadow rays of the
// cell's estimates.
TEST(Hardening3Samplers, DiagnosticsMeasureSomethingForEverySampler) {
  const Scene s = rll::test::small_builtin_scene("cornell-box", 24, 24);
  {
    const auto out = render_aovs(s, "rht", {Aov::Probability});
    size_t finite = 0;
    for (float v : out[0].second) {
      if (std::isnan(v)) continue;
      ++finite;
      EXPECT_GT(v, 0);
      EXPECT_LE(v, 1.0f + 1e-5f);
    }
    EXPECT_GT(finite, out[0].second.size() / 2);
  }
  {
    const auto out = render_aovs(s, "oracle", {Aov::Rewards});
    size_t finite = 0, traced = 0;
    for (float v : out[0].second) {
      if (std::isnan(v)) continue;
      ++finite;
      traced += v > 0;  // 0 where no light faces the cell: no shadow ray was worth tracing
      EXPECT_GE(v, 0);
      EXPECT_LT(v, 1e9f) << "a stand-in, not a count";
    }
    EXPECT_GT(finite, out[0].second.size() / 2);
    EXPECT_GT(traced, finite / 2);
  }
}
