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
                              bool learnt_target = false, bool cluster = false,
                              int candidates = 4) {
  const Scene scene = small_builtin_scene(scene_name, w, h);
  RenderRequest r;
  r.integrator.type = type;
  r.integrator.max_depth = 3;
  r.spp = spp;
  r.sampler = sampler;
  r.seed = 11;
  const Image one = render_scene(scene, r);
  r.integrator.nee_candidates = candidates;
  r.integrator.nee_learnt_target = learnt_target;
  r.integrator.nee_cluster = cluster;
  r.seed = 12;
  const Image four = render_scene(scene, r);
  const std::string what = fmt::format(
      "{} {} {}: {} candidates{}{} vs 1", scene_name, sampler, integrator_name(type), candidates,
      learnt_target ? " (learnt target)" : "", cluster ? " from one cluster" : "");
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

// Candidates from one cluster (nee.draw=cluster, docs/nee.md): the first from rll's table, the
// others from its cluster; the record carries resampling's estimate of the cluster's
// contribution. Against rll with one sample, as above, 5% asserted: on the paper's two scenes and
// on spot-hall-small (spot lights, whose cones make the light within a cluster matter most).
TEST(ResampledNee, ClusterRoom) {
  for (IntegratorType type : {IntegratorType::Direct, IntegratorType::Path})
    expect_resampling_agrees("cornell-boxes-room", 32, 24, type, 256, "rll", 0.05, false, true, 8);
}

TEST(ResampledNee, ClusterArch) {
  for (IntegratorType type : {IntegratorType::Direct, IntegratorType::Path})
    expect_resampling_agrees("arch-interior", 32, 24, type, 256, "rll", 0.05, false, true, 8);
}

TEST(ResampledNee, ClusterSpotsLearntTarget) {
  expect_resampling_agrees("spot-hall", 320, 240, IntegratorType::Direct, 32, "rll", 0.05,
                           true, true, 8);
}
