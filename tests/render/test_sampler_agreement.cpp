// Every light sampler renders the same image in expectation: independent renders with
// different samplers (and seeds) agree in mean within a confidence bound.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <algorithm>
#include <cstdio>

#include "rll/scene/builtin.h"
#include "support/biased_sampler.h"
#include "support/power.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;

namespace {

Scene small_scene(const std::string& name, int w, int h) {
  return small_builtin_scene(name, w, h);
}

void expect_samplers_agree(const Scene& scene, IntegratorType type, int spp,
                           const std::vector<std::string>& samplers, double power) {
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
        << samplers[i] << " vs " << samplers[0] << ": mean difference " << d.mean << " +- "
        << d.stderr_ << " (means " << image_mean(img) << " vs " << image_mean(reference) << ")";
    expect_bound_sees(img, reference, samplers[i] + " vs " + samplers[0], power);
  }
}

// The reference of the region-wise tests: `tree` at seed 11, depth 3.
RenderRequest tree_request(IntegratorType type, int spp) {
  RenderRequest r;
  r.integrator.type = type;
  r.integrator.max_depth = 3;
  r.spp = spp;
  r.sampler = "tree";
  r.seed = 11;
  return r;
}

// `sampler` renders the image `tree` renders: over the whole image and in each of 4 x 4 regions
// (z = 4.5 each: 17 bounds falsely fail with probability about 1e-4 together).
void expect_matches_tree_by_region(const Scene& scene, IntegratorType type, int spp,
                                   const std::string& sampler, double power,
                                   const std::vector<std::string>& set = {}) {
  RenderRequest r = tree_request(type, spp);
  Image reference = render_scene(scene, r);
  r.sampler = sampler;
  r.set = set;
  r.seed = 12;
  Image img = render_scene(scene, r);
  EXPECT_EQ(region_disagreement(img, reference), "")
      << sampler << " vs tree (means " << image_mean(img) << " vs " << image_mean(reference) << ")";
  expect_bound_sees(img, reference, sampler + " vs tree", power);
}

// How many of the bounds of expect_matches_tree_by_region (the whole image, 4 x 4 regions) reject
// `img` against `reference`; prints the largest z.
int rejecting_bounds(const Image& img, const Image& reference, const std::string& what) {
  std::vector<Estimate> bounds = region_differences(img, reference, 4, 4);
  bounds.push_back(difference_estimate(img, reference));
  int rejecting = 0;
  double largest_z = 0;
  for (const Estimate& d : bounds) {
    rejecting += std::abs(d.mean) > 4.5 * d.stderr_ + 1e-6;
    largest_z = std::max(largest_z, std::abs(d.mean) / std::max(d.stderr_, 1e-30));
  }
  std::printf("[ power    ] %s: %d of %zu bounds reject it (largest z %.1f)\n", what.c_str(),
              rejecting, bounds.size(), largest_z);
  return rejecting;
}

// The region bounds' power against a sampler bug rather than a uniformly scaled image: `tree`
// wrapped to report one group of lights as 5% less likely than it draws them, which makes that
// group's next-event light 5% too bright (BiasedSampler::Pmf::Understated). The group is the
// brightest node of the tree with at most `group_lights` lights.
void expect_regions_see_group_bias(const Scene& scene, IntegratorType type, int spp,
                                   uint32_t group_lights) {
  RenderRequest r = tree_request(type, spp);
  const Image reference = render_scene(scene, r);
  r.seed = 12;
  std::vector<uint32_t> group;  // in the render's light order, which its tree sets
  const SamplerWrap wrap = [&](LightSampler& tree, const Scene& lit,
                               const LightTree& light_tree) -> std::unique_ptr<LightSampler> {
    group = brightest_light_group(lit, light_tree, group_lights);
    return std::make_unique<BiasedSampler>(tree, group, 1.05, BiasedSampler::Pmf::Understated);
  };
  const Image biased = render_scene_wrapped(scene, r, wrap);
  EXPECT_GT(rejecting_bounds(biased, reference,
                             fmt::format("tree with {} lights 5% too bright", group.size())),
            0)
      << "the region bounds cannot see a 5% bias of one light group";
}

