// Resampled next-event estimation (nee.candidates = M, docs/nee.md) converges to the image of one
// light sample per vertex, for every sampler it sits on, region by region.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include "support/power.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;

namespace {

// `sampler` with M = 4 candidates against itself with one, other seeds: the whole image and each
// of 4 x 4 regions within 4.5 standard errors (17 bounds falsely fail with probability about
// 1e-4 together), and the bound must see the image made `power` brighter and darker.
// With `learnt_target`, the M = 4 render resamples by the learnt target (nee.target=learnt).
void expect_resampling_agrees(const std::string& scene_name, int w, int h, IntegratorType type,
                              int spp, const std::string& sampler, double power,
                              bool learnt_target = false) {
  const Scene scene = small_builtin_scene(scene_name, w, h);
  RenderRequest r;
  r.integrator.type = type;
  r.integrator.max_depth = 3;
  r.spp = spp;
  r.sampler = sampler;
  r.seed = 11;
  const Image one = render_scene(scene, r);
  r.integrator.nee_candidates = 4;
  r.integrator.nee_learnt_target = learnt_target;
  r.seed = 12;
  const Image four = render_scene(scene, r);
  const std::string what =
      fmt::format("{} {} {}: 4 candidates{} vs 1", scene_name, sampler, integrator_name(type),
                  learnt_target ? " (learnt target)" : "");
  EXPECT_EQ(region_disagreement(four, one), "")
      << what << " (means " << image_mean(four) << " vs " << image_mean(one) << ")";
  expect_bound_sees(four, one, what, power);
}

}  // namespace

// Power, measured (the smallest bias of the whole image the bound sees both ways): 5% asserted
// wherever it is seen. power at 512 spp sees 4% on cornell-boxes-room (tree and rll at 256 spp
// 2-3%). On arch-interior power is the exception: the sun and sky dome, bright unshadowed and
// behind the walls for most points, win most resamplings and are then occluded, and a dim
// visible candidate kept in their place carries the sum of the weights: rare large values
// (docs/nee.md), so its bound sees 29% (direct) and 49% (path) at 512 spp; asserted at 1.25x.
// power at 512 spp asserted at `power_bias`, tree and rll at 256 spp at 5%.
void expect_resampling_agrees_for_samplers(const std::string& scene, IntegratorType type,
                                           double power_bias) {
  expect_resampling_agrees(scene, 32, 24, type, 512, "power", power_bias);
  for (const char* s : {"tree", "rll"}) expect_resampling_agrees(scene, 32, 24, type, 256, s, 0.05);
}

TEST(ResampledNee, RoomDirect) {
  expect_resampling_agrees_for_samplers("cornell-boxes-room", IntegratorType::Direct, 0.05);
}

TEST(ResampledNee, RoomPath) {
  expect_resampling_agrees_for_samplers("cornell-boxes-room", IntegratorType::Path, 0.05);
}

TEST(ResampledNee, ArchDirect) {
  expect_resampling_agrees_for_samplers("arch-interior", IntegratorType::Direct, 0.37);
}

TEST(ResampledNee, ArchPath) {
  expect_resampling_agrees_for_samplers("arch-interior", IntegratorType::Path, 0.61);
}

// rll with the learnt target (nee.target=learnt: the unshadowed target times the cell's learnt
// visibility factor of the candidate's cluster, docs/nee.md) against rll with one sample, as
// above: 5% asserted (measured: the bound sees 2.0-3.5% of the image).
TEST(ResampledNee, LearntTargetRoom) {
  for (IntegratorType type : {IntegratorType::Direct, IntegratorType::Path})
    expect_resampling_agrees("cornell-boxes-room", 32, 24, type, 256, "rll", 0.05, true);
}

TEST(ResampledNee, LearntTargetArch) {
  for (IntegratorType type : {IntegratorType::Direct, IntegratorType::Path})
    expect_resampling_agrees("arch-interior", 32, 24, type, 256, "rll", 0.05, true);
}
