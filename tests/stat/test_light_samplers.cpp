// The four checks every light sampler passes, through the dispatch every renderer runs
// (lights/light_dispatch.h over the sampler's view), on several built-in scenes and several
// hundred shading contexts each: sample_light's pmf equals light_pmf; pmfs sum to one; sampled
// counts fit N*pmf (chi-square, pooled small bins, Sidak-corrected); each light that can contribute
// has pmf > 0; and with stratified u each light is drawn N*pmf times to within one draw. Every
// check runs twice: learning samplers trained, and u drawn, with Owen-scrambled Sobol' points and
// with independent points (the renderer's two point sets).
#include <gtest/gtest.h>

#include <fmt/format.h>

#include "rll/accel/accel.h"
#include "rll/core/rng.h"
#include "support/sampler_contexts.h"
#include "support/statistics.h"

using namespace rll;
using namespace rll::test;

namespace {

struct SamplerCase {
  std::string label;
  std::string sampler;
  std::vector<std::string> set;
};

const std::vector<SamplerCase>& sampler_cases() {
  static const std::vector<SamplerCase> cases = {
      {"uniform", "uniform", {}},
      {"power", "power", {}},
      {"tree", "tree", {}},
      // RLL on a trained state (train_sampler renders passes first), every within-cluster mode.
      {"rll_tree", "rll", {}},
      {"rll_power", "rll", {"rll.within=power"}},
      // Cuts that start small and grow, a hybrid within-cluster rule, the mean target.
      {"rll_grow", "rll", {"rll.initial_cut=16", "rll.splits=4", "rll.within=hybrid", "rll.descend_above=8", "rll.target=mean"}},
      {"rll_tree_defensive", "rll", {"rll.defensive=tree", "rll.within=power", "rll.initial_cut=32", "rll.splits=2"}},
      {"rll_full_table", "rll", {"rll.capacity=48"}},
      {"rll_uniform", "rll", {"rll.within=uniform"}},
      // The guided descent: the tree's steps scaled by the cell's learnt factors above the cut;
      // with a full table, and with lights drawn by power inside a smaller cut's clusters.
      {"rll_guided", "rll", {"rll.sampling=guided", "rll.capacity=48"}},
      {"rll_guided_power", "rll", {"rll.sampling=guided", "rll.within=power", "rll.cut_size=24", "rll.epsilon=0.02"}},
      // Finer cells where the light changes (rll.refine): two levels, a low gain, so that many
      // of the contexts' cells are refined cells' children.
      {"rll_refine", "rll", {"rll.refine=2", "rll.refine_gain=0.1", "rll.refine_min=32"}},
      // The error budget's ideal light within a cluster (rll.ideal_light, docs/rll.md): the host
      // kind around rll, its tables at the cells' anchors.
      {"rll_ideal_light", "rll", {"rll.ideal_light=2"}},
      // Fermat's RLL as published, and with uniform choice inside clusters (cold cells uniform).
      {"fermat", "fermat", {}},
      {"fermat_uniform", "fermat", {"fermat.within=uniform", "fermat.reset_every=8"}},
      {"rll_paper",
       "rll",
       {"rll.within=uniform", "rll.reward=fullpdf", "rll.prior=power", "rll.split_by=power"}},
      // Wang et al. 2021 (ltc): defaults, and a small table with few clusters, small cuts and a
      // large defensive weight (full table: tree fallback beside learnt entries).
      {"ltc", "ltc", {}},
      {"ltc_small", "ltc", {"ltc.clusters=64", "ltc.bins=2", "ltc.capacity=40", "ltc.initial_cut=2", "ltc.max_cut=6", "ltc.epsilon=0.5"}},
  };
  return cases;
}

// spot-hall-small: spot lights (whose cones exclude most points), a point light, a lamp and a
// sun in one tree. screen-hall: large textured emitters split into pieces of nearly equal power.
const std::vector<std::string> kScenes = {"cornell-box",      "cornell-boxes-room", "arch-interior",
                                          "many-lights-open", "furnace",            "spot-hall-small",
                                          "screen-hall"};
constexpr int kContexts = 200;
constexpr int kChiContexts = 6;
constexpr int kChiSamples = 20000;
// Every chi-square test of this file, for the Sidak correction.
const int kChiTests = int(kScenes.size() * sampler_cases().size()) * kChiContexts * 2;
using Param = std::tuple<size_t, std::string, PointSet>;

// The sampler reached as every renderer reaches it: the dispatch over its view.
struct Fixture : SamplerScene {
  std::vector<LightContext> contexts;
  SamplerView view;
  SampledLight sample(const LightContext& ctx, double u) const {
    return sample_light(view, ctx, u);
  }
  float pmf(const LightContext& ctx, uint32_t light) const { return light_pmf(view, ctx, light); }
};

Fixture make_fixture(const SamplerCase& c, const std::string& scene_name, PointSet points) {
  Fixture f{sampler_scene(scene_name, c.sampler, c.set), {}, {}};
  train_sampler(f.scene, *f.accel, *f.sampler, 32,
                points);  // RLL: strongly non-uniform cells (test_rll_learning)
  f.view = f.sampler->sampler_view();
  f.contexts = make_contexts(f.scene, *f.accel, kContexts, 1234);
  for (size_t i = 0; i < f.contexts.size(); ++i)
    prepare_point(f.view, f.contexts[i], float(i % 97) / 97.0f);
  return f;
}

class LightSamplerStat : public ::testing::TestWithParam<Param> {
 protected:
  static std::map<Param, Fixture>& cache() {
    static std::map<Param, Fixture> c;
    return c;
  }
  Fixture& fixture() {
    const Param& key = GetParam();
    auto it = cache().find(key);
    if (it == cache().end())
      it = cache()
               .emplace(key, make_fixture(sampler_cases()[std::get<0>(key)], std::get<1>(key),
                                          std::get<2>(key)))
               .first;
    return it->second;
  }
  PointSet points() const { return std::get<2>(GetParam()); }
};

TEST_P(LightSamplerStat, SampledPmfEqualsPmf) {
  Fixture& f = fixture();
  for (size_t c = 0; c < f.contexts.size(); ++c)
    for (int k = 0; k < 64; ++k) {
      const LightContext& ctx = f.contexts[c];
      SampledLight s = f.sample(ctx, SampleStream(99, c, uint64_t(k), points()).next_double());
      ASSERT_GT(s.pmf, 0) << "sample returned no light";
      ASSERT_EQ(s.pmf, f.pmf(ctx, s.light)) << "light " << s.light;
    }
}

TEST_P(LightSamplerStat, PmfsSumToOne) {
  Fixture& f = fixture();
  const uint32_t n = uint32_t(f.scene.lights.size());
  for (size_t i = 0; i < f.contexts.size(); ++i) {
    double sum = 0;
    for (uint32_t l = 0; l < n; ++l) sum += f.pmf(f.contexts[i], l);
    ASSERT_NEAR(sum, 1.0, 1e-4) << "context " << i;
  }
}

TEST_P(LightSamplerStat, ContributingLightsHavePositivePmf) {
  Fixture& f = fixture();
  const uint32_t n = uint32_t(f.scene.lights.size());
  // Checking every light at every context is slow for 10k lights: a strided subset of both.
  const uint32_t stride = n > 3000 ? 7 : 1;
  for (size_t i = 0; i < f.contexts.size(); i += 2)
    for (uint32_t l = uint32_t(i % stride); l < n; l += stride) {
      if (!light_can_contribute(f.scene.lights[l], f.contexts[i].p, f.contexts[i].n)) continue;
      ASSERT_GT(f.pmf(f.contexts[i], l), 0) << "context " << i << " light " << l;
    }
}

TEST_P(LightSamplerStat, ChiSquareOfSampledCounts) {
  Fixture& f = fixture();
  const size_t n = f.scene.lights.size();
  const double alpha = sidak_alpha(0.01, kChiTests);
  for (int c = 0; c < kChiContexts; ++c) {
    const LightContext& ctx = f.contexts[size_t(c) * f.contexts.size() / kChiContexts];
    std::vector<double> observed(n, 0), expected(n, 0);
    for (int k = 0; k < kChiSamples; ++k)
      observed[f.sample(ctx, SampleStream(4242, uint64_t(c), uint64_t(k), points()).next_double())
                   .light] += 1;
    for (uint32_t l = 0; l < n; ++l) expected[l] = double(kChiSamples) * f.pmf(ctx, l);
    ChiSquareResult r = chi_square(observed, expected);
    EXPECT_FALSE(r.sample_in_zero_bin) << "context " << c << ": a light with pmf 0 was sampled";
    EXPECT_GT(r.p_value, alpha) << "context " << c << ": chi2 " << r.chi2 << " dof " << r.dof;
  }
}

TEST_P(LightSamplerStat, StratifiedCountsMatchPmf) {
  // With u stratified over [0,1), each light's share of draws divided by its pmf is one to
  // within two draws: sum over draws of [light]/(pmf*N) ~ 1 (pbrt's sampler test). Every
  // sampler maps u to a light through at most two intervals of u per light (RLL's defensive
  // mixture has two branches; the others one), so the count is N*pmf +- 2.
  Fixture& f = fixture();
  const size_t n = f.scene.lights.size();
  const int N = 200000;
  for (int c = 0; c < 3; ++c) {
    const LightContext& ctx = f.contexts[size_t(c) * 37 % f.contexts.size()];
    std::vector<double> count(n, 0);
    for (int k = 0; k < N; ++k) count[f.sample(ctx, (k + 0.5) / N).light] += 1;
    for (uint32_t l = 0; l < n; ++l) {
      double p = f.pmf(ctx, l);
      if (p == 0) {
        ASSERT_EQ(count[l], 0) << "light " << l << " drawn with pmf 0";
        continue;
      }
      double expected = p * N;
      ASSERT_NEAR(count[l] / expected, 1.0, 2.0 / expected + 1e-4)
          << "context " << c << " light " << l;
    }
  }
}

std::string case_name(const ::testing::TestParamInfo<Param>& info) {
  std::string s = sampler_cases()[std::get<0>(info.param)].label + "_" + std::get<1>(info.param) +
                  "_" + point_set_name(std::get<2>(info.param));
  for (auto& ch : s)
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  return s;
}

INSTANTIATE_TEST_SUITE_P(AllSamplers, LightSamplerStat,
                         ::testing::Combine(::testing::Range<size_t>(0, sampler_cases().size()),
                                            ::testing::ValuesIn(kScenes),
                                            ::testing::Values(PointSet::Sobol,
                                                              PointSet::Independent)),
                         case_name);

}  // namespace
