// rll's cell grid: the key of a point's cell, and the view-direction bins of glossy points
// (rll.direction_bins).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "rll/core/params.h"
#include "rll/learn/cell_grid.h"
#include "rll/lights/rll_sampler.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;

namespace {

// Cell of a point on the floor of cornell-box seen from `wo`.
uint32_t cell_of(const RllLightSampler& rll, const Scene& scene, Vec3 wo, bool glossy) {
  LightContext c;
  c.p = 0.5f * (scene.bounds.lo + scene.bounds.hi);
  c.p.y = scene.bounds.lo.y;
  c.n = c.ns = Vec3(0, 1, 0);
  c.wo = wo;
  c.glossy = glossy;
  c.footprint = 1e-3f * length(scene.bounds.diagonal());
  rll.prepare(c, 0.5f);
  return c.cell;
}

}  // namespace

TEST(CellGrid, DirectionBinsSplitGlossyPointsByViewDirection) {
  const Scene scene = small_builtin_scene("cornell-box", 16, 16);
  const Vec3 up_left = normalize(Vec3(-1, 1, 0)), up_right = normalize(Vec3(1, 1, 0));
  RllLightSampler binned(scene, rll_settings_from(Params::parse({"rll.direction_bins=4"})));
  RllLightSampler plain(scene, rll_settings_from(Params()));
  // A glossy point seen from two far-apart directions: two cells with bins, one without.
  EXPECT_NE(cell_of(binned, scene, up_left, true), cell_of(binned, scene, up_right, true));
  EXPECT_EQ(cell_of(plain, scene, up_left, true), cell_of(plain, scene, up_right, true));
  // A diffuse point, or one seen from an unknown direction, is never binned.
  EXPECT_EQ(cell_of(binned, scene, up_left, false), cell_of(binned, scene, up_right, false));
  EXPECT_EQ(cell_of(binned, scene, Vec3(0), true), cell_of(binned, scene, Vec3(0), false));
  // Nearby directions share a bin.
  EXPECT_EQ(cell_of(binned, scene, up_left, true), cell_of(binned, scene, normalize(Vec3(-1, 1.02f, 0.01f)), true));
}

TEST(CellGrid, DirectionBinsCoverTheSphereAndEnterTheKey) {
  CellGridSettings s;
  s.direction_bins = 3;
  const CellKeyer keyer(s, Bounds3{Vec3(0), Vec3(1)});
  std::vector<int> hits(9, 0);
  for (int i = 0; i < 2000; ++i) {
    const float z = 1 - 2 * (float(i) + 0.5f) / 2000, phi = 2.39996f * float(i), r = std::sqrt(1 - z * z);
    const uint32_t b = keyer.direction_bin(Vec3(r * std::cos(phi), r * std::sin(phi), z));
    ASSERT_GE(b, 1u);
    ASSERT_LE(b, 9u);
    ++hits[b - 1];
  }
  for (int h : hits) EXPECT_GT(h, 0);
  // Each bin keys its own cell.
  CellCoord c = keyer.locate_at_level(Vec3(0.3f), Vec3(0, 0, 1), -3);
  std::vector<uint64_t> keys;
  for (uint32_t dir = 0; dir <= 9; ++dir) {
    c.dir = dir;
    keys.push_back(keyer.key(c));
  }
  std::sort(keys.begin(), keys.end());
  EXPECT_EQ(std::unique(keys.begin(), keys.end()), keys.end());
}

TEST(CellGrid, LevelRoundingNearestOrStochastic) {
  // The level of detail of a footprint: with `Nearest` one level whatever u, the cell edge
  // within a factor sqrt(2) of the footprint's cell size; with `Stochastic` the level below or
  // above, the upper one for a fraction of u equal to the fractional level (so that the edge
  // follows the footprint on average).
  const Bounds3 bounds{Vec3(0), Vec3(1)};
  const float diameter = length(bounds.diagonal());
  CellGridSettings near, random;
  random.level_rounding = CellGridSettings::LevelRounding::Stochastic;
  ASSERT_EQ(near.level_rounding, CellGridSettings::LevelRounding::Nearest) << "the default";
  const CellKeyer kn(near, bounds), kr(random, bounds);
  const Vec3 p(0.3f), n(0, 0, 1);
  for (float footprint : {1e-4f, 3e-4f, 7.1e-4f, 1.5e-3f, 4e-3f}) {
    const float size = kn.cell_size(footprint), lf = std::log2(size / diameter);
    const int level = kn.locate(p, n, footprint, 0.0f).level;
    const float edge = std::ldexp(diameter, level);
    EXPECT_LE(edge, size * std::sqrt(2.0f) * 1.0001f) << footprint;
    EXPECT_GE(edge, size / std::sqrt(2.0f) * 0.9999f) << footprint;
    int upper = 0;
    const int samples = 1000;
    for (int i = 0; i < samples; ++i) {
      const float u = (float(i) + 0.5f) / samples;
      EXPECT_EQ(kn.locate(p, n, footprint, u).level, level) << "nearest must not depend on u";
      const int l = kr.locate(p, n, footprint, u).level;
      ASSERT_TRUE(l == int(std::floor(lf)) || l == int(std::floor(lf)) + 1) << l << " for " << lf;
      upper += l == int(std::floor(lf)) + 1;
    }
    EXPECT_NEAR(double(upper) / samples, lf - std::floor(lf), 2.0 / samples) << footprint;
  }
}

TEST(CellGrid, LevelRoundingIsAParameterFermatKeepsStochastic) {
  EXPECT_EQ(rll_settings_from(Params{}).grid.level_rounding,
            CellGridSettings::LevelRounding::Nearest);
  EXPECT_EQ(rll_settings_from(Params::parse({"rll.level_rounding=stochastic"})).grid.level_rounding,
            CellGridSettings::LevelRounding::Stochastic);
  EXPECT_EQ(fermat_settings().grid.level_rounding, CellGridSettings::LevelRounding::Stochastic);
  EXPECT_THROW(rll_settings_from(Params::parse({"rll.level_rounding=up"})), std::exception);
}
