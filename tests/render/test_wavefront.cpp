// The wavefront renderer (rll/wavefront) against the megakernel (render/): the same image within
// noise region by region for power, tree and rll, direct and path, on the paper's scenes, with the
// bound's power shown on an image 5% too bright; the same image to the bit for the same seed where
// the sampler learns nothing within a pass; bit-identical for any thread count and slot budget;
// and rll's cell table learnt by the wavefront renderer passes the light-sampler checks.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <algorithm>
#include <cstring>

#include "rll/accel/accel.h"
#include "rll/core/parallel.h"
#include "rll/core/params.h"
#include "rll/render/integrator.h"
#include "rll/wavefront/wavefront.h"
#include "support/sampler_contexts.h"
#include "support/statistics.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;

namespace {

struct Render {
  std::string sampler = "power";
  IntegratorType type = IntegratorType::Path;
  int spp = 8;
  uint64_t seed = 1;
  bool wavefront = true;
  int threads = 0;
  uint32_t path_slots = WavefrontSettings{}.path_slots;
  WavefrontTracer tracer = WavefrontTracer::Embree;
  int nee_candidates = 1;
  WavefrontTimes* times = nullptr;
};

// A scene rendered by one of the two renderers with a fresh sampler: its image and film counts.
Image render_image(const Scene& scene, const LightTree& tree, const Accel& accel, const Render& r,
                   RenderProgress* progress = nullptr) {
  ThreadLimit limit(r.threads);
  Params params;
  auto sampler = make_light_sampler(r.sampler, scene, tree, params, &accel);
  IntegratorSettings is;
  is.type = r.type;
  is.nee_candidates = r.nee_candidates;
  Film film(scene.width, scene.height);
  RenderSettings rs;
  rs.spp = r.spp;
  rs.seed = r.seed;
  RenderProgress p;
  if (r.wavefront) {
    WavefrontSettings ws;
    ws.path_slots = r.path_slots;
    ws.times = r.times;
    ws.tracer = r.tracer;
    p = render_wavefront(scene, accel, *sampler, is, film, rs, nullptr, {}, ws);
  } else {
    Integrator integrator(scene, accel, *sampler, is);
    p = render(scene, integrator, *sampler, film, rs);
  }
  if (progress) *progress = p;
  return film.resolve();
}

bool same_bits(const Image& a, const Image& b) {
  return a.pixel_count() == b.pixel_count() &&
         std::memcmp(a.pixels().data(), b.pixels().data(), a.pixel_count() * sizeof(Rgb)) == 0;
}

Image scaled(Image image, float s) {
  for (Rgb& p : image.pixels()) p = p * s;
  return image;
}

struct SceneCase {
  std::string name;
  int width, height, spp_direct, spp_path;
  // `power`'s samples per pixel (both integrators) and the bias its comparison is shown to catch.
  int power_spp;
  float power_bias;
};

// tree and rll are shown to catch a 5% bias at the scene's sample counts. `power` needs 3-4x more
// (768 spp; the renders are still under 2.5 s a pair) where it catches 5%: there its image's
// z for a 5% bias, without the noise of the unbiased difference, is about 6-15. On arch-interior
// it cannot: that z is 4.9 at 256 spp but 0.8 at 768 (direct), 0.2 at 192 and 0.3 at 768 (path),
// falling as samples are added, the mark of rare large samples (a few paths that find the
// lights through the small windows) whose variance swamps the mean; it keeps its 15% at the
// scene's counts, which the region bounds see.
const std::vector<SceneCase> kScenes = {{"cornell-boxes-room", 32, 24, 256, 192, 768, 0.05f},
                                        {"arch-interior", 32, 24, 256, 192, 0, 0.15f},
                                        {"glazed-room", 32, 24, 256, 192, 768, 0.05f},
                                        {"many-lights-open", 32, 24, 256, 192, 768, 0.05f}};
const std::vector<std::string> kSamplers = {"power", "tree", "rll"};

class WavefrontAgreement : public ::testing::TestWithParam<std::tuple<size_t, IntegratorType>> {};

// The wavefront's image of `r` with another seed, traced by Embree and by rll's own BVH (the GPU's
// traversal, run here on the CPU), against the megakernel's: within noise over the image and in
// 4 x 4 regions, and the bound's power shown: an image `bias` too bright, or too dark, is caught.
void expect_wavefront_agrees(const Scene& scene, const LightTree& tree, const Accel& accel,
                             Render r, const Image& megakernel, float bias) {
  r.wavefront = true;
  for (const WavefrontTracer tracer : {WavefrontTracer::Embree, WavefrontTracer::Bvh}) {
    SCOPED_TRACE(tracer == WavefrontTracer::Bvh ? "rll's BVH" : "Embree");
    r.tracer = tracer;
    r.seed = 2;  // independent of the megakernel's samples
    const Image wavefront = render_image(scene, tree, accel, r);
    EXPECT_EQ(region_disagreement(wavefront, megakernel), "");
    for (const float scale : {1 + bias, 1 - bias}) {
      const Image biased = scaled(wavefront, scale);
      const Estimate d = difference_estimate(biased, megakernel);
      EXPECT_NE(region_disagreement(biased, megakernel), "")
          << "the comparison cannot see an image scaled by " << scale << " at these settings: z "
          << d.mean / d.stderr_;
    }
  }
}

TEST_P(WavefrontAgreement, EqualsMegakernelWithinNoiseByRegion) {
  const SceneCase& sc = kScenes[std::get<0>(GetParam())];
  const IntegratorType type = std::get<1>(GetParam());
  Scene scene = small_builtin_scene(sc.name, sc.width, sc.height);
  const LightTree tree = build_light_tree(scene);
  const Accel accel(scene.mesh);
  for (const std::string& sampler : kSamplers) {
    SCOPED_TRACE(sampler);
    Render r;
    r.sampler = sampler;
    r.type = type;
    r.spp = type == IntegratorType::Direct ? sc.spp_direct : sc.spp_path;
    float bias = 0.05f;
    if (sampler == "power") {
      if (sc.power_spp > 0) r.spp = sc.power_spp;
      bias = sc.power_bias;
    }
    r.wavefront = false;
    r.seed = 1;
    expect_wavefront_agrees(scene, tree, accel, r, render_image(scene, tree, accel, r), bias);
  }
}

// Where the sampler learns nothing within a pass, the wavefront takes each path through the same
// functions with the same numbers as the megakernel: the same film, to the bit.
void expect_megakernels_image_to_the_bit(Scene scene, IntegratorType type) {
  const LightTree tree = build_light_tree(scene);
  const Accel accel(scene.mesh);
  // One light sample per vertex, the reservoir's choice of four (nee.candidates=4), and rht's
  // several samples a vertex (render/nee_draw.h).
  for (const auto& [sampler, candidates] :
       {std::pair{"power", 1}, std::pair{"tree", 1}, std::pair{"tree", 4}, std::pair{"rht", 1}}) {
    SCOPED_TRACE(fmt::format("{}, nee.candidates={}", sampler, candidates));
    Render r;
    r.sampler = sampler;
    r.type = type;
    r.spp = 4;
    r.nee_candidates = candidates;
    r.wavefront = false;
    RenderProgress pm, pw;
    const Image megakernel = render_image(scene, tree, accel, r, &pm);
    r.wavefront = true;
    r.path_slots = 500;  // several batches per pass
    const Image wavefront = render_image(scene, tree, accel, r, &pw);
    EXPECT_TRUE(same_bits(wavefront, megakernel)) << sampler;
    EXPECT_EQ(pw.rays.camera, pm.rays.camera) << sampler;
    EXPECT_EQ(pw.rays.bounce, pm.rays.bounce) << sampler;
    EXPECT_EQ(pw.rays.shadow, pm.rays.shadow) << sampler;
    EXPECT_EQ(pw.rays.shadow_visible, pm.rays.shadow_visible) << sampler;
    EXPECT_LE(pm.rays.shadow_visible, pm.rays.shadow) << sampler;
    EXPECT_EQ(pw.spp_done, pm.spp_done);
    EXPECT_EQ(pw.passes, pm.passes);
  }
}

TEST_P(WavefrontAgreement, SameSeedGivesTheMegakernelsImageToTheBit) {
  const SceneCase& sc = kScenes[std::get<0>(GetParam())];
  expect_megakernels_image_to_the_bit(small_builtin_scene(sc.name, sc.width / 2, sc.height / 2),
                                      std::get<1>(GetParam()));
}

// Spot lights (and a point light, a lamp and a sun beside them): the same film, to the bit.
TEST(Wavefront, SpotLightsGiveTheMegakernelsImageToTheBit) {
  const Scene scene = small_builtin_scene("spot-hall-small", 32, 24);
  for (const IntegratorType type : {IntegratorType::Direct, IntegratorType::Path}) {
    SCOPED_TRACE(integrator_name(type));
    expect_megakernels_image_to_the_bit(scene, type);
  }
}

// rht draws several samples a vertex, each with its own shadow ray: the wavefront keeps a sample
// slot for each (nee_draws_per_vertex) and must give the megakernel's image within noise, whole
// and in each of 4 x 4 regions, by Embree and by rll's BVH, with other seeds. Power: a 5% brighter
// or darker image is caught at these settings (the bound's own check below; measured at about
// 3% on both integrators).
TEST(Wavefront, RhtEqualsMegakernelWithinNoiseByRegion) {
  Scene scene = small_builtin_scene("cornell-boxes-room", 32, 24);
  const LightTree tree = build_light_tree(scene);
  const Accel accel(scene.mesh);
  for (const IntegratorType type : {IntegratorType::Direct, IntegratorType::Path}) {
    SCOPED_TRACE(integrator_name(type));
    Render r;
    r.sampler = "rht";
    r.type = type;
    r.spp = type == IntegratorType::Direct ? 128 : 96;
    r.seed = 1;
    expect_wavefront_agrees(scene, tree, accel, r, render_image(scene, tree, accel, r), 0.05f);
  }
}

std::string agreement_name(
    const ::testing::TestParamInfo<std::tuple<size_t, IntegratorType>>& info) {
  std::string s =
      kScenes[std::get<0>(info.param)].name + "_" + integrator_name(std::get<1>(info.param));
  for (auto& ch : s)
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  return s;
}

INSTANTIATE_TEST_SUITE_P(Scenes, WavefrontAgreement,
                         ::testing::Combine(::testing::Range<size_t>(0, kScenes.size()),
                                            ::testing::Values(IntegratorType::Direct,
                                                              IntegratorType::Path)),
                         agreement_name);

// rll learns while rendering (records from every thread, end_pass between passes): its image is
// still the same to the bit with 1, 2 and 4 threads, and with any budget of path slots.
TEST(Wavefront, BitIdenticalForAnyThreadCount) {
  Scene scene = small_builtin_scene("cornell-boxes-room", 24, 18);
  const LightTree tree = build_light_tree(scene);
  const Accel accel(scene.mesh);
  Render r;
  r.sampler = "rll";
  r.spp = 12;
  r.threads = 1;
  const Image one = render_image(scene, tree, accel, r);
  for (int threads : {2, 4}) {
    r.threads = threads;
    EXPECT_TRUE(same_bits(render_image(scene, tree, accel, r), one)) << threads << " threads";
  }
  r.path_slots = 777;
  EXPECT_TRUE(same_bits(render_image(scene, tree, accel, r), one)) << "777 path slots";
  r.seed = 2;  // the comparison can fail: another seed gives another image
  EXPECT_FALSE(same_bits(render_image(scene, tree, accel, r), one));
}

// The stage times (--stats of `rll interactive`): filled when asked for, without changing the
// image; every stage that ran took time, and the stages fit in the render's total.
TEST(Wavefront, StageTimesAreRecordedWithoutChangingTheImage) {
  Scene scene = small_builtin_scene("cornell-boxes-room", 24, 18);
  const LightTree tree = build_light_tree(scene);
  const Accel accel(scene.mesh);
  Render r;
  r.sampler = "rll";
  r.spp = 4;
  r.path_slots = 300;  // several batches per pass
  const Image plain = render_image(scene, tree, accel, r);
  WavefrontTimes times;
  r.times = &times;
  EXPECT_TRUE(same_bits(render_image(scene, tree, accel, r), plain));
  for (size_t s = 0; s < kWavefrontStages; ++s)  // (ReSTIR's only with a restir sampler)
    if (!is_restir_stage(s)) {
      EXPECT_GT(times.stage_seconds[s], 0.0) << kWavefrontStageNames[s];
    }
  EXPECT_LE(times.stages_sum(), times.total_seconds);
  // A second render adds to the record.
  const WavefrontTimes first = times;
  render_image(scene, tree, accel, r);
  EXPECT_GT(times.total_seconds, first.total_seconds);
  EXPECT_GT(times[WavefrontStage::ClosestHit],
            first.stage_seconds[size_t(WavefrontStage::ClosestHit)]);
}

// The light-sampler contract on an rll cell table learnt by the wavefront renderer: sample's pmf
// equals pmf() exactly, pmfs sum to one, sampled counts fit N * pmf, and stratified u draws each
// light N * pmf times to within two draws.
TEST(Wavefront, RllLearntByTheWavefrontPassesTheSamplerChecks) {
  for (const char* name : {"cornell-boxes-room", "arch-interior"}) {
    SCOPED_TRACE(name);
    Scene scene = small_builtin_scene(name, 48, 36);
    const LightTree tree = build_light_tree(scene);
    const Accel accel(scene.mesh);
    Params params;
    auto sampler = make_light_sampler("rll", scene, tree, params, &accel);
    IntegratorSettings is;
    is.max_depth = 3;
    Film film(scene.width, scene.height);
    RenderSettings rs;
    rs.spp = 32;
    rs.pass_spp = rs.max_pass_spp = 1;  // 32 passes: strongly non-uniform cells
    render_wavefront(scene, accel, *sampler, is, film, rs);
    // The same passes by the megakernel learn the same table; an untrained one differs.
    auto by_megakernel = make_light_sampler("rll", scene, tree, params, &accel);
    Integrator integrator(scene, accel, *by_megakernel, is);
    Film film2(scene.width, scene.height);
    render(scene, integrator, *by_megakernel, film2, rs);
    auto untrained = make_light_sampler("rll", scene, tree, params, &accel);

    std::vector<LightContext> contexts = make_contexts(scene, accel, 100, 1234);
    const uint32_t n = uint32_t(scene.lights.size());
    int differ_from_untrained = 0;
    for (size_t i = 0; i < contexts.size(); ++i) {
      LightContext mk = contexts[i], cold = contexts[i];
      prepare_point(sampler->sampler_view(), contexts[i], float(i % 97) / 97.0f);
      prepare_point(by_megakernel->sampler_view(), mk, float(i % 97) / 97.0f);
      prepare_point(untrained->sampler_view(), cold, float(i % 97) / 97.0f);
      for (uint32_t l = 0; l < n; l += 7) {
        const float p = light_pmf(sampler->sampler_view(), contexts[i], l);
        ASSERT_EQ(p, light_pmf(by_megakernel->sampler_view(), mk, l))
            << "context " << i << " light " << l;
        differ_from_untrained += p != light_pmf(untrained->sampler_view(), cold, l);
      }
    }
    EXPECT_GT(differ_from_untrained, 0) << "nothing was learnt";
    expect_sampler_contract(*sampler, contexts, n);
  }
}

}  // namespace
