// The light samplers' dispatch on the GPU against the CPU (issue 31): prepare_point, sample_light,
// light_pmf and record_nee (lights/light_dispatch.h) over each sampler's SamplerView, run by
// sampler_probe on both devices (rll/cuda/sampler_check.h), on shading contexts of built-in
// scenes; rll with cells learnt by a short render.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "rll/accel/accel.h"
#include "rll/core/params.h"
#include "rll/cuda/sampler_check.h"
#include "support/sampler_contexts.h"
#include "support/test_support.h"

namespace rll {
namespace {

// Equal within float rounding: the GPU fuses multiplies and adds, so importances, and with them a
// descent's steps, may differ in their last bits; a wrong formula is off by O(1).
bool close(float a, float b) {
  if (a == b) return true;
  if (!std::isfinite(a) || !std::isfinite(b)) return false;
  return std::abs(a - b) <= 1e-3f * std::max({1.0f, std::abs(a), std::abs(b)});
}

class GpuSamplers : public ::testing::TestWithParam<std::string> {};

TEST_P(GpuSamplers, DispatchMatchesTheCpu) {
  for (const char* scene_name : {"cornell-boxes-room", "arch-interior"}) {
    Scene scene = test::small_builtin_scene(scene_name, 48, 36);
    const LightTree tree = build_light_tree(scene);
    const Accel accel(scene.mesh);
    auto sampler = make_light_sampler(GetParam(), scene, tree, Params{});
    test::train_sampler(scene, accel, *sampler, 4);
    const SamplerView view = sampler->sampler_view();
    ASSERT_NE(view.kind, SamplerKind::None);
    const std::vector<LightContext> contexts = test::make_contexts(scene, accel, 2000, 5);
    std::vector<SamplerProbe> probes;
    Pcg32 rng(17);
    const uint32_t lights = uint32_t(scene.lights.size());
    for (const LightContext& ctx : contexts)
      for (int k = 0; k < 8; ++k) {
        SamplerProbe p;
        p.ctx = ctx;
        p.u_prepare = rng.next_float();
        p.u = rng.next_double();
        p.light = rng.next_bounded(lights);
        p.estimate = rng.next_float();
        // Every probe's cell made on the CPU first, so that both devices find the same ones.
        LightContext c = ctx;
        prepare_point(sampler->sampler_view(), c, p.u_prepare);
        probes.push_back(p);
      }
    const std::vector<SamplerProbeResult> gpu = sampler_probe_gpu(view, probes);
    ASSERT_EQ(gpu.size(), probes.size());
    size_t same_light = 0;
    for (size_t i = 0; i < probes.size(); ++i) {
      const SamplerProbeResult c = sampler_probe(view, probes[i]), &g = gpu[i];
      ASSERT_EQ(c.cell, g.cell) << scene_name << " probe " << i;
      ASSERT_TRUE(close(c.pmf_of_light, g.pmf_of_light))
          << scene_name << " probe " << i << ": " << c.pmf_of_light << " " << g.pmf_of_light;
      // Each device's sample carries its own light_pmf.
      ASSERT_EQ(g.sampled.pmf, g.pmf_of_sampled) << scene_name << " probe " << i;
      ASSERT_GT(g.sampled.pmf, 0) << scene_name << " probe " << i;
      if (c.sampled.light == g.sampled.light) {
        ++same_light;
        ASSERT_TRUE(close(c.sampled.pmf, g.sampled.pmf)) << scene_name << " probe " << i;
      }
    }
    // u near a step's boundary may go the other way under different rounding: rarely.
    EXPECT_GE(double(same_light), 0.999 * double(probes.size())) << scene_name;
  }
}

INSTANTIATE_TEST_SUITE_P(Kinds, GpuSamplers,
                         ::testing::Values("uniform", "power", "tree", "rll", "fermat"));

}  // namespace
}  // namespace rll
