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

}  // namespace
