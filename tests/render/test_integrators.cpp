// The integrators agree in expectation: `direct` and `path` with max depth 1 estimate the same
// direct light, and the path integrator's NEE-only, BSDF-only and MIS strategies the same
// image. Independent renders (different seeds) are compared over the whole image and region
// by region, so that a bias confined to one object (the metal block) cannot hide in the mean.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>

#include "rll/core/params.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;

namespace {

// Per-pixel difference estimates over a grid of image regions.
std::vector<Estimate> region_differences(const Image& a, const Image& b, int nx, int ny) {
  std::vector<Estimate> out;
  for (int ry = 0; ry < ny; ++ry)
    for (int rx = 0; rx < nx; ++rx) {
      const int x0 = rx * a.width() / nx, x1 = (rx + 1) * a.width() / nx;
      const int y0 = ry * a.height() / ny, y1 = (ry + 1) * a.height() / ny;
      Image ra(x1 - x0, y1 - y0), rb(x1 - x0, y1 - y0);
      for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
          ra.at(x - x0, y - y0) = a.at(x, y);
          rb.at(x - x0, y - y0) = b.at(x, y);
        }
      out.push_back(difference_estimate(ra, rb));
    }
  return out;
}

// a and b agree over the image and in each of 4 x 4 regions. The regional bound is
// Bonferroni-corrected: 16 regions at z = 4.5 falsely fail with probability 1e-4 together.
void expect_images_agree(const Image& a, const Image& b, const std::string& what) {
  Estimate d = difference_estimate(a, b);
  EXPECT_LE(std::abs(d.mean), 4.5 * d.stderr_)
      << what << ": mean difference " << d.mean << " +- " << d.stderr_ << " (means "
      << image_mean(a) << ", " << image_mean(b) << ")";
  ::testing::Test::RecordProperty(
      what, fmt::format("{} +- {} (mean {})", d.mean, d.stderr_, image_mean(a)));
  const auto regions = region_differences(a, b, 4, 4);
  for (size_t i = 0; i < regions.size(); ++i)
    EXPECT_LE(std::abs(regions[i].mean), 4.5 * regions[i].stderr_)
        << what << ", region " << i << ": difference " << regions[i].mean << " +- "
        << regions[i].stderr_;
}

RenderRequest request(const std::string& sampler, const std::string& integrator, int max_depth,
                      const std::string& strategy, int spp, uint64_t seed) {
  RenderRequest r;
  r.sampler = sampler;
  std::vector<std::string> set;
  if (integrator == "path") set.push_back("path.strategy=" + strategy);
  r.integrator = make_integrator_settings(integrator, max_depth, Params::parse(set));
  r.spp = spp;
  r.seed = seed;
  return r;
}

TEST(Integrators, DirectEqualsPathDepthOneCornellBox) {
  const Scene scene = small_builtin_scene("cornell-box", 48, 48);
  Image direct = render_scene(scene, request("power", "direct", 1, "", 64, 1));
  Image path = render_scene(scene, request("power", "path", 1, "mis", 64, 1));
  expect_images_agree(direct, path, "cornell-box");
}

// A sky dome of 2048 triangles and 42 lamps inside boxes. The visibility-blind power sampler
// picks a box's own lamp with probability ~1e-5 (the sky's power dwarfs the lamps'), so that
// NEE alone would see the lamps' light only as rare spikes; the light tree finds the near lamp.
TEST(Integrators, DirectEqualsPathDepthOneUnderSky) {
  const Scene scene = small_builtin_scene("cornell-boxes-room", 64, 48);
  Image direct = render_scene(scene, request("tree", "direct", 1, "", 128, 3));
  Image path = render_scene(scene, request("tree", "path", 1, "mis", 128, 3));
  expect_images_agree(direct, path, "cornell-boxes-room");
}

TEST(Integrators, StrategiesAgreeCornellBox) {
  const Scene scene = small_builtin_scene("cornell-box", 32, 32);
  Image mis = render_scene(scene, request("power", "path", 3, "mis", 64, 5));
  Image nee = render_scene(scene, request("power", "path", 3, "nee", 64, 5));
  Image bsdf = render_scene(scene, request("power", "path", 3, "bsdf", 2048, 5));
  expect_images_agree(nee, mis, "nee vs mis");
  expect_images_agree(bsdf, mis, "bsdf vs mis");
  expect_images_agree(bsdf, nee, "bsdf vs nee");
}

}  // namespace
