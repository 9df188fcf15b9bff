// A pass cut part way (by a time budget or a Ctrl-C) leaves the pixels it reached more samples
// than the rest; the film counts each pixel's own samples, so the image still converges to the
// full render's (issue 45: equal-time renders end on the budget, and the last pass may be cut).
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <thread>

#include "rll/accel/accel.h"
#include "rll/core/params.h"
#include "rll/lights/light_sampler.h"
#include "rll/render/film.h"
#include "rll/render/render.h"
#include "support/power.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;

namespace {

struct CutRender {
  Image image;
  uint32_t fewest = 0, most = 0;  // samples of a pixel
  int passes = 0;
};

// `sampler` on `scene`, direct light, passes of 64, 64, 128, 128 ... samples per pixel up to `spp`,
// cancelled by another thread about half way through the third pass (after the second pass, it
// waits as long as that pass took; the third is twice as long).
CutRender cut_render(const Scene& scene, const LightTree& tree, const std::string& sampler,
                     const std::vector<std::string>& set, int spp, uint64_t seed) {
  Params params = Params::parse(set);
  Accel accel(scene.mesh);
  auto s = make_light_sampler(sampler, scene, tree, params, &accel);
  IntegratorSettings is;
  is.type = IntegratorType::Direct;
  Integrator integrator(scene, accel, *s, is);
  Film film(scene.width, scene.height);
  RenderSettings rs;
  rs.spp = spp;
  rs.seed = seed;
  rs.pass_spp = 64;
  rs.max_pass_spp = 128;
  std::atomic<bool> cancel{false};
  std::thread canceller;
  double before = 0;
  const RenderProgress p =
      render(scene, integrator, *s, film, rs, &cancel, [&](const RenderProgress& pr, const Film&) {
        if (pr.passes == 1) before = pr.seconds;
        if (pr.passes != 2) return;
        const auto wait = std::chrono::duration<double>(pr.seconds - before);
        canceller = std::thread([&cancel, wait] {
          std::this_thread::sleep_for(wait);
          cancel = true;
        });
      });
  if (canceller.joinable()) canceller.join();
  CutRender out;
  out.image = film.resolve();
  out.fewest = film.min_count();
  out.most = *std::max_element(film.counts().begin(), film.counts().end());
  out.passes = p.passes;
  return out;
}

}  // namespace

// rll (its end of pass learns from the cut pass's rewards too) cut part way against tree's full
// render, over the image and in each of 4 x 4 regions. Sees 5%.
TEST(CutPass, ImageAgreesWithAFullRenderByRegion) {
  Scene scene = small_builtin_scene("cornell-boxes-room", 32, 24);
  const LightTree tree = build_light_tree(scene);
  const std::vector<std::string> set = {"rll.capacity=4096"};
  CutRender cut;
  // The cut must fall inside a pass (pixels with unequal counts); a machine stalled past the
  // whole third pass cuts a later one, and one stalled past the render tries again.
  for (int attempt = 0; attempt < 3 && cut.fewest == cut.most; ++attempt)
    cut = cut_render(scene, tree, "rll", set, 1024, 2 + attempt);
  ASSERT_LT(cut.fewest, cut.most) << "no render was cut inside a pass";
  EXPECT_GE(cut.fewest, 128u);  // the first two passes are whole
  std::printf("[ cut      ] pixels hold %u to %u samples after %d passes\n", cut.fewest, cut.most,
              cut.passes);

  RenderRequest full;
  full.sampler = "tree";
  full.integrator.type = IntegratorType::Direct;
  full.spp = 512;
  full.seed = 11;
  const Image reference = render_scene(scene, tree, full);
  EXPECT_EQ(region_disagreement(cut.image, reference), "")
      << "means " << image_mean(cut.image) << " vs " << image_mean(reference);
  expect_bound_sees(cut.image, reference, "cut rll vs tree", 0.05);
}
