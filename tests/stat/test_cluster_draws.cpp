// Candidates from one cluster (nee.draw=cluster, docs/nee.md): sample_in_cluster draws from the
// cluster of a first draw with the distribution the sampler itself draws that cluster's lights
// with. Checked through the dispatch, as the renderers reach it: every second draw lies in the
// first one's cluster and carries the light's full pmf; the second draw's marginal over lights
// (first draw, then one in its cluster) is the sampler's own distribution, light_pmf (chi-square
// over independent pairs, counts of stratified pairs); which is what makes the candidates i.i.d.
// within the cluster, and resampling within it unbiased.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "rll/core/sampling.h"
#include "rll/lights/light_dispatch.h"
#include "support/sampler_contexts.h"
#include "support/statistics.h"

using namespace rll;
using namespace rll::test;

namespace {

struct ClusterCase {
  std::string label;
  std::vector<std::string> set;
  int passes;  // 0: untrained, every cell without a cut (the tree's draw below the cluster)
};

const std::vector<ClusterCase>& cluster_cases() {
  static const std::vector<ClusterCase> cases = {
      {"rll", {}, 8},
      {"rll_untrained", {}, 0},
      {"rll_defensive_tree", {"rll.defensive=tree", "rll.initial_cut=32", "rll.splits=2"}, 8},
      {"rll_power", {"rll.within=power"}, 8},
      {"rll_hybrid", {"rll.within=hybrid", "rll.descend_above=8"}, 8},
      {"rll_guided", {"rll.sampling=guided"}, 8},
      {"rll_cold_uniform", {"rll.cold=uniform"}, 1},
  };
  return cases;
}

const std::vector<std::string> kScenes = {"cornell-boxes-room", "arch-interior", "spot-hall-small"};
constexpr int kContexts = 60;
constexpr int kChiContexts = 3;
constexpr int kChiSamples = 20000;

using Param = std::tuple<size_t, std::string>;

class ClusterDraws : public ::testing::TestWithParam<Param> {};

// The cluster of light l in the point's cut (what rll_sample records), from the view's arrays.
uint32_t cluster_of(const SamplerView& v, const LightContext& ctx, uint32_t light) {
  return detail::rll_cluster_of(detail::rll_cut(*v.rll, ctx.cell), light);
}

TEST_P(ClusterDraws, SameClusterFullPmfAndMarginal) {
  const ClusterCase& c = cluster_cases()[std::get<0>(GetParam())];
  SamplerScene s = sampler_scene(std::get<1>(GetParam()), "rll", c.set);
  if (c.passes > 0) train_sampler(s.scene, *s.accel, *s.sampler, c.passes);
  const SamplerView v = s.sampler->sampler_view();
  ASSERT_TRUE(draws_clusters(v));
  std::vector<LightContext> contexts = make_contexts(s.scene, *s.accel, kContexts, 77);
  for (size_t i = 0; i < contexts.size(); ++i) prepare_point(v, contexts[i], float(i % 89) / 89.0f);
  const uint32_t n = uint32_t(s.scene.lights.size());

  // Every second draw: in the first one's cluster, with the light's full pmf (the cluster's
  // probability times the light's within it: a product in another order than light_pmf's, so
  // equal to a few ulps), never a light the sampler cannot draw.
  for (size_t ci = 0; ci < contexts.size(); ++ci) {
    const LightContext& ctx = contexts[ci];
    for (int k = 0; k < 24; ++k) {
      SampleStream stream(5, ci, uint64_t(k));
      const SampledLight first = sample_light(v, ctx, stream.next_double());
      ASSERT_GT(first.pmf, 0);
      const SampledLight second = sample_in_cluster(v, ctx, first, stream.next_double());
      ASSERT_GT(second.pmf, 0) << "context " << ci;
      EXPECT_EQ(cluster_of(v, ctx, second.light), cluster_of(v, ctx, first.light))
          << "context " << ci << " lights " << first.light << ", " << second.light;
      const float pmf = light_pmf(v, ctx, second.light);
      EXPECT_NEAR(second.pmf, pmf, 1e-5f * pmf) << "context " << ci << " light " << second.light;
      const ClusterDraw a = cluster_draw(first), b = cluster_draw(second);
      EXPECT_EQ(b.cluster, a.cluster);
      EXPECT_EQ(b.cluster_pmf, a.cluster_pmf);
      EXPECT_EQ(b.target, a.target);
    }
  }

  // The cluster's probability in the first draw's record is the sum of light_pmf over the
  // cluster's lights (so P(l | cluster) = pmf / it sums to one over the cluster).
  for (size_t ci = 0; ci < contexts.size(); ci += 7) {
    const LightContext& ctx = contexts[ci];
    const SampledLight first = sample_light(v, ctx, SampleStream(6, ci, 0).next_double());
    const uint32_t k = cluster_of(v, ctx, first.light);
    double sum = 0;
    for (uint32_t l = 0; l < n; ++l)
      if (cluster_of(v, ctx, l) == k) sum += light_pmf(v, ctx, l);
    EXPECT_NEAR(sum / cluster_draw(first).cluster_pmf, 1.0, 1e-4) << "context " << ci;
  }

  // The second draw's marginal is light_pmf: independent pairs by chi-square (Sidak over every
  // context of every case and scene); no light of pmf 0 is ever drawn.
  const double alpha =
      sidak_alpha(0.01, int(cluster_cases().size() * kScenes.size()) * kChiContexts);
  for (int cc = 0; cc < kChiContexts; ++cc) {
    const LightContext& ctx = contexts[size_t(cc) * 17 % contexts.size()];
    std::vector<double> random(n, 0), expected(n, 0);
    for (int k = 0; k < kChiSamples; ++k) {
      SampleStream stream(4243, uint64_t(cc), uint64_t(k));
      const SampledLight first = sample_light(v, ctx, stream.next_double());
      const SampledLight second = sample_in_cluster(v, ctx, first, stream.next_double());
      if (second.pmf > 0) random[second.light] += 1;
    }
    for (uint32_t l = 0; l < n; ++l) {
      expected[l] = light_pmf(v, ctx, l) * kChiSamples;
      if (expected[l] == 0) ASSERT_EQ(random[l], 0) << "light " << l << " drawn with pmf 0";
    }
    const ChiSquareResult chi = chi_square(random, expected);
    EXPECT_FALSE(chi.sample_in_zero_bin) << "context " << cc;
    EXPECT_GT(chi.p_value, alpha) << c.label << " context " << cc << ": chi2 " << chi.chi2
                                  << " dof " << chi.dof;
  }
}

std::string case_name(const ::testing::TestParamInfo<Param>& info) {
  std::string scene = std::get<1>(info.param);
  for (char& ch : scene)
    if (ch == '-') ch = '_';
  return cluster_cases()[std::get<0>(info.param)].label + "_" + scene;
}

INSTANTIATE_TEST_SUITE_P(Rll, ClusterDraws,
                         ::testing::Combine(::testing::Range(size_t(0), cluster_cases().size()),
                                            ::testing::ValuesIn(kScenes)),
                         case_name);

// Where a cluster's lights would come from a mixture of two rules (the tree's defensive descent
// and a table inside the cluster), and for samplers without clusters, there is no such draw.
TEST(ClusterDraws, RefusedWhereNotExact) {
  SamplerScene mixed =
      sampler_scene("cornell-box", "rll", {"rll.defensive=tree", "rll.within=power"});
  EXPECT_FALSE(draws_clusters(mixed.sampler->sampler_view()));
  SamplerScene tree = sampler_scene("cornell-box", "tree", {});
  EXPECT_FALSE(draws_clusters(tree.sampler->sampler_view()));
  SamplerScene rll = sampler_scene("cornell-box", "rll", {});
  EXPECT_TRUE(draws_clusters(rll.sampler->sampler_view()));
}

}  // namespace