// Power (the smallest bias of the whole image the bound sees both ways, measured): each test
// asserts about 1.25x its figure, 5% where it sees that. Where it is above 5% the count was not
// raised: the figures fall as 1/sqrt(spp), so 5% would take 2-20x the samples (bench them first).
// The regions see a 5% bias in 0-14 of 16 (printed as "[ power    ]").

// Sees 3.0-3.5%.
TEST(SamplerAgreement, CornellBoxDirect) {
  expect_samplers_agree(small_scene("cornell-box", 32, 32), IntegratorType::Direct, 64,
                        {"power", "uniform", "tree", "rll"}, 0.05);
}

// Sees 5.5% (uniform), 7% (tree), 10% (rll).
TEST(SamplerAgreement, CornellBoxPath) {
  expect_samplers_agree(small_scene("cornell-box", 24, 24), IntegratorType::Path, 64,
                        {"power", "uniform", "tree", "rll"}, 0.13);
}

// Sees 9% (power), 11% (uniform), 6.5% (rll).
TEST(SamplerAgreement, ManyLightsOpenDirect) {
  expect_samplers_agree(small_scene("many-lights-open", 32, 24), IntegratorType::Direct, 64,
                        {"tree", "power", "uniform", "rll"}, 0.14);
}

// Sees 23% (power), 15% (rll).
TEST(SamplerAgreement, ManyLightsOpenPath) {
  expect_samplers_agree(small_scene("many-lights-open", 24, 18), IntegratorType::Path, 32,
                        {"tree", "power", "rll"}, 0.29);
}

// Wang et al. 2021 (ltc) converges to the tree's image, region by region: on the occluded room
// (where its learnt cuts move most probability) and on the open scene with many lights.
// Sees 4%.
TEST(SamplerAgreement, LtcMatchesTreeRoomDirect) {
  expect_matches_tree_by_region(small_scene("cornell-boxes-room", 32, 24), IntegratorType::Direct,
                                128, "ltc", 0.05);
}

// Sees 9%.
TEST(SamplerAgreement, LtcMatchesTreeRoomPath) {
  expect_matches_tree_by_region(small_scene("cornell-boxes-room", 24, 18), IntegratorType::Path, 64,
                                "ltc", 0.12);
}

// Sees 7%.
TEST(SamplerAgreement, LtcMatchesTreeManyLightsDirect) {
  expect_matches_tree_by_region(small_scene("many-lights-open", 32, 24), IntegratorType::Direct, 64,
                                "ltc", 0.09);
}

// Sees 17.5%.
TEST(SamplerAgreement, LtcMatchesTreeManyLightsPath) {
  expect_matches_tree_by_region(small_scene("many-lights-open", 24, 18), IntegratorType::Path, 32,
                                "ltc", 0.22);
}

}  // namespace

// Fermat's RLL as published (the fermat preset) converges to the tree's image, region by region.
// Sees 8%.
TEST(SamplerAgreement, FermatMatchesTreeRoomDirect) {
  expect_matches_tree_by_region(small_scene("cornell-boxes-room", 32, 24), IntegratorType::Direct,
                                128, "fermat", 0.10);
}

// Sees 23%.
TEST(SamplerAgreement, FermatMatchesTreeManyLightsPath) {
  expect_matches_tree_by_region(small_scene("many-lights-open", 24, 18), IntegratorType::Path, 32,
                                "fermat", 0.29);
}

// Half of the 10,240 lights of many-lights-open 5% too bright: seen at 256 spp by 2 of the 17
// bounds (largest z 4.7), so 384 spp. On cornell-boxes-room, half of the lights (825 sky-dome
// triangles) 5% too bright moved the direct image's mean by 0.04% at 512 spp: no bound there sees
// it.
TEST(SamplerAgreement, RegionBoundsSeeAFivePercentBiasOfOneLightGroup) {
  const Scene scene = small_scene("many-lights-open", 32, 24);
  expect_regions_see_group_bias(scene, IntegratorType::Direct, 384,
                                uint32_t(scene.lights.size() / 2));
}

