// Path-space filtering's parts (render/psf.h): the psf.* keys (Fermat's defaults, bad values
// refused naming the key), the cell table (every key finds one cell, whatever the threads, and a
// batch of all-distinct keys never fills it), a cell's mean (the ratio of its radiance to its
// throughput: a path alone gets exactly its own radiance) and the cell size's width.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <thread>
#include <vector>

#include "rll/core/error.h"
#include "rll/core/params.h"
#include "rll/render/integrator.h"
#include "rll/render/psf.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;

namespace {

PsfSettings psf_from(std::vector<std::string> set, const std::string& integrator = "path",
                     int max_depth = 5) {
  const Params params = Params::parse(set);
  const IntegratorSettings s = make_integrator_settings(integrator, max_depth, params, "psf");
  params.check_all_used();
  return s.psf;
}

TEST(PsfSettings, DefaultsAreFermats) {
  const PsfSettings s = psf_from({});
  EXPECT_TRUE(s.on);
  EXPECT_EQ(s.depth, 1);  // psfpt's psf_depth: the first bounce
  EXPECT_EQ(s.width, 3.0f);
  EXPECT_EQ(s.max_prob, 32.0f);
  EXPECT_EQ(s.min_dist, 0.0f);
  EXPECT_EQ(s.clamp, 100.0f);  // psfpt's firefly_filter
  EXPECT_TRUE(s.demodulate);   // psfpt's diffuse cache, demodulated by its albedo
  EXPECT_FALSE(psf_from({"psf.demodulate=0"}).demodulate);
  EXPECT_EQ(psf_from({}, "direct", 1).depth, 0) << "direct has the camera vertex only";
  EXPECT_EQ(psf_from({"psf.depth=2", "psf.width=0.5", "psf.clamp=0"}).depth, 2);
  // Without --filter psf the filter is off.
  EXPECT_FALSE(make_integrator_settings("path", 5, Params{}).psf.on);
}

TEST(PsfSettings, BadValuesAreRefusedNamingTheKey) {
  for (const std::string kv :
       {"psf.width=0", "psf.width=-1", "psf.width=nan", "psf.width=abc", "psf.max_prob=0",
        "psf.min_dist=-0.1", "psf.clamp=-5", "psf.depth=-2", "psf.depth=1.5", "psf.temporal=1",
        "psf.temporal=-0.1", "psf.temporal=nan", "psf.temporal=2", "psf.demodulate=2",
        "psf.demodulate=0.5", "psf.demodulate=-1"}) {
    SCOPED_TRACE(kv);
    const std::string key = kv.substr(0, kv.find('='));
    expect_mentions(error_of([&] { psf_from({kv}); }), {key});
  }
  // A cut past the last vertex would filter nothing.
  expect_mentions(error_of([&] { psf_from({"psf.depth=5"}, "path", 5); }),
                  {"psf.depth=5", "--max-depth 5"});
  expect_mentions(error_of([&] { psf_from({"psf.depth=1"}, "direct", 1); }), {"psf.depth=1"});
  // An unknown psf key, and a psf key without the filter.
  expect_mentions(error_of([&] { psf_from({"psf.widht=2"}); }), {"psf.widht", "psf.width"});
  expect_mentions(error_of([&] {
                    make_integrator_settings("path", 5, Params::parse({"psf.width=2"}), "none");
                  }),
                  {"psf.width", "--filter psf"});
  expect_mentions(error_of([&] { make_integrator_settings("path", 5, Params{}, "bilateral"); }),
                  {"--filter", "bilateral", "psf"});
}

// Every parameter of the table is listed with its default (`rll filters --params psf`).
TEST(PsfSettings, TableListsEveryKey) {
  const std::vector<std::string> lines = describe_params(psf_params(), "psf", PsfSettings{});
  ASSERT_EQ(lines.size(), 7u);
  for (const std::string key : {"psf.depth=-1", "psf.width=3", "psf.max_prob=32", "psf.min_dist=0",
                                "psf.clamp=100", "psf.temporal=0", "psf.demodulate=1"})
    EXPECT_TRUE(std::any_of(lines.begin(), lines.end(), [&](const std::string& l) {
      return l.rfind(key, 0) == 0;
    })) << key;
}

struct Table {
  std::vector<uint64_t> keys;
  std::vector<ExactSum> sums;
  uint32_t used = 0;
  explicit Table(size_t paths) : keys(psf_capacity(paths)), sums(6 * keys.size()) {}
  PsfTableView view() { return {view_of(keys), {sums.data(), sums.size()}, &used}; }
};

// As many distinct keys as the batch has paths, inserted from four threads, twice each: every key
// gets one cell, the same on both inserts, and the table counts each once.
TEST(PsfTable, EveryKeyGetsOneCellFromAnyThread) {
  const size_t n = 20000;
  Table t(n);
  const PsfTableView v = t.view();
  std::vector<uint32_t> first(n), second(n);
  auto insert = [&](std::vector<uint32_t>& out, size_t begin, size_t step) {
    for (size_t i = begin; i < n; i += step) out[i] = psf_cell(v, mix64(i) | 1);
  };
  std::vector<std::thread> threads;
  for (size_t k = 0; k < 4; ++k) threads.emplace_back([&, k] { insert(first, k, 4); });
  for (auto& th : threads) th.join();
  threads.clear();
  for (size_t k = 0; k < 4; ++k) threads.emplace_back([&, k] { insert(second, 3 - k, 4); });
  for (auto& th : threads) th.join();
  EXPECT_EQ(first, second);
  EXPECT_EQ(t.used, n);
  EXPECT_EQ(std::set<uint32_t>(first.begin(), first.end()).size(), n);
  for (size_t i = 0; i < n; ++i) ASSERT_EQ(t.keys[first[i]], mix64(i) | 1);
}

// A batch of `pixels` paths: its table, film and records, and the filter with `clamp`.
struct Batch {
  Table t;
  std::vector<double> sum;
  std::vector<uint32_t> count;
  std::vector<PsfRecord> records;
  PsfConstants f;
  Batch(size_t pixels, float clamp)
      : t(pixels), sum(3 * pixels, 0.0), count(pixels, 0), records(pixels) {
    f.on = true;
    f.clamp = clamp;
  }
  FilmView film() { return {view_of(sum), view_of(count), int(count.size())}; }
  PsfEnd end(size_t pixel, const PsfCut& cut, const Rgb& L) {
    return psf_end_path(f, t.view(), film(), view_of(records), pixel, cut, L);
  }
  void resolve() {
    for (size_t p = 0; p < records.size(); ++p)
      psf_resolve_pixel(f, t.view(), film(), view_of(records), p);
  }
};

// A cell's mean is the ratio of its paths' radiance after the cut to their throughputs at it,
// per channel; each path gets it times its own throughput, clamped. A path alone in its cell gets
// its own radiance back.
TEST(PsfTable, CellMeanIsRadianceOverThroughput) {
  Batch b(4, 0);
  const std::vector<double>& sum = b.sum;
  const PsfCut first{7, Rgb(0.5f, 1.0f, 0.0f), Rgb(0.25f)};
  const PsfCut second{7, Rgb(1.5f, 1.0f, 0.0f), Rgb(0)};
  const PsfCut alone{9, Rgb(0.3f, 0.2f, 0.1f), Rgb(0)};
  EXPECT_EQ(b.end(0, first, Rgb(1, 2, 3)), PsfEnd::Filtered);
  EXPECT_EQ(b.end(1, second, Rgb(5, 4, 0)), PsfEnd::Filtered);
  EXPECT_EQ(b.end(2, alone, Rgb(0.7f, 0.11f, 0.013f)), PsfEnd::Filtered);
  EXPECT_EQ(b.end(3, PsfCut{}, Rgb(2)), PsfEnd::Unfiltered);
  EXPECT_EQ(b.t.used, 2u);
  // Before the resolve: what was gathered before the cuts, every sample counted once.
  EXPECT_EQ(sum[0], 0.25);
  EXPECT_EQ(sum[9], 2.0);
  EXPECT_EQ(b.count, std::vector<uint32_t>(4, 1));
  b.resolve();
  // Cell 7: radiance (6, 6, 3) over throughput (2, 2, 0): means 3, 3 and none (no throughput).
  EXPECT_NEAR(sum[0], 0.25 + 0.5 * 3, 1e-6);
  EXPECT_NEAR(sum[1], 0.25 + 1.0 * 3, 1e-6);
  EXPECT_NEAR(sum[2], 0.25, 1e-6);
  EXPECT_NEAR(sum[3], 1.5 * 3, 1e-6);
  EXPECT_NEAR(sum[6], 0.7, 1e-6);
  EXPECT_NEAR(sum[7], 0.11, 1e-7);
  EXPECT_NEAR(sum[8], 0.013, 1e-8);
  EXPECT_EQ(sum[9], 2.0) << "an uncut path is not resolved";
  EXPECT_EQ(b.count, std::vector<uint32_t>(4, 1));
}

// The clamp bounds every contribution to the film per channel, the splat included; a path whose
// radiance is not finite is dropped (counted, 0 added) and leaves its cell alone.
TEST(PsfTable, ClampAndNonFinitePaths) {
  Batch b(3, 10);
  const std::vector<double>& sum = b.sum;
  const PsfCut cut{5, Rgb(1), Rgb(50, 1, 1)};
  EXPECT_EQ(b.end(0, cut, Rgb(400, 2, 1)), PsfEnd::Filtered);
  EXPECT_EQ(b.end(1, cut, Rgb(NAN, 1, 1)), PsfEnd::NonFinite);
  EXPECT_EQ(b.end(2, PsfCut{}, Rgb(1, INFINITY, 1)), PsfEnd::NonFinite);
  b.resolve();
  EXPECT_NEAR(sum[0], 10 + 10, 1e-6);  // before clamped, the cell's 400 clamped
  EXPECT_NEAR(sum[1], 1 + 2, 1e-6);
  for (size_t i = 3; i < 9; ++i) EXPECT_EQ(sum[i], 0.0) << i;
  EXPECT_EQ(b.count, std::vector<uint32_t>(3, 1));
}

// The cell's radius is psf.width footprints (Fermat's psf_width), its edge twice that before the
// level of detail rounds it to a power of two.
TEST(PsfKey, CellSizeFollowsTheWidth) {
  Bounds3 b;
  b.lo = Vec3(0);
  b.hi = Vec3(10);
  PsfSettings s;
  s.on = true;
  s.depth = 1;
  for (float width : {0.5f, 3.0f, 12.0f}) {
    s.width = width;
    const PsfConstants c = make_psf_constants(s, b);
    EXPECT_FLOAT_EQ(c.keyer.cell_size(0.01f), 2 * width * 0.01f);
  }
  // Two points a footprint apart share cells at width 3 far more often than at width 0.1.
  auto shared = [&](float width) {
    s.width = width;
    const PsfConstants c = make_psf_constants(s, b);
    int same = 0;
    Pcg32 rng(7, 1);
    for (int i = 0; i < 2000; ++i) {
      float u[5];
      for (float& x : u) x = rng.next_float();
      const Vec3 p(5, 5, 1 + rng.next_float());
      const Vec3 n(0, 0, 1), wo(0, 0.6f, 0.8f);
      same += psf_key(c, p, n, wo, 0.01f, 1, u) ==
              psf_key(c, p + Vec3(0.01f, 0, 0), n, wo, 0.01f, 1, u);
    }
    return same;
  };
  EXPECT_GT(shared(3.0f), 1500);
  EXPECT_LT(shared(0.1f), 200);
}

// Temporal reuse: a cell of this sample's table adds w times the six sums its key had in the last
// sample's, found past the cells its home slot's probe runs through; a cell whose key the last
// sample had not, and a free slot, add nothing.
TEST(PsfTemporal, BlendAddsTheLastSamplesSumsTimesTheWeight) {
  PsfConstants f;
  f.on = true;
  f.temporal = 0.75f;
  Table last(2), now(2);  // 5 cells each
  const PsfTableView l = last.view(), t = now.view();
  // Keys 1, 11 and 21 share the home slot (key >> 1) % 5 = 0: 21 lands in slot 2 after the others.
  for (uint64_t key : {1u, 11u, 21u}) psf_cell(l, key);
  ASSERT_EQ(last.keys[2], 21u);
  EXPECT_EQ(psf_find(l, 21), 2u);
  EXPECT_EQ(psf_find(l, 31), kPsfNoCell);
  for (int i = 0; i < 6; ++i) last.sums[6 * 2 + i].add(double(i + 1));
  const uint32_t found = psf_cell(t, 21), missing = psf_cell(t, 33);
  for (int i = 0; i < 6; ++i) now.sums[6 * found + i].add(0.5);
  for (size_t c = 0; c < now.keys.size(); ++c)
    EXPECT_EQ(psf_blend_cell(f, t, l, c), c == found) << "cell " << c;
  for (int i = 0; i < 6; ++i) {
    EXPECT_EQ(now.sums[6 * found + i].value(), 0.5 + 0.75 * (i + 1)) << "sum " << i;
    EXPECT_EQ(now.sums[6 * missing + i].value(), 0.0);
  }
}

// Demodulation's split (psf.demodulate): a plastic's diffuse share of f(wo, wi) is its Lambertian
// lobe (the same plastic without a specular lobe) over f, in [0, 1]; a Lambertian's is 1; a
// conductor has no diffuse part, a coated diffuse a layered one.
TEST(PsfDemodulation, DiffuseShareIsTheLambertianLobe) {
  MaterialData plastic;
  plastic.type = MaterialType::Plastic;
  plastic.albedo = Rgb(0.6f, 0.3f, 0.0f);
  plastic.roughness = 0.2f;
  MaterialData matte = plastic;
  matte.specular = Rgb(0);
  const Vec3 n(0, 0, 1), wo = normalize(Vec3(0.3f, -0.2f, 1.0f));
  const Bsdf b(plastic, plastic.albedo, n, n, wo), d(matte, matte.albedo, n, n, wo);
  EXPECT_EQ(b.diffuse_part(), Bsdf::DiffusePart::Separable);
  int glossy = 0;
  for (const Vec3& w : {Vec3(-0.3f, 0.2f, 1.0f), Vec3(0.5f, 0.5f, 0.3f), Vec3(-0.9f, 0.1f, 0.2f)}) {
    const Vec3 wi = normalize(w);
    const Rgb share = b.diffuse_share(wo, wi), f = b.eval(wo, wi), fd = d.eval(wo, wi);
    for (int c = 0; c < 3; ++c) {
      EXPECT_GE(share[c], 0.0f);
      EXPECT_LE(share[c], 1.0f);
      EXPECT_NEAR(share[c] * f[c], fd[c], 1e-5f * f[c]) << c;
    }
    glossy += share[0] < 0.99f;
    EXPECT_EQ(share[2], 0.0f) << "no diffuse lobe in a channel of albedo 0";
  }
  EXPECT_GT(glossy, 0) << "the mirror direction is mostly glossy";
  MaterialData lambert;
  lambert.albedo = Rgb(0.5f);
  EXPECT_EQ(Bsdf(lambert, lambert.albedo, n, n, wo).diffuse_share(wo, normalize(Vec3(1, 0, 1))),
            Rgb(1));
  MaterialData metal;
  metal.type = MaterialType::Conductor;
  EXPECT_EQ(Bsdf(metal, metal.albedo, n, n, wo).diffuse_part(), Bsdf::DiffusePart::None);
  MaterialData coated;
  coated.type = MaterialType::CoatedDiffuse;
  EXPECT_EQ(Bsdf(coated, coated.albedo, n, n, wo).diffuse_part(), Bsdf::DiffusePart::Layered);
}

// A split cut: its light samples' glossy share (times the throughput) goes to the film with what
// came before the cut, and at the end the glossy share of what came back through its bounce;
// the cell takes the diffuse shares, its mean weighed by the throughput times the albedo.
TEST(PsfDemodulation, SplitSendsTheGlossyShareToTheFilm) {
  MaterialData plastic;
  plastic.type = MaterialType::Plastic;
  plastic.albedo = Rgb(0.5f);
  plastic.roughness = 0.2f;
  const Vec3 n(0, 0, 1), wo = normalize(Vec3(0.3f, -0.2f, 1.0f));
  const Bsdf bsdf(plastic, plastic.albedo, n, n, wo);
  const Vec3 wi = normalize(Vec3(-0.3f, 0.2f, 1.0f));  // the mirror direction: glossy
  const Rgb share = bsdf.diffuse_share(wo, wi);
  ASSERT_LT(share[0], 0.9f) << "a glossy share to split";
  PsfCut cut{7, Rgb(2) * plastic.albedo, Rgb(0.1f)};
  const Rgb kept = psf_split_nee(bsdf, wo, wi, Rgb(2), Rgb(1), cut);
  EXPECT_EQ(kept, share);
  EXPECT_NEAR(cut.before[0], 0.1f + 2 * (1 - share[0]), 1e-6f);
  Rgb L = Rgb(2) * kept;  // the path's radiance after the cut: its kept light sample
  psf_split_bounce(bsdf, wo, wi, L, cut);
  EXPECT_EQ(L, Rgb(0));
  EXPECT_EQ(cut.kept, Rgb(2) * share);
  Batch b(1, 0);
  b.f.demodulate = true;
  EXPECT_EQ(b.end(0, cut, Rgb(4)), PsfEnd::Filtered);  // 4 came back through the bounce
  EXPECT_NEAR(b.sum[0], cut.before[0] + 4 * (1 - share[0]), 1e-5);
  b.resolve();  // alone in its cell: its own diffuse share back
  EXPECT_NEAR(b.sum[0], cut.before[0] + 4 * (1 - share[0]) + 2 * share[0] + 4 * share[0], 1e-5);
}

}  // namespace
