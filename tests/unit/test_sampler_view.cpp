// The light samplers as data (lights/sampler_view.h, light_dispatch.h), the one way every renderer
// and tool samples: prepare_point, sample_light, light_pmf and record_nee over a sampler's
// SamplerView (rll with cells learnt by a short render); their samples carry the pmf that
// light_pmf gives to the bit, what they learn does not depend on the order of the records, their
// pmfs sum to one, a sampler without a device version is the host kind over its own calls, and
// the power table inverts its own CDF.
#include <gtest/gtest.h>

#include <bit>
#include <filesystem>
#include <fstream>
#include <regex>
#include <type_traits>

#include "rll/accel/accel.h"
#include "rll/core/params.h"
#include "rll/core/rng.h"
#include "rll/cuda/wavefront.h"
#include "rll/lights/light_dispatch.h"
#include "rll/lights/oracle_sampler.h"
#include "rll/lights/rll_sampler.h"
#include "rll/lights/simple_samplers.h"
#include "rll/lighttree/light_tree.h"
#include "rll/scene/builtin.h"
#include "support/sampler_contexts.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;

namespace {

static_assert(std::is_trivially_copyable_v<SamplerView>);
static_assert(std::is_trivially_copyable_v<LightTreeView>);
static_assert(std::is_trivially_copyable_v<DistributionView>);
static_assert(std::is_trivially_copyable_v<SobolView>);
static_assert(std::is_trivially_copyable_v<RllView>);
static_assert(std::is_trivially_copyable_v<CellKeyer>);

struct Fixture {
  Scene scene;
  std::unique_ptr<LightTree> tree;  // (by pointer: the samplers keep its address)
  std::unique_ptr<Accel> accel;
  std::vector<LightContext> contexts;
};

Fixture make_fixture(const std::string& name) {
  Fixture f;
  f.scene = small_builtin_scene(name, 48, 36);
  f.tree = std::make_unique<LightTree>(build_light_tree(f.scene));
  f.accel = std::make_unique<Accel>(f.scene.mesh);
  f.contexts = make_contexts(f.scene, *f.accel, 80, 77);
  return f;
}

Fixture& fixture(const std::string& name) {
  static std::map<std::string, Fixture> cache;
  auto it = cache.find(name);
  if (it == cache.end()) it = cache.emplace(name, make_fixture(name)).first;
  return it->second;
}

// A sampler by name with --set options, trained by a short render where it learns.
struct SamplerCase {
  const char* label;
  const char* name;
  std::vector<std::string> set;
};
const SamplerCase kCases[] = {
    {"uniform", "uniform", {}},
    {"power", "power", {}},
    {"tree", "tree", {}},
    {"rll", "rll", {}},
    {"rll_power", "rll", {"rll.within=power"}},
    {"rll_hybrid_grow",
     "rll",
     {"rll.initial_cut=16", "rll.splits=4", "rll.within=hybrid", "rll.descend_above=8"}},
    {"rll_defensive_tree",
     "rll",
     {"rll.defensive=tree", "rll.within=power", "rll.initial_cut=32", "rll.splits=2"}},
    {"rll_full_table", "rll", {"rll.capacity=48"}},
    {"rll_guided", "rll", {"rll.sampling=guided", "rll.capacity=48"}},
    {"rll_paper", "rll", {"rll.within=uniform", "rll.reward=fullpdf"}},
    {"fermat", "fermat", {}},
};

std::unique_ptr<LightSampler> make_case(Fixture& f, const SamplerCase& c, int passes) {
  Params params = Params::parse(c.set);
  auto sampler = make_light_sampler(c.name, f.scene, *f.tree, params);
  if (passes > 0) train_sampler(f.scene, *f.accel, *sampler, passes);
  return sampler;
}

using Param = std::tuple<std::string, size_t>;  // scene, case

class SamplerViewDispatch : public ::testing::TestWithParam<Param> {};

// A sample's pmf is light_pmf's to the bit, at points prepared by the dispatch (prepare_point
// finds the same cell again), and a second view of the sampler answers as the first.
TEST_P(SamplerViewDispatch, SamplesCarryTheirPmfBitForBit) {
  Fixture& f = fixture(std::get<0>(GetParam()));
  auto sampler = make_case(f, kCases[std::get<1>(GetParam())], 4);
  const SamplerView v = sampler->sampler_view(), again = sampler->sampler_view();
  ASSERT_NE(v.kind, SamplerKind::None);
  const uint32_t lights = uint32_t(f.scene.lights.size());
  size_t with_cell = 0;
  for (size_t c = 0; c < f.contexts.size(); ++c) {
    LightContext ctx = f.contexts[c], mine = f.contexts[c];
    const float u_prepare = float(c % 97) / 97.0f;
    prepare_point(v, ctx, u_prepare);
    prepare_point(again, mine, u_prepare);
    ASSERT_EQ(mine.cell, ctx.cell) << "context " << c;
    with_cell += ctx.cell != kNoCell;
    for (uint64_t k = 0; k < 32; ++k) {
      const double u = SampleStream(3, c, k, PointSet::Sobol).next_double();
      const SampledLight a = sample_light(v, ctx, u), b = sample_light(again, mine, u);
      ASSERT_EQ(a.light, b.light) << "context " << c << " u " << u;
      ASSERT_EQ(std::bit_cast<uint32_t>(a.pmf), std::bit_cast<uint32_t>(b.pmf));
      ASSERT_GT(a.pmf, 0);
      ASSERT_EQ(std::bit_cast<uint32_t>(light_pmf(v, ctx, a.light)), std::bit_cast<uint32_t>(a.pmf))
          << "light " << a.light;
    }
    ASSERT_EQ(light_pmf(v, ctx, lights), 0.0f) << "a light past the last";
  }
  if (v.prepares) {
    // (rll.capacity=48 leaves most points without a cell, by design.)
    EXPECT_GT(with_cell, f.contexts.size() / 6) << "too few points had a cell";
  }
}

// What record_nee learns does not depend on the order the records come in (renders are the same
// for any thread count): two samplers fed the same next-event samples, the second in the
// reverse order, sample alike after each end of pass.
TEST_P(SamplerViewDispatch, RecordNeeLearnsAlikeInAnyOrder) {
  Fixture& f = fixture(std::get<0>(GetParam()));
  const SamplerCase& sc = kCases[std::get<1>(GetParam())];
  auto a = make_case(f, sc, 0), b = make_case(f, sc, 0);
  if (!a->sampler_view().learns) GTEST_SKIP() << sc.label << " does not learn";
  Pcg32 rng(3);
  struct Fed {
    LightContext ca, cb;
    SampledLight sa, sb;
    NeeRecord r;
  };
  for (int pass = 0; pass < 3; ++pass) {
    const SamplerView va = a->sampler_view(), vb = b->sampler_view();
    std::vector<Fed> fed;
    for (size_t c = 0; c < f.contexts.size(); ++c)
      for (int k = 0; k < 4; ++k) {
        Fed e{f.contexts[c], f.contexts[c], {}, {}, {}};
        const float up = rng.next_float();
        const double u = rng.next_double();
        e.r.estimate = e.r.unoccluded = e.r.max_rgb =
            rng.next_float() < 0.3f ? 0.0f : rng.next_float();
        prepare_point(va, e.ca, up);
        prepare_point(vb, e.cb, up);
        e.sa = sample_light(va, e.ca, u);
        e.sb = sample_light(vb, e.cb, u);
        ASSERT_EQ(e.sa.light, e.sb.light);
        fed.push_back(e);
      }
    for (const Fed& e : fed)
      if (e.sa.pmf > 0) record_nee(va, e.ca, e.sa, e.r);
    for (auto e = fed.rbegin(); e != fed.rend(); ++e)
      if (e->sb.pmf > 0) record_nee(vb, e->cb, e->sb, e->r);
    a->end_pass();
    b->end_pass();
  }
  const SamplerView va = a->sampler_view(), vb = b->sampler_view();
  for (size_t c = 0; c < f.contexts.size(); ++c) {
    LightContext ca = f.contexts[c], cb = f.contexts[c];
    prepare_point(va, ca, 0.5f);
    prepare_point(vb, cb, 0.5f);
    for (uint32_t l = uint32_t(c % 5); l < f.scene.lights.size(); l += 5)
      ASSERT_EQ(std::bit_cast<uint32_t>(light_pmf(va, ca, l)),
                std::bit_cast<uint32_t>(light_pmf(vb, cb, l)))
          << "context " << c << " light " << l;
  }
}

TEST_P(SamplerViewDispatch, PmfsSumToOne) {
  Fixture& f = fixture(std::get<0>(GetParam()));
  auto sampler = make_case(f, kCases[std::get<1>(GetParam())], 4);
  const SamplerView v = sampler->sampler_view();
  for (size_t c = 0; c < f.contexts.size(); c += 10) {
    LightContext ctx = f.contexts[c];
    prepare_point(v, ctx, 0.25f);
    double sum = 0;
    for (uint32_t l = 0; l < f.scene.lights.size(); ++l) sum += light_pmf(v, ctx, l);
    ASSERT_NEAR(sum, 1.0, 1e-4) << "context " << c;
  }
}

INSTANTIATE_TEST_SUITE_P(Samplers, SamplerViewDispatch,
                         ::testing::Combine(::testing::Values("cornell-boxes-room",
                                                              "arch-interior"),
                                            ::testing::Range(size_t(0), std::size(kCases))),
                         [](const auto& info) {
                           std::string s = std::get<0>(info.param) + "_" +
                                           kCases[std::get<1>(info.param)].label;
                           for (char& ch : s)
                             if (ch == '-') ch = '_';
                           return s;
                         });

// The host kind reaches its class's own calls: ltc's prepare finds entries, its samples carry
// their pmf, and what record_nee gives it is learnt (against a twin prepared and sampled alike
// that records nothing, its pmfs move at the end of the pass).
TEST(SamplerView, HostKindRunsTheClassesCalls) {
  Fixture& f = fixture("cornell-boxes-room");
  auto ltc = make_light_sampler("ltc", f.scene, *f.tree, Params{});
  auto twin = make_light_sampler("ltc", f.scene, *f.tree, Params{});
  const SamplerView v = ltc->sampler_view(), vt = twin->sampler_view();
  ASSERT_EQ(v.kind, SamplerKind::Host);
  ASSERT_TRUE(v.prepares && v.learns);
  size_t with_cell = 0;
  Pcg32 rng(5);
  for (int pass = 0; pass < 2; ++pass) {
    for (const LightContext& c0 : f.contexts) {
      LightContext c = c0, ct = c0;
      prepare_point(v, c, 0.5f);
      prepare_point(vt, ct, 0.5f);
      with_cell += c.cell != kNoCell;
      for (int k = 0; k < 16; ++k) {
        const double u = rng.next_double();
        const SampledLight s = sample_light(v, c, u), st = sample_light(vt, ct, u);
        ASSERT_GT(st.pmf, 0);
        ASSERT_GT(s.pmf, 0);
        ASSERT_EQ(s.pmf, light_pmf(v, c, s.light));
        if (pass == 0) {  // (then what the first learnt differs)
          ASSERT_EQ(s.light, st.light);
        }
        NeeRecord r;
        r.estimate = r.unoccluded = r.max_rgb = s.light % 2 ? 1.0f : 0.0f;
        record_nee(v, c, s, r);
      }
    }
    ltc->end_pass();
    twin->end_pass();
  }
  EXPECT_GT(with_cell, f.contexts.size()) << "prepare_point did not reach ltc's prepare";
  size_t moved = 0;
  const SamplerView after = ltc->sampler_view(), twin_after = twin->sampler_view();
  for (const LightContext& c0 : f.contexts) {
    LightContext c = c0, ct = c0;
    prepare_point(after, c, 0.5f);
    prepare_point(twin_after, ct, 0.5f);
    for (uint32_t l = 0; l < f.scene.lights.size(); l += 3)
      moved += light_pmf(after, c, l) != light_pmf(twin_after, ct, l);
  }
  EXPECT_GT(moved, 0u) << "record_nee did not reach ltc's record";
}

// Every sampler has a view: ltc, without a device version, the host kind; rht its own.
TEST(SamplerView, EverySamplerHasAView) {
  Fixture& f = fixture("cornell-boxes-room");
  EXPECT_EQ(make_light_sampler("ltc", f.scene, *f.tree, Params{})->sampler_view().kind,
            SamplerKind::Host);
  EXPECT_EQ(make_light_sampler("rht", f.scene, *f.tree, Params{})->sampler_view().kind,
            SamplerKind::Rht);
  for (const char* name : {"uniform", "power", "tree", "rll", "fermat"})
    EXPECT_NE(make_light_sampler(name, f.scene, *f.tree, Params{})->sampler_view().kind,
              SamplerKind::Host)
        << name;
  // Every sampler with a device view renders on the GPU, rht too (its reservoirs in the path
  // slots' memory); ltc, the host kind, is refused by name.
  for (const char* name : {"uniform", "power", "tree", "rll", "fermat", "rht"})
    EXPECT_NO_THROW(
        cuda::require_device_version(*make_light_sampler(name, f.scene, *f.tree, Params{}), name))
        << name;
  EXPECT_THROW(
      cuda::require_device_version(*make_light_sampler("ltc", f.scene, *f.tree, Params{}), "ltc"),
      Error);
}

// The learnt cells the diagnostics read are what the sampler says it holds (no cast to its class):
// rll's and fermat's own, the oracle's frozen rll's with the oracle beside it, none elsewhere.
TEST(SamplerView, LearntCellsAreTheSamplersOwn) {
  Fixture& f = fixture("cornell-boxes-room");
  for (const char* name : {"uniform", "power", "tree", "ltc", "rht"}) {
    const auto s = make_light_sampler(name, f.scene, *f.tree, Params{});
    EXPECT_EQ(s->learnt_cells().rll, nullptr) << name;
    EXPECT_EQ(s->learnt_cells().oracle, nullptr) << name;
  }
  for (const char* name : {"rll", "fermat"}) {
    const auto s = make_light_sampler(name, f.scene, *f.tree, Params{});
    EXPECT_EQ(static_cast<const LightSampler*>(s->learnt_cells().rll), s.get()) << name;
    EXPECT_EQ(s->learnt_cells().oracle, nullptr) << name;
  }
  Params fast = Params::parse({"oracle.discovery_spp=1", "oracle.points=1", "oracle.rays=1",
                               "oracle.refine=0", "oracle.bounces=0"});
  const auto o = make_light_sampler("oracle", f.scene, *f.tree, fast, f.accel.get());
  ASSERT_NE(o->learnt_cells().oracle, nullptr);
  EXPECT_EQ(static_cast<const LightSampler*>(o->learnt_cells().oracle), o.get());
  EXPECT_EQ(o->learnt_cells().rll, &o->learnt_cells().oracle->rll());
  // Remade with the lights, the knowledge is the new rll's.
  o->lights_changed(f.scene);
  EXPECT_EQ(o->learnt_cells().rll, &o->learnt_cells().oracle->rll());
}

// Outside the factory (lights/light_sampler.cpp) nothing asks a sampler its class: no
// dynamic_cast to a sampler in the library, the command-line tool or the Python module (tests
// may); and the class keeps the host's lifecycle only, at most 7 virtual methods with the
// destructor.
TEST(SamplerView, ContractIsNarrowAndUncast) {
  namespace fs = std::filesystem;
  const fs::path root = RLL_SOURCE_DIR;
  const std::regex cast(R"(dynamic_cast<[^>]*LightSampler\b)");
  std::vector<std::string> found;
  for (const char* dir : {"src", "apps", "python"})
    for (const auto& e : fs::recursive_directory_iterator(root / dir)) {
      const std::string ext = e.path().extension().string();
      if (!e.is_regular_file() || (ext != ".cpp" && ext != ".h" && ext != ".cu")) continue;
      if (e.path().filename() == "light_sampler.cpp") continue;
      std::ifstream in(e.path());
      std::string line;
      for (int n = 1; std::getline(in, line); ++n)
        if (std::regex_search(line, cast))
          found.push_back(fs::relative(e.path(), root).string() + ":" + std::to_string(n));
    }
  EXPECT_TRUE(found.empty()) << "a dynamic_cast to a sampler at "
                             << ::testing::PrintToString(found);

  std::ifstream in(root / "src/rll/lights/light_sampler.h");
  ASSERT_TRUE(in) << "light_sampler.h";
  std::string line;
  int virtuals = 0;
  while (std::getline(in, line))
    if (std::regex_search(line, std::regex(R"(^\s*virtual\b)"))) ++virtuals;
  EXPECT_GE(virtuals, 1);
  EXPECT_LE(virtuals, 7) << "LightSampler keeps the host's lifecycle only";
}

// The power table's sample is the index whose interval of the CDF holds u, for a CDF summed here
// as DiscreteDistribution documents it (running sums of w / total), zero weights never drawn.
TEST(SamplerView, PowerTableInvertsItsCdf) {
  const std::vector<float> w = {0.5f, 0, 3, 1e-6f, 0, 0, 2, 7.25f, 0, 1};
  const DiscreteDistribution d(w);
  const DistributionView v = d.view();
  double total = 0;
  for (float x : w) total += x;
  std::vector<double> cdf;
  double acc = 0;
  for (float x : w) cdf.push_back(acc += x / total);
  cdf.back() = 1;
  Pcg32 rng(11);
  for (int i = 0; i < 20000; ++i) {
    const double u = i < 10 ? (i == 0 ? 0.0 : cdf[size_t(i - 1)]) : rng.next_double();
    double remapped = -1;
    const size_t k = sample_discrete(v, u, &remapped);
    ASSERT_LT(k, w.size());
    ASSERT_GT(w[k], 0) << "u " << u;
    ASSERT_LE(k == 0 ? 0.0 : cdf[k - 1], u);
    ASSERT_LT(u, cdf[k]);
    ASSERT_GE(remapped, 0);
    ASSERT_LT(remapped, 1);
    const SampledLight s = power_sample(v, u);
    ASSERT_EQ(s.light, k);
    ASSERT_EQ(s.pmf, float(w[k] / total));
  }
  EXPECT_EQ(power_pmf(v, uint32_t(w.size())), 0.0f);
  EXPECT_EQ(power_sample(DistributionView{}, 0.5).pmf, 0.0f) << "an empty table draws nothing";
}

// A SampleStream over tables of its own gives the host tables' values (what a device copy of them
// must give).
TEST(SamplerView, SampleStreamOverOwnTablesEqualsHostTables) {
  const SobolTables own;
  ASSERT_NE(own.view().tables, host_sobol_view().tables);
  for (uint64_t pixel = 0; pixel < 16; ++pixel)
    for (uint64_t k = 0; k < 16; ++k) {
      SampleStream a(own.view(), 9, pixel, k, PointSet::Sobol), b(9, pixel, k, PointSet::Sobol);
      for (int d = 0; d < 1100; d += 1 + d / 8) {
        a.seek(uint32_t(d));
        b.seek(uint32_t(d));
        ASSERT_EQ(a.next_double(), b.next_double()) << "dimension " << d;
      }
    }
}

}  // namespace