// The resampled hierarchical tree (rht, docs/rht.md: several candidates per draw, two reservoir
// stages, a shadow ray per kept sample) converges to the tree's image, region by region: on the
// occluded room (local lamps and a sky dome), on arch-interior (a sky dome and a directional sun,
// chosen first) and on the open scene with many lights; at rht's defaults (four shadow rays a
// vertex) and at the public code's setting (one).
// Sees 3%.
TEST(SamplerAgreement, RhtMatchesTreeRoomDirect) {
  expect_matches_tree_by_region(small_scene("cornell-boxes-room", 32, 24), IntegratorType::Direct,
                                192, "rht", 0.05);
}

// Sees 9%.
TEST(SamplerAgreement, RhtMatchesTreeRoomPath) {
  expect_matches_tree_by_region(small_scene("cornell-boxes-room", 24, 18), IntegratorType::Path,
                                64, "rht", 0.12);
}

// Sees 4%.
TEST(SamplerAgreement, RhtMatchesTreeArchDirect) {
  expect_matches_tree_by_region(small_scene("arch-interior", 32, 24), IntegratorType::Direct, 128,
                                "rht", 0.05);
}

// Sees 11%.
TEST(SamplerAgreement, RhtMatchesTreeArchPath) {
  expect_matches_tree_by_region(small_scene("arch-interior", 24, 18), IntegratorType::Path, 64,
                                "rht", 0.14);
}

// The public code's setting: gamma 0.2, 16 first-stage reservoirs, one shadow ray.
// Sees 4%.
TEST(SamplerAgreement, RhtCodeSettingMatchesTreeRoomDirect) {
  expect_matches_tree_by_region(small_scene("cornell-boxes-room", 32, 24), IntegratorType::Direct,
                                192, "rht", 0.05,
                                {"rht.gamma=0.2", "rht.reservoirs=16", "rht.samples=1"});
}

// Sees 7.5%.
TEST(SamplerAgreement, RhtMatchesTreeManyLightsDirect) {
  expect_matches_tree_by_region(small_scene("many-lights-open", 32, 24), IntegratorType::Direct, 64,
                                "rht", 0.095);
}

// screen-hall: three large textured emitters (split into 8,333 lights of nearly equal power)
// beside 12 small lamps, behind partitions. Every sampler renders tree's image, region by region.
// Sees 3.5% (power, rll, rht), 4.0% (ltc), 4.5% (fermat); at 64 spp 6-6.5%.
TEST(SamplerAgreement, TexturedEmittersMatchTreeByRegionPath) {
  const Scene scene = small_scene("screen-hall", 32, 24);
  for (const char* sampler : {"power", "rll", "ltc", "rht", "fermat"})
    expect_matches_tree_by_region(scene, IntegratorType::Path, 128, sampler, 0.05);
}

// spot-hall-small: spot, goniometric and projection lights and point lamps in occluded rooms
// (every light kind in one tree; spot-hall is 102,400 of its spots). Every sampler renders tree's
// image, region by region, path. The spots' narrow cones make a noisy image: at 1024 spp the
// bounds see a bias of the whole image of 8.5% (power), 17.5% (rll: its cells at 32x24 see few
// samples each), 6% (ltc), 5% (rht), 8% (fermat); each case asserts its own, with some room.
TEST(SamplerAgreement, LightKindsMatchTreeByRegionPath) {
  const Scene scene = small_scene("spot-hall-small", 32, 24);
  const std::pair<const char*, double> cases[] = {
      {"power", 0.10}, {"rll", 0.20}, {"ltc", 0.07}, {"rht", 0.06}, {"fermat", 0.09}};
  for (const auto& [sampler, sees] : cases)
    expect_matches_tree_by_region(scene, IntegratorType::Path, 1024, sampler, sees);
}

// The brightest node of at most 6,000 lights (5,659 pieces of the textured emitters) 5% too
// bright: seen by 1 of the 17 bounds at 128 spp (largest z 4.9), barely. A node of 2,686 pieces
// 5% too bright is seen by none (largest z 3.0 at 64 spp, 4.2 at 128, 3.3 at 256): through MIS a
// biased pmf moves only the light-sampled share of the emitters' light.
TEST(SamplerAgreement, TexturedEmitterRegionBoundsSeeAFivePercentBias) {
  expect_regions_see_group_bias(small_scene("screen-hall", 32, 24), IntegratorType::Path, 128, 6000);
}

