// Randomness is keyed by (seed, pixel, sample, dimension), never by thread: the same seed gives
// the same image bit for bit with one thread or two, and another seed gives another image.
#include <gtest/gtest.h>

#include <cstring>

#include "support/test_support.h"

using namespace rll;
using namespace rll::test;

namespace {

bool bit_identical(const Image& a, const Image& b) {
  return a.width() == b.width() && a.height() == b.height() &&
         std::memcmp(a.pixels().data(), b.pixels().data(), a.pixel_count() * sizeof(Rgb)) == 0;
}

size_t differing_pixels(const Image& a, const Image& b) {
  size_t n = 0;
  for (size_t i = 0; i < a.pixel_count(); ++i) n += a[i] == b[i] ? 0 : 1;
  return n;
}

class Determinism : public ::testing::TestWithParam<std::tuple<std::string, PointSet>> {};

TEST_P(Determinism, SameSeedSameImageWithAnyThreadCount) {
  // 40 x 36: not a multiple of the 16-pixel tiles.
  const Scene scene = small_builtin_scene("cornell-box", 40, 36);
  RenderRequest r;
  r.sampler = std::get<0>(GetParam());
  r.points = std::get<1>(GetParam());
  r.integrator.max_depth = 4;  // Russian roulette from depth 3 draws numbers too
  r.spp = 8;
  r.seed = 12345;
  r.threads = 1;
  const Image one = render_scene(scene, r);
  r.threads = 2;
  const Image two = render_scene(scene, r);
  EXPECT_TRUE(bit_identical(one, two)) << differing_pixels(one, two) << " pixels differ";
  EXPECT_GT(image_mean(one), 0);

  r.seed = 12346;
  const Image other = render_scene(scene, r);
  // Noise differs nearly everywhere (a few pixels see only the black background or the lamp).
  EXPECT_GT(differing_pixels(one, other), one.pixel_count() * 9 / 10);
}

INSTANTIATE_TEST_SUITE_P(Samplers, Determinism,
                         ::testing::Combine(::testing::Values("power", "uniform"),
                                            ::testing::Values(PointSet::Sobol, PointSet::Independent)),
                         [](const auto& info) {
                           return std::get<0>(info.param) + "_" + point_set_name(std::get<1>(info.param));
                         });

}  // namespace
