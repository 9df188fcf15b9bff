// Path-space filtering (--filter psf, render/psf.h): on the furnace, whose radiance is the same
// everywhere, the filtered image is the analytic one (the filter's bias is zero there); at a
// width tending to zero every path is alone in its cell and the filtered image converges to the
// unfiltered one; a seed gives the same image to the bit with any thread count, any budget of
// path slots, on the megakernel and the wavefront (Embree's or rll's BVH); a table that would not
// fit the memory budget is refused before it is allocated.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "rll/accel/accel.h"
#include "rll/core/error.h"
#include "rll/core/parallel.h"
#include "rll/core/params.h"
#include "rll/render/integrator.h"
#include "rll/render/render.h"
#include "rll/scene/builder.h"
#include "rll/scene/builtin.h"
#include "rll/wavefront/wavefront.h"
#include "support/small_scene.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;

namespace {

struct PsfRender {
  std::string sampler = "power";
  std::string integrator = "path";
  int max_depth = 4;
  std::vector<std::string> set;  // psf.* and other keys
  bool filter = true;
  int spp = 4;
  uint64_t seed = 1;
  int threads = 0;
  bool wavefront = false;
  WavefrontTracer tracer = WavefrontTracer::Embree;
  uint32_t path_slots = 0;
};

struct PsfResult {
  Image image;
  RenderProgress progress;
};

PsfResult render_psf(const Scene& scene, const LightTree& tree, const Accel& accel,
                     const PsfRender& r) {
  ThreadLimit limit(r.threads);
  const Params params = Params::parse(r.set);
  auto sampler = make_light_sampler(r.sampler, scene, tree, params, &accel);
  const IntegratorSettings is =
      make_integrator_settings(r.integrator, r.max_depth, params, r.filter ? "psf" : "none");
  params.check_all_used();
  Film film(scene.width, scene.height);
  RenderSettings rs;
  rs.spp = r.spp;
  rs.seed = r.seed;
  PsfResult out;
  if (r.wavefront) {
    WavefrontSettings ws;
    ws.tracer = r.tracer;
    ws.path_slots = r.path_slots;
    out.progress = render_wavefront(scene, accel, *sampler, is, film, rs, nullptr, {}, ws);
  } else {
    Integrator integrator(scene, accel, *sampler, is);
    out.progress = render(scene, integrator, *sampler, film, rs);
  }
  out.image = film.resolve();
  return out;
}

struct Fixture : SmallScene {
  using SmallScene::SmallScene;
  PsfResult render(const PsfRender& r) const { return render_psf(scene, tree, *accel, r); }
};

bool same_bits(const Image& a, const Image& b) {
  return a.pixel_count() == b.pixel_count() &&
         std::memcmp(a.pixels().data(), b.pixels().data(), a.pixel_count() * sizeof(Rgb)) == 0;
}

double furnace_value(int max_depth) {
  double sum = 0, ak = 1;
  for (int k = 0; k <= max_depth; ++k, ak *= kFurnaceAlbedo) sum += ak;
  return kFurnaceEmission * sum;
}

// The furnace's radiance is Le sum a^k at every point and in every direction, so every cell's mean
// is an unbiased estimate of what each of its paths would have brought back alone: the filtered
// image is the analytic one, over the image and region by region, at the default width and a wide
// one, cut at the camera vertex and at deeper vertices, path and direct. 16 renders of one sample
// per pixel give each mean and its standard error (15 degrees of freedom: 5.5 of them bound a
// false failure at about 1e-4 for each of the 17 means). Demodulated (the default: the cells
// average radiance over the albedo, 0.5) and not.
TEST(PsfFurnace, FilteredImageIsTheAnalyticRadiance) {
  const Fixture f("furnace", 32, 32);
  struct Case {
    std::string integrator;
    int max_depth;
    std::vector<std::string> set;
  };
  for (const Case& c : std::vector<Case>{{"path", 3, {}},
                                         {"path", 3, {"psf.demodulate=0"}},
                                         {"path", 3, {"psf.depth=0", "psf.width=12"}},
                                         {"path", 5, {"psf.depth=2"}},
                                         {"direct", 1, {}}}) {
    const std::string what = fmt::format("{} depth {} {}", c.integrator, c.max_depth,
                                         c.set.empty() ? "defaults" : c.set[0]);
    SCOPED_TRACE(what);
    std::vector<Image> renders;
    PsfCounts counts;
    uint64_t samples = 0;
    for (uint64_t seed = 1; seed <= 16; ++seed) {
      PsfRender r;
      r.integrator = c.integrator;
      r.max_depth = c.max_depth;
      r.set = c.set;
      r.spp = 1;
      r.seed = seed;
      const PsfResult res = f.render(r);
      renders.push_back(res.image);
      counts += res.progress.filter;
      samples += res.progress.samples;
    }
    // The filter ran: most paths were cut, and cells were shared.
    EXPECT_GT(counts.paths, samples / 2);
    EXPECT_LT(counts.cells * 2, counts.paths);
    const double expected = furnace_value(c.max_depth);
    const SeedEstimates e = over_seeds(renders);
    EXPECT_NEAR(e.image.mean, expected, 5.5 * e.image.stderr_ + 1e-5)
        << "mean " << e.image.mean << " +- " << e.image.stderr_ << ", analytic " << expected;
    for (size_t i = 0; i < e.regions.size(); ++i)
      EXPECT_NEAR(e.regions[i].mean, expected, 5.5 * e.regions[i].stderr_ + 1e-5)
          << "region " << i << ": " << e.regions[i].mean << " +- " << e.regions[i].stderr_;
    // The bound sees a 2% bias (a cell mean that counted its paths wrongly, a splat missing).
    EXPECT_LT(5.5 * e.image.stderr_, 0.02 * expected);
  }
}

// At a width tending to zero each path is alone in its cell, whose mean is then its own radiance:
// the filtered image converges to the unfiltered one (a render with another seed), region by
// region. At the default width, the filtered image is another one (the filter ran and shares).
TEST(PsfWidth, TinyWidthConvergesToTheUnfilteredImage) {
  const Fixture f("cornell-box", 48, 48);
  PsfRender r;
  r.spp = 32;
  r.seed = 3;
  r.set = {"psf.width=1e-4", "psf.clamp=0", "psf.depth=0"};
  const PsfResult tiny = f.render(r);
  EXPECT_EQ(tiny.progress.filter.cells, tiny.progress.filter.paths) << "every path alone";
  EXPECT_GT(tiny.progress.filter.paths, tiny.progress.samples / 2);
  PsfRender plain = r;
  plain.filter = false;
  plain.set = {};
  plain.seed = 4;
  const PsfResult unfiltered = f.render(plain);
  EXPECT_EQ(region_disagreement(tiny.image, unfiltered.image), "");
  // The same seed unfiltered: the same paths, each its own cell's mean, within float rounding.
  plain.seed = 3;
  const Image same_seed = f.render(plain).image;
  double worst = 0;
  for (size_t i = 0; i < same_seed.pixel_count(); ++i)
    for (int c = 0; c < 3; ++c)
      worst = std::max(worst, double(std::abs(tiny.image[i][c] - same_seed[i][c])) /
                                  (std::abs(same_seed[i][c]) + 1e-3));
  EXPECT_LT(worst, 1e-4);
  // The default width shares cells between paths: a different, smoother image.
  r.set = {"psf.depth=0"};
  const PsfResult wide = f.render(r);
  EXPECT_LT(wide.progress.filter.cells * 4, wide.progress.filter.paths);
  EXPECT_FALSE(same_bits(wide.image, tiny.image));
}

// A floor of two colours, red (0.8, 0, 0) and green (0, 0.8, 0) halves, under a large lamp, seen
// from below the lamp; cut at the camera vertex (psf.depth=0) with wide cells that span both
// halves. Demodulated (psf.demodulate=1), a cell holds irradiance and each path multiplies its own
// albedo back in: a pixel of the red half stays red (green exactly 0, as unfiltered); filtering
// the whole radiance (0) blurs green into it.
struct TwoColours {
  Scene scene;
  LightTree tree;
  std::unique_ptr<Accel> accel;
  TwoColours() {
    SceneBuilder b(scene);
    const uint32_t red = b.diffuse(Rgb(0.8f, 0, 0)), green = b.diffuse(Rgb(0, 0.8f, 0));
    b.quad(Vec3(0, 0, 0), Vec3(0, 0, 2), Vec3(1, 0, 0), red);  // z cross x = +y
    b.quad(Vec3(1, 0, 0), Vec3(0, 0, 2), Vec3(1, 0, 0), green);
    b.quad(Vec3(-1, 1.2f, -1), Vec3(4, 0, 0), Vec3(0, 0, 4), b.emitter(Rgb(1)));  // faces -y
    scene.camera.position = Vec3(1, 1, 1);
    scene.camera.target = Vec3(1, 0, 1);
    scene.camera.up = Vec3(0, 0, -1);
    scene.camera.fov = 80;
    scene.has_camera = true;
    scene.width = 32;
    scene.height = 24;
    scene.finalize();
    tree = build_light_tree(scene);
    accel = std::make_unique<Accel>(scene.mesh);
  }
  Image render(bool filter, const std::string& demodulate) const {
    PsfRender r;
    r.filter = filter;
    if (filter) r.set = {"psf.depth=0", "psf.width=40", "psf.demodulate=" + demodulate};
    r.spp = 8;
    return render_psf(scene, tree, *accel, r).image;
  }
};

TEST(PsfDemodulation, KeepsTheColoursThatTheWholeRadianceBlurs) {
  const TwoColours f;
  const Image plain = f.render(false, ""), demodulated = f.render(true, "1"),
              whole = f.render(true, "0");
  size_t red = 0, green = 0, bled_whole = 0, bled_demodulated = 0;
  for (size_t i = 0; i < plain.pixel_count(); ++i) {
    const Rgb p = plain[i];
    if (p[2] != 0) ADD_FAILURE() << "no blue anywhere";
    for (const bool on_red : {true, false}) {
      const int own = on_red ? 0 : 1, other = on_red ? 1 : 0;
      if (!(p[own] > 0 && p[other] == 0)) continue;  // (a pixel wholly on one half)
      ++(on_red ? red : green);
      EXPECT_GT(demodulated[i][own], 0.0f) << i;
      bled_demodulated += demodulated[i][other] != 0;
      bled_whole += whole[i][other] > 0.01f * whole[i][own];
    }
  }
  ASSERT_GT(red, plain.pixel_count() / 4);
  ASSERT_GT(green, plain.pixel_count() / 4);
  EXPECT_EQ(bled_demodulated, 0u) << "demodulated: a half's pixels keep their colour";
  EXPECT_GT(bled_whole, (red + green) / 4) << "the whole radiance filtered mixes the halves";
}

// A seed gives the same filtered image to the bit with 1 and 2 threads, on the megakernel and the
// wavefront (Embree's tracer and rll's BVH, any budget of path slots), for a sampler that learns
// nothing within a pass (power, tree) and for rll (learning between passes); demodulated (the
// default: the room's plastic sphere splits its lobes, its metal box is not cut) and not.
TEST(PsfDeterminism, SameImageForAnyThreadCountAndRenderer) {
  const Fixture f("cornell-boxes-room", 40, 30);
  for (const std::string sampler : {"power", "tree", "rll", "power:whole"}) {
    SCOPED_TRACE(sampler);
    PsfRender r;
    r.sampler = sampler.substr(0, sampler.find(':'));
    if (sampler == "rll") r.set = {"rll.capacity=4096"};
    if (sampler == "power:whole") r.set = {"psf.demodulate=0"};
    r.spp = 5;  // passes of 1, 1, 2, 1 spp
    r.seed = 21;
    r.threads = 1;
    const PsfResult one = f.render(r);
    EXPECT_GT(one.progress.filter.paths, 0u);
    EXPECT_EQ(one.progress.filter.batches, 5u);
    r.threads = 2;
    const PsfResult two = f.render(r);
    EXPECT_TRUE(same_bits(one.image, two.image)) << "2 threads";
    EXPECT_EQ(one.progress.filter.cells, two.progress.filter.cells);
    r.wavefront = true;
    const PsfResult wave = f.render(r);
    if (r.sampler != "rll") {  // (rll learns within a pass from records in another order)
      EXPECT_TRUE(same_bits(one.image, wave.image)) << "wavefront";
      EXPECT_EQ(one.progress.filter.cells, wave.progress.filter.cells);
      EXPECT_EQ(one.progress.filter.paths, wave.progress.filter.paths);
    }
    r.path_slots = 333;
    EXPECT_TRUE(same_bits(f.render(r).image, wave.image)) << "333 slots";
    // rll's BVH (the GPU's traversal) hits within float rounding of Embree's: its own images.
    r.tracer = WavefrontTracer::Bvh;
    const Image bvh = f.render(r).image;
    r.threads = 1;
    r.path_slots = 0;
    EXPECT_TRUE(same_bits(f.render(r).image, bvh)) << "bvh, 1 thread";
    r.seed = 22;  // the comparison can fail: another seed gives another image
    EXPECT_FALSE(same_bits(f.render(r).image, bvh));
  }
}

// A filtered sample is counted once, by the film's add of what the path gathered before its cut
// (the resolve adds its cell's share to the sums only): every pixel holds spp samples, and a pass
// is a batch per sample.
TEST(PsfFilm, EveryPixelCountsItsSamplesOnce) {
  const Fixture f("cornell-box", 20, 20);
  for (bool wavefront : {false, true}) {
    PsfRender r;
    r.spp = 3;
    r.wavefront = wavefront;
    const PsfResult res = f.render(r);
    EXPECT_EQ(res.progress.spp_done, 3);
    EXPECT_EQ(res.progress.samples, 3u * 400u);
    EXPECT_EQ(res.progress.filter.batches, 3u);
  }
}

// The table for a film is checked against the memory budget before it is allocated, on the
// megakernel and the wavefront, with a message naming the filter and its size.
TEST(PsfMemory, TableThatWouldNotFitIsRefused) {
  const Fixture f("cornell-box", 64, 64);
  // 64 x 64 pixels at kPsfBytesPerPixel: about 1 MB; the budget is half of it.
  const BudgetScope budget(size_t(64 * 64 * kPsfBytesPerPixel / 2));
  for (bool wavefront : {false, true}) {
    PsfRender r;
    r.wavefront = wavefront;
    r.spp = 1;
    const std::string message = error_of([&] { f.render(r); });
    expect_mentions(message, {"path-space filter", "4096 pixels", "more than"});
  }
  PsfRender unfiltered;
  unfiltered.filter = false;
  unfiltered.spp = 1;
  EXPECT_NO_THROW(f.render(unfiltered)) << "the film alone fits";
}

}  // namespace
