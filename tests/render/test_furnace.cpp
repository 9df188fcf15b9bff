// The furnace (builtin:furnace): inside a closed emissive diffuse sphere every path of k bounces
// carries Le a^k, so the image mean is Le * sum_{k=0..d} a^k for d = max depth, for every
// integrator and light sampler. That holds exactly because the built-in sphere has flat facets
// (smooth shading normals would drop reflections below the geometric surface: ~0.2% a bounce).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include "rll/core/params.h"
#include "rll/scene/builtin.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;

namespace {

double furnace_value(int max_depth) {
  double sum = 0, ak = 1;
  for (int k = 0; k <= max_depth; ++k, ak *= kFurnaceAlbedo) sum += ak;
  return kFurnaceEmission * sum;
}

const Scene& flat_furnace() {
  static const Scene scene = [] {
    Scene s = make_builtin_scene("furnace");
    s.finalize();
    return s;
  }();
  return scene;
}

struct FurnaceCase {
  std::string sampler;
  IntegratorType type;
  int max_depth;
  std::string name() const {
    return fmt::format("{}_{}_d{}", integrator_name(type), sampler, max_depth);
  }
  friend void PrintTo(const FurnaceCase& c, std::ostream* os) { *os << c.name(); }
};

std::vector<FurnaceCase> furnace_cases() {
  std::vector<FurnaceCase> cases;
  for (std::string sampler : {"uniform", "power"}) {
    cases.push_back({sampler, IntegratorType::Direct, 1});
    for (int d : {1, 2, 3, 5}) cases.push_back({sampler, IntegratorType::Path, d});  // RR from 3
  }
  return cases;
}

class Furnace : public ::testing::TestWithParam<FurnaceCase> {};

TEST_P(Furnace, MeanIsAnalytic) {
  const FurnaceCase& c = GetParam();
  RenderRequest r;
  r.sampler = c.sampler;
  r.integrator.type = c.type;
  r.integrator.max_depth = c.max_depth;
  r.spp = 32;
  r.seed = 7;
  Image img = render_scene(flat_furnace(), r);
  Estimate e = block_estimate(img);
  const double expected = furnace_value(c.max_depth);
  RecordProperty("mean", std::to_string(e.mean));
  RecordProperty("stderr", std::to_string(e.stderr_));
  EXPECT_NEAR(e.mean, expected, 4.5 * e.stderr_ + 1e-6 * expected)
      << "mean " << e.mean << " +- " << e.stderr_ << ", analytic " << expected;
  // The bound is tight enough to see the last bounce missing.
  EXPECT_LT(4.5 * e.stderr_, 0.5 * kFurnaceEmission * std::pow(kFurnaceAlbedo, c.max_depth));
}

INSTANTIATE_TEST_SUITE_P(Integrators, Furnace, ::testing::ValuesIn(furnace_cases()),
                         [](const auto& info) { return info.param.name(); });

// Every strategy of the path integrator, BSDF-only included, on the flat furnace.
TEST(FurnaceScene, EveryStrategyIsAnalytic) {
  for (std::string strategy : {"nee", "bsdf", "mis"}) {
    RenderRequest r;
    r.integrator =
        make_integrator_settings("path", 3, Params::parse({"path.strategy=" + strategy}));
    r.spp = 32;
    r.seed = 8;
    Estimate e = block_estimate(render_scene(flat_furnace(), r));
    EXPECT_NEAR(e.mean, furnace_value(3), 4.5 * e.stderr_ + 1e-6)
        << strategy << ": mean " << e.mean << " +- " << e.stderr_;
  }
}

// The analytic answer needs flat facets: no shading normal may differ from the geometric one.
TEST(FurnaceScene, BuiltinHasFlatFacets) {
  Scene s = make_builtin_scene("furnace");
  s.finalize();
  for (const Vec3& n : s.mesh.normals) EXPECT_EQ(length_sq(n), 0.0f);
}

}  // namespace
