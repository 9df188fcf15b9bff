// builtin:glazed-room renders the same with every light sampler: light reaches the room through
// Dirac glass (thin panes and glass slabs, where no light sample is taken and the sky is found by
// the BSDF ray alone) and through an open skylight (sky and sun, sampled by each light sampler).
// Each sampler's render must agree with an independent `tree` render, over the image and in each
// of 4 x 4 regions, within a bound tight enough to see a 10% bias. At 256 spp the bound on the
// mean (4.5 standard errors) is ~1.6% of the image mean; the whole file takes ~4 s on 2 cores.
// Checked to fail when one image is scaled by 1.05 and when the last bounce is left out (every
// sampler, mean and most regions).
#include <gtest/gtest.h>

#include <algorithm>

#include "rll/lights/light_sampler.h"
#include "rll/scene/builtin.h"
#include "support/power.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;

namespace {

const int kDepth = 4;
const int kSpp = 256;

const Scene& glazed_room() {
  static const Scene scene = small_builtin_scene("glazed-room", 32, 24);
  return scene;
}

const Image& tree_reference() {
  static const Image image =
      render_scene(glazed_room(), request("tree", "path", kDepth, "mis", kSpp, 1));
  return image;
}

class GlazedRoom : public ::testing::TestWithParam<std::string> {};

TEST_P(GlazedRoom, AgreesWithTree) {
  const std::string& name = GetParam();
  const auto& names = light_sampler_names();
  const uint64_t seed = 100 + uint64_t(std::find(names.begin(), names.end(), name) - names.begin());
  RenderRequest r = request(name, "path", kDepth, "mis", kSpp, seed);
  if (name == "oracle") r.set = {"oracle.points=4", "oracle.rays=2"};
  const Image& ref = tree_reference();
  Image img = render_scene(glazed_room(), r);
  EXPECT_GT(image_mean(ref), 0.01);
  expect_images_agree(img, ref, name + " vs tree");
  expect_bound_sees(img, ref, name + " vs tree", 0.05);  // sees 2-2.5% with every sampler
  // The bound must be tight enough to catch a bias of 10% of the image mean.
  Estimate d = difference_estimate(img, ref);
  EXPECT_LT(4.5 * d.stderr_, 0.10 * image_mean(ref)) << name << ": test too noisy to mean anything";
}

INSTANTIATE_TEST_SUITE_P(Samplers, GlazedRoom, ::testing::ValuesIn(light_sampler_names()),
                         [](const auto& info) { return info.param; });

}  // namespace
