// The wavefront renderer on the GPU (cuda/wavefront.h) against the CPU (issue 31): the same image
// within noise region by region as the CPU wavefront traced by the same BVH, for power, tree, rll
// and rht, direct and path, on the paper's scenes, with the bound's power shown on an image 5% too
// bright or dark; the same image for the same seed twice; rll's cell table learnt on the GPU
// passes the light-sampler checks; a sampler without a device version is refused by name.
#include <gtest/gtest.h>

#include <cstring>

#include "rll/accel/accel.h"
#include "rll/core/error.h"
#include "rll/core/params.h"
#include "rll/cuda/wavefront.h"
#include "rll/wavefront/wavefront.h"
#include "support/sampler_contexts.h"
#include "support/test_support.h"

namespace rll {
namespace {

struct Case {
  std::string scene;
  int spp_direct, spp_path;
};
// The scenes and sample counts of the CPU's wavefront agreement test (tests/render).
const std::vector<Case> kCases = {{"cornell-boxes-room", 256, 192},
                                  {"arch-interior", 256, 192},
                                  {"glazed-room", 256, 192},
                                  {"many-lights-open", 256, 192}};

Image render_on(cuda::GpuRenderer* gpu, const Scene& scene, const Accel& accel,
                LightSampler& sampler, IntegratorType type, int spp, uint64_t seed,
                int pass_spp = 0) {
  IntegratorSettings is;
  is.type = type;
  Film film(scene.width, scene.height);
  RenderSettings rs;
  rs.spp = spp;
  rs.seed = seed;
  if (pass_spp > 0) rs.pass_spp = rs.max_pass_spp = pass_spp;
  if (gpu) {
    gpu->render(scene, sampler, is, film, rs);
  } else {
    WavefrontSettings ws;
    ws.tracer = WavefrontTracer::Bvh;
    render_wavefront(scene, accel, sampler, is, film, rs, nullptr, {}, ws);
  }
  return film.resolve();
}

Image scaled(Image image, float s) {
  for (Rgb& p : image.pixels()) p = p * s;
  return image;
}

TEST(GpuWavefront, EqualsTheCpuWithinNoiseByRegion) {
  for (const Case& c : kCases) {
    Scene scene = test::small_builtin_scene(c.scene, 32, 24);
    const LightTree tree = build_light_tree(scene);
    const Accel accel(scene.mesh);
    cuda::GpuRenderer gpu(scene);
    for (const IntegratorType type : {IntegratorType::Direct, IntegratorType::Path}) {
      // rht: its reservoirs in the path slots' memory (render/rht_nee.h), as on the CPU wavefront.
      for (const char* name : {"power", "tree", "rll", "rht"}) {
        SCOPED_TRACE(c.scene + " " + integrator_name(type) + " " + name);
        const int spp = type == IntegratorType::Direct ? c.spp_direct : c.spp_path;
        auto on_cpu = make_light_sampler(name, scene, tree, Params{}, &accel);
        auto on_gpu = make_light_sampler(name, scene, tree, Params{}, &accel);
        const Image cpu = render_on(nullptr, scene, accel, *on_cpu, type, spp, 1);
        const Image gpu_image = render_on(&gpu, scene, accel, *on_gpu, type, spp, 2);
        EXPECT_EQ(test::region_disagreement(gpu_image, cpu), "");
        for (const float s : {1.05f, 0.95f})
          EXPECT_NE(test::region_disagreement(scaled(gpu_image, s), cpu), "")
              << "the comparison cannot see an image scaled by " << s;
      }
    }
  }
}

TEST(GpuWavefront, SameSeedSameImage) {
  Scene scene = test::small_builtin_scene("cornell-boxes-room", 48, 36);
  const LightTree tree = build_light_tree(scene);
  const Accel accel(scene.mesh);
  cuda::GpuRenderer gpu(scene);
  std::vector<Image> images;
  for (int run = 0; run < 2; ++run) {
    auto sampler = make_light_sampler("rll", scene, tree, Params{}, &accel);
    images.push_back(render_on(&gpu, scene, accel, *sampler, IntegratorType::Path, 16, 7, 1));
  }
  ASSERT_EQ(images[0].pixel_count(), images[1].pixel_count());
  EXPECT_EQ(std::memcmp(images[0].pixels().data(), images[1].pixels().data(),
                        images[0].pixel_count() * sizeof(Rgb)),
            0);
}

TEST(GpuWavefront, RllLearntOnTheGpuPassesTheSamplerChecks) {
  for (const char* name : {"cornell-boxes-room", "arch-interior"}) {
    SCOPED_TRACE(name);
    Scene scene = test::small_builtin_scene(name, 48, 36);
    const LightTree tree = build_light_tree(scene);
    const Accel accel(scene.mesh);
    cuda::GpuRenderer gpu(scene);
    auto sampler = make_light_sampler("rll", scene, tree, Params{}, &accel);
    auto untrained = make_light_sampler("rll", scene, tree, Params{}, &accel);
    render_on(&gpu, scene, accel, *sampler, IntegratorType::Path, 32, 1, 1);
    std::vector<LightContext> contexts = test::make_contexts(scene, accel, 100, 1234);
    const uint32_t n = uint32_t(scene.lights.size());
    int differ = 0;
    for (size_t i = 0; i < contexts.size(); ++i) {
      LightContext cold = contexts[i];
      prepare_point(sampler->sampler_view(), contexts[i], float(i % 97) / 97.0f);
      prepare_point(untrained->sampler_view(), cold, float(i % 97) / 97.0f);
      for (uint32_t l = 0; l < n; l += 7)
        differ += light_pmf(sampler->sampler_view(), contexts[i], l) !=
                  light_pmf(untrained->sampler_view(), cold, l);
    }
    EXPECT_GT(differ, 0) << "nothing was learnt on the GPU";
    test::expect_sampler_contract(*sampler, contexts, n);
  }
}

TEST(GpuWavefront, RefusesASamplerWithoutADeviceVersion) {
  Scene scene = test::small_builtin_scene("cornell-boxes-room", 16, 12);
  const LightTree tree = build_light_tree(scene);
  const Accel accel(scene.mesh);
  cuda::GpuRenderer gpu(scene);
  auto ltc = make_light_sampler("ltc", scene, tree, Params{}, &accel);
  try {
    render_on(&gpu, scene, accel, *ltc, IntegratorType::Path, 1, 1);
    FAIL() << "ltc rendered on the GPU";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("ltc"), std::string::npos) << e.what();
  }
}

// The path-space filter's temporal reuse (psf.temporal, render/psf.h) on the GPU, whose tables
// stay on the device from frame to frame: frames that follow frames blend (cells found, another
// image), the same frames for a seed twice, and a render that follows no frame is the one
// without the key to the bit.
TEST(GpuWavefront, PsfTemporalFramesBlendOnTheDevice) {
  Scene scene = test::small_builtin_scene("cornell-boxes-room", 40, 30);
  const LightTree tree = build_light_tree(scene);
  const Accel accel(scene.mesh);
  cuda::GpuRenderer gpu(scene);
  struct Frames {
    std::vector<Image> images;
    PsfCounts counts;
  };
  auto frames = [&](const std::string& temporal, bool follows) {
    const Params params = Params::parse({"psf.temporal=" + temporal});
    const IntegratorSettings is = make_integrator_settings("path", 4, params, "psf");
    auto sampler = make_light_sampler("power", scene, tree, params, &accel);
    Frames out;
    for (int f = 0; f < 3; ++f) {
      Film film(scene.width, scene.height);
      RenderSettings rs;
      rs.spp = 2;
      rs.seed = 5;
      rs.frame = f;
      rs.follows_frame = follows && f > 0;
      out.counts += gpu.render(scene, *sampler, is, film, rs).filter;
      out.images.push_back(film.resolve());
    }
    return out;
  };
  auto same = [](const Image& a, const Image& b) {
    return std::memcmp(a.pixels().data(), b.pixels().data(), a.pixel_count() * sizeof(Rgb)) == 0;
  };
  const Frames off = frames("0", true), still = frames("0.8", false);
  const Frames blended = frames("0.8", true), again = frames("0.8", true);
  EXPECT_EQ(off.counts.reused, 0u);
  EXPECT_GT(blended.counts.reused, 0u);
  EXPECT_EQ(blended.counts.reused, again.counts.reused);
  for (size_t f = 0; f < 3; ++f) {
    SCOPED_TRACE(f);
    EXPECT_TRUE(same(still.images[f], off.images[f])) << "a render that follows no frame";
    EXPECT_TRUE(same(blended.images[f], again.images[f])) << "the same seed twice";
    EXPECT_EQ(same(blended.images[f], off.images[f]), f == 0) << "blended from frame 1 on";
  }
}

}  // namespace
}  // namespace rll
