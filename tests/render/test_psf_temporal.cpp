// The path-space filter's temporal reuse (psf.temporal, render/psf.h): off (and on a render that
// follows no frame) it changes no image; on the furnace the blended frames are still the analytic
// radiance; on a still scene it lowers each frame's variance; a seed gives the same frames with
// any thread count and on the megakernel and the wavefront.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "rll/accel/accel.h"
#include "rll/core/parallel.h"
#include "rll/core/params.h"
#include "rll/render/integrator.h"
#include "rll/render/render.h"
#include "rll/scene/builtin.h"
#include "rll/session/session.h"
#include "rll/wavefront/wavefront.h"
#include "support/small_scene.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;

namespace {

struct Frames {
  std::vector<std::string> set;  // psf.* keys
  int frames = 4;
  int spp = 1;  // per frame
  uint64_t seed = 1;
  int threads = 0;
  bool wavefront = false;
  uint32_t path_slots = 0;
  bool history = true;  // the renders keep the filter's cells from frame to frame
  bool follows = true;  // frames after the first follow the one before
  int max_depth = 3;
};

struct FramesResult {
  std::vector<Image> images;  // one per frame
  PsfCounts counts;
};

struct Fixture : SmallScene {
  using SmallScene::SmallScene;

  // The frames of a still scene as `rll render --frames` renders them: each its own film and
  // seed (the frame enters it), the filter's cells kept in one history.
  FramesResult render(const Frames& r) const {
    ThreadLimit limit(r.threads);
    const Params params = Params::parse(r.set);
    auto sampler = make_light_sampler("power", scene, tree, params, accel.get());
    const IntegratorSettings is = make_integrator_settings("path", r.max_depth, params, "psf");
    params.check_all_used();
    PsfHistory history(size_t(scene.width) * scene.height);
    FramesResult out;
    for (int f = 0; f < r.frames; ++f) {
      Film film(scene.width, scene.height);
      RenderSettings rs;
      rs.spp = r.spp;
      rs.seed = r.seed;
      rs.frame = f;
      rs.follows_frame = r.follows && f > 0;
      RenderProgress p;
      PsfHistory* h = r.history ? &history : nullptr;
      if (r.wavefront) {
        WavefrontSettings ws;
        ws.path_slots = r.path_slots;
        ws.psf_history = h;
        p = render_wavefront(scene, *accel, *sampler, is, film, rs, nullptr, {}, ws);
      } else {
        Integrator integrator(scene, *accel, *sampler, is);
        p = rll::render(scene, integrator, *sampler, film, rs, nullptr, {}, h);
      }
      out.images.push_back(film.resolve());
      out.counts += p.filter;
    }
    return out;
  }
};

bool same_bits(const Image& a, const Image& b) {
  return a.pixel_count() == b.pixel_count() &&
         std::memcmp(a.pixels().data(), b.pixels().data(), a.pixel_count() * sizeof(Rgb)) == 0;
}

bool same_frames(const FramesResult& a, const FramesResult& b) {
  if (a.images.size() != b.images.size()) return false;
  for (size_t f = 0; f < a.images.size(); ++f)
    if (!same_bits(a.images[f], b.images[f])) return false;
  return true;
}

// psf.temporal=0 (the default, or given) renders every frame as without the key; with a weight,
// frames that follow no frame (a still render, a first frame) blend nothing, nor do renders
// given no history: the same images to the bit, on the megakernel and the wavefront. The frames
// that do follow blend and differ (the comparison can fail).
TEST(PsfTemporal, OffOrWithoutAFrameBeforeChangesNoImage) {
  const Fixture f("cornell-box", 24, 24);
  for (bool wavefront : {false, true}) {
    SCOPED_TRACE(wavefront ? "wavefront" : "megakernel");
    Frames r;
    r.frames = 3;
    r.spp = 2;
    r.wavefront = wavefront;
    const FramesResult plain = f.render(r);
    EXPECT_EQ(plain.counts.reused, 0u);
    Frames zero = r;
    zero.set = {"psf.temporal=0"};
    EXPECT_TRUE(same_frames(f.render(zero), plain)) << "psf.temporal=0";
    Frames on = r;
    on.set = {"psf.temporal=0.5"};
    on.follows = false;
    EXPECT_TRUE(same_frames(f.render(on), plain)) << "frames that follow none";
    on.follows = true;
    on.history = false;
    EXPECT_TRUE(same_frames(f.render(on), plain)) << "no history";
    on.history = true;
    const FramesResult blended = f.render(on);
    EXPECT_TRUE(same_bits(blended.images[0], plain.images[0])) << "the first frame";
    EXPECT_FALSE(same_bits(blended.images[2], plain.images[2])) << "a frame that follows";
    EXPECT_GT(blended.counts.reused, 0u);
  }
}

double furnace_value(int max_depth) {
  double sum = 0, ak = 1;
  for (int k = 0; k <= max_depth; ++k, ak *= kFurnaceAlbedo) sum += ak;
  return kFurnaceEmission * sum;
}

// The mean and standard error over renders (seeds) of a value of each.
Estimate over_renders(const std::vector<double>& v) {
  double mean = 0, var = 0;
  for (double x : v) mean += x;
  mean /= double(v.size());
  for (double x : v) var += (x - mean) * (x - mean);
  var /= double(v.size() - 1);
  return {mean, std::sqrt(var / double(v.size()))};
}

// On the furnace every cell of every frame has the same expected mean, Le sum a^k: a blend of a
// frame's cells with the last frame's is still the analytic radiance, over the image and region
// by region, in the last of 4 frames of 1 spp (blended 3 times) at a weight of 0.9 and of 0.5.
// 16 seeds give each mean and its standard error (15 degrees of freedom: 5.5 of them bound a
// false failure at about 1e-4 for each of the 17 means); the bound sees a 2% bias.
TEST(PsfTemporal, FurnaceFramesAreTheAnalyticRadiance) {
  const Fixture f("furnace", 32, 32);
  const double expected = furnace_value(3);
  for (const std::string weight : {"0.9", "0.5"}) {
    SCOPED_TRACE(weight);
    const int n = 4;
    std::vector<std::vector<double>> values(1 + n * n);
    PsfCounts counts;
    for (uint64_t seed = 1; seed <= 16; ++seed) {
      Frames r;
      r.set = {"psf.temporal=" + weight};
      r.seed = seed;
      const FramesResult res = f.render(r);
      counts += res.counts;
      const Image& last = res.images.back();
      values[0].push_back(image_mean(last));
      for (int ry = 0; ry < n; ++ry)
        for (int rx = 0; rx < n; ++rx)
          values[1 + ry * n + rx].push_back(image_mean(image_region(last, rx, ry, n, n)));
    }
    // Frames blended: most cells of the frames that follow found their key in the last one's.
    EXPECT_GT(4 * counts.reused, counts.cells);
    const Estimate image = over_renders(values[0]);
    EXPECT_NEAR(image.mean, expected, 5.5 * image.stderr_ + 1e-5)
        << "mean " << image.mean << " +- " << image.stderr_ << ", analytic " << expected;
    for (size_t i = 1; i < values.size(); ++i) {
      const Estimate e = over_renders(values[i]);
      EXPECT_NEAR(e.mean, expected, 5.5 * e.stderr_ + 1e-5) << "region " << i - 1;
    }
    EXPECT_LT(5.5 * image.stderr_, 0.02 * expected);
  }
}

// The median over the pixels of each pixel's variance over seeds (its channels' summed) in the
// last of 6 frames of 1 spp. The median: the pixels on the lamp's edge, whose samples see the
// lamp or the ceiling (emission, which the filter never shares), would swamp a mean.
double last_frame_variance(const Fixture& f, const std::vector<std::string>& set) {
  const int seeds = 12;
  std::vector<Image> last;
  for (int s = 0; s < seeds; ++s) {
    Frames r;
    r.set = set;
    r.frames = 6;
    r.seed = uint64_t(100 + s);
    last.push_back(f.render(r).images.back());
  }
  const size_t pixels = last[0].pixel_count();
  std::vector<double> variance(pixels, 0.0);
  for (size_t p = 0; p < pixels; ++p)
    for (int c = 0; c < 3; ++c) {
      double mean = 0, var = 0;
      for (const Image& img : last) mean += img[p][c];
      mean /= seeds;
      for (const Image& img : last) var += (img[p][c] - mean) * (img[p][c] - mean);
      variance[p] += var / (seeds - 1);
    }
  std::nth_element(variance.begin(), variance.begin() + pixels / 2, variance.end());
  return variance[pixels / 2];
}

// On a still scene a frame that blends the last frames' cells has less noise than one alone: at
// a weight of 0.75 a cell weighs about 1 + 0.75 + 0.75^2 ... = 4 samples' paths instead of one,
// which takes the noise of a cell's mean to (1 - w) / (1 + w) = 1/7 of its own. What the jitter
// adds (which cell a pixel's path falls in, at which level) stays: cut at the camera vertex
// (psf.depth=0, so that its direct light is filtered too; at the default depth its unfiltered
// noise hides the rest), over 12 seeds of 6 frames, the last frame's median pixel variance is
// 0.59 of the unblended one (0.63 with other seeds). The bound, 0.8, is far from both that and 1,
// what a blend that did nothing gives (its frames are the unblended ones to the bit).
TEST(PsfTemporal, BlendedFramesOfAStillSceneAreLessNoisy) {
  const Fixture f("cornell-box", 24, 24);
  const double off = last_frame_variance(f, {"psf.depth=0"});
  const double on = last_frame_variance(f, {"psf.depth=0", "psf.temporal=0.75"});
  EXPECT_GT(off, 0);
  EXPECT_LT(on, 0.8 * off) << "blended " << on << ", alone " << off;
  EXPECT_GT(on, 0.02 * off) << "a blend keeps the frame's own paths";
}

// A seed gives the same blended frames to the bit with 1 and 2 threads, on the megakernel and the
// wavefront (any budget of path slots), over frames of 2 samples (each blending the one before).
TEST(PsfTemporal, SameFramesForAnyThreadCountAndRenderer) {
  const Fixture f("cornell-boxes-room", 40, 30);
  Frames r;
  r.set = {"psf.temporal=0.8"};
  r.frames = 3;
  r.spp = 2;
  r.seed = 7;
  r.max_depth = 4;
  r.threads = 1;
  const FramesResult one = f.render(r);
  EXPECT_GT(one.counts.reused, 0u);
  r.threads = 2;
  EXPECT_TRUE(same_frames(f.render(r), one)) << "2 threads";
  r.wavefront = true;
  const FramesResult wave = f.render(r);
  EXPECT_TRUE(same_frames(wave, one)) << "wavefront";
  EXPECT_EQ(wave.counts.reused, one.counts.reused);
  EXPECT_EQ(wave.counts.cells, one.counts.cells);
  r.path_slots = 333;
  r.threads = 1;
  EXPECT_TRUE(same_frames(f.render(r), one)) << "333 slots";
  r.seed = 8;  // the comparison can fail: another seed gives other frames
  EXPECT_FALSE(same_frames(f.render(r), one));
}

// The two tables of temporal reuse are checked against the memory budget before they are
// allocated, with a message naming them; the filter alone still fits that budget.
TEST(PsfTemporal, HistoryThatWouldNotFitIsRefused) {
  const size_t pixels = 64 * 64;
  const BudgetScope budget(size_t(double(pixels) * (kPsfBytesPerPixel + 1)));
  EXPECT_NO_THROW(check_psf_memory(pixels));
  expect_mentions(error_of([&] { PsfHistory h(pixels); }),
                  {"path-space filter", "psf.temporal", "4096 pixels", "more than"});
}

// A still render with psf.temporal (no frame before it, none after) blends nothing and keeps no
// cells for a next frame: the session allocates no second table for it (temporal_bytes 0), and
// the memory it checks is what it allocates: a budget that holds the film and the filter but not
// the second table renders the still image, and refuses the frames that would need it.
TEST(PsfTemporal, StillRenderAllocatesNoSecondTable) {
  SessionSettings ss;
  ss.scene = "builtin:cornell-box";
  ss.resolution = "32x24";
  ss.filter = "psf";
  ss.set = {"psf.temporal=0.5"};
  const double pixels = 32 * 24;
  const BudgetScope budget(
      size_t(pixels * (kRenderBytesPerPixel + kPsfBytesPerPixel + kPsfTemporalBytesPerPixel / 2)));
  const RenderSession session(ss);
  auto sampler = session.make_sampler("power");
  RenderSettings rs;
  rs.spp = 2;
  Film film(32, 24);
  const RenderProgress p = session.render(*sampler, film, rs, "still", false);
  EXPECT_EQ(p.filter.batches, 2u);
  EXPECT_EQ(session.psf_history_bytes(), 0u) << "no second table for a still render";
  rs.precedes_frame = true;  // the first frame of an animation: its cells are kept
  expect_mentions(error_of([&] { session.render(*sampler, film, rs, "frame", false); }),
                  {"psf.temporal", "more than"});
  EXPECT_EQ(session.psf_history_bytes(), 0u);
}

}  // namespace
