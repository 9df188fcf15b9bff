// Every light sampler renders the same image in expectation: independent renders with
// different samplers (and seeds) agree in mean within a confidence bound.
#include <gtest/gtest.h>

#include "rll/scene/builtin.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;

namespace {

Scene small_scene(const std::string& name, int w, int h) { return small_builtin_scene(name, w, h); }

void expect_samplers_agree(const Scene& scene, IntegratorType type, int spp, const std::vector<std::string>& samplers) {
  RenderRequest base;
  base.integrator.type = type;
  base.integrator.max_depth = 3;
  base.spp = spp;
  base.sampler = samplers[0];
  base.seed = 1;
  Image reference = render_scene(scene, base);
  for (size_t i = 1; i < samplers.size(); ++i) {
    RenderRequest r = base;
    r.sampler = samplers[i];
    r.seed = 1 + i;
    Image img = render_scene(scene, r);
    Estimate d = difference_estimate(img, reference);
    EXPECT_LE(std::abs(d.mean), 4.5 * d.stderr_ + 1e-6)
        << samplers[i] << " vs " << samplers[0] << ": mean difference " << d.mean << " +- " << d.stderr_
        << " (means " << image_mean(img) << " vs " << image_mean(reference) << ")";
  }
}

// `sampler` renders the image `tree` renders: over the whole image and in each of 4 x 4 regions
// (z = 4.5 each: 17 bounds falsely fail with probability about 1e-4 together).
void expect_matches_tree_by_region(const Scene& scene, IntegratorType type, int spp, const std::string& sampler) {
  RenderRequest r;
  r.integrator.type = type;
  r.integrator.max_depth = 3;
  r.spp = spp;
  r.sampler = "tree";
  r.seed = 11;
  Image reference = render_scene(scene, r);
  r.sampler = sampler;
  r.seed = 12;
  Image img = render_scene(scene, r);
  Estimate d = difference_estimate(img, reference);
  EXPECT_LE(std::abs(d.mean), 4.5 * d.stderr_ + 1e-6)
      << sampler << " vs tree: mean difference " << d.mean << " +- " << d.stderr_ << " (means " << image_mean(img)
      << " vs " << image_mean(reference) << ")";
  const auto regions = region_differences(img, reference, 4, 4);
  for (size_t i = 0; i < regions.size(); ++i)
    EXPECT_LE(std::abs(regions[i].mean), 4.5 * regions[i].stderr_ + 1e-6)
        << sampler << " vs tree, region " << i << ": difference " << regions[i].mean << " +- " << regions[i].stderr_;
}

TEST(SamplerAgreement, CornellBoxDirect) {
  expect_samplers_agree(small_scene("cornell-box", 32, 32), IntegratorType::Direct, 64, {"power", "uniform", "tree", "rll"});
}

TEST(SamplerAgreement, CornellBoxPath) {
  expect_samplers_agree(small_scene("cornell-box", 24, 24), IntegratorType::Path, 64, {"power", "uniform", "tree", "rll"});
}

TEST(SamplerAgreement, ManyLightsOpenDirect) {
  expect_samplers_agree(small_scene("many-lights-open", 32, 24), IntegratorType::Direct, 64,
                        {"tree", "power", "uniform", "rll"});
}

TEST(SamplerAgreement, ManyLightsOpenPath) {
  expect_samplers_agree(small_scene("many-lights-open", 24, 18), IntegratorType::Path, 32, {"tree", "power", "rll"});
}

// Wang et al. 2021 (ltc) converges to the tree's image, region by region: on the occluded room
// (where its learnt cuts move most probability) and on the open scene with many lights.
TEST(SamplerAgreement, LtcMatchesTreeRoomDirect) {
  expect_matches_tree_by_region(small_scene("cornell-boxes-room", 32, 24), IntegratorType::Direct, 128, "ltc");
}

TEST(SamplerAgreement, LtcMatchesTreeRoomPath) {
  expect_matches_tree_by_region(small_scene("cornell-boxes-room", 24, 18), IntegratorType::Path, 64, "ltc");
}

TEST(SamplerAgreement, LtcMatchesTreeManyLightsDirect) {
  expect_matches_tree_by_region(small_scene("many-lights-open", 32, 24), IntegratorType::Direct, 64, "ltc");
}

TEST(SamplerAgreement, LtcMatchesTreeManyLightsPath) {
  expect_matches_tree_by_region(small_scene("many-lights-open", 24, 18), IntegratorType::Path, 32, "ltc");
}

}  // namespace

// Fermat's RLL as published (the fermat preset) converges to the tree's image, region by region.
TEST(SamplerAgreement, FermatMatchesTreeRoomDirect) {
  expect_matches_tree_by_region(small_scene("cornell-boxes-room", 32, 24), IntegratorType::Direct, 128, "fermat");
}

TEST(SamplerAgreement, FermatMatchesTreeManyLightsPath) {
  expect_matches_tree_by_region(small_scene("many-lights-open", 24, 18), IntegratorType::Path, 32, "fermat");
}
