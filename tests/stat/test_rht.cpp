// The resampled hierarchical tree's split descent (lights/rht_view.h) and reservoirs
// (render/rht_nee.h): the probability that a draw yields a light, replayed along the light's path
// (rht_pmf), equals the pdf the descent gave it to the bit and the frequency at which draws yield
// it; every light that can contribute can be yielded; the first stage weighs a candidate by its
// tree importance over that probability; a reservoir keeps each of its items with probability
// weight / (its weight sum). On cornell-boxes-room (local lights and a sky dome), arch-interior
// (a sky dome and a directional sun, which rht chooses first) and many-lights-open (10,240 lights).
#include <gtest/gtest.h>

#include <cmath>

#include "rll/accel/accel.h"
#include "rll/lights/rht_sampler.h"
#include "rll/lighttree/light_tree.h"
#include "rll/render/rht_nee.h"
#include "support/sampler_contexts.h"
#include "support/statistics.h"

using namespace rll;
using namespace rll::test;

namespace {

const std::vector<std::string> kScenes = {"cornell-boxes-room", "arch-interior",
                                          "many-lights-open"};
constexpr int kContexts = 120;     // reachability and exact pdfs
constexpr int kFreqContexts = 24;  // yield frequencies
constexpr int kDraws = 12000;      // draws per frequency context

struct Fixture : SamplerScene {
  RhtView view;  // the sampler's view's (SamplerKind::Rht)
  std::vector<LightContext> contexts;
};

Fixture make_fixture(const std::string& scene_name, const std::vector<std::string>& set) {
  Fixture f{sampler_scene(scene_name, "rht", set), {}, {}};
  f.view = f.sampler->sampler_view().rht;
  f.contexts = make_contexts(f.scene, *f.accel, kContexts, 4321);
  return f;
}

struct Draw {
  double u;
  float u_split;
  uint64_t key;
};
Draw draw_numbers(uint64_t context, uint64_t k) {
  SampleStream s(77, context, k, PointSet::Independent);
  Draw d;
  d.u = s.next_double();
  d.u_split = s.next();
  d.key = mix64(uint64_t(s.next_double() * 0x1p53));
  return d;
}

// The descent's share of draws and the number its u is rescaled to, as rht_nee takes them.
float descent_share(const RhtView& v) {
  return 1 - rht_directional_probability(v);
}

class RhtDescent : public ::testing::TestWithParam<std::string> {
 protected:
  static Fixture& fixture() {
    static std::map<std::string, Fixture> cache;
    const std::string& name = GetParam();
    auto it = cache.find(name);
    if (it == cache.end()) it = cache.emplace(name, make_fixture(name, {})).first;
    return it->second;
  }
};

// Every yielded candidate's pdf is rht_pmf of its light exactly, its weight's importance is the
// leaf's tree importance, and no light is yielded twice by one draw.
TEST_P(RhtDescent, YieldedPdfEqualsReplayedPmfAndWeightIsImportance) {
  Fixture& f = fixture();
  const RhtView& v = f.view;
  const LightTreeView& t = v.tree;
  std::vector<int> seen(f.scene.lights.size(), -1);
  long yields = 0;
  for (size_t c = 0; c < f.contexts.size(); ++c) {
    const LightContext& ctx = f.contexts[c];
    for (int k = 0; k < 64; ++k) {
      const Draw d = draw_numbers(c, uint64_t(k));
      const int stamp = int(c * 64 + size_t(k));
      rht_descend(v, ctx.p, ctx.n, d.u, d.u_split, d.key, descent_share(v),
                  [&](uint32_t light, float pdf, float importance) {
                    ++yields;
                    ASSERT_NE(seen[light], stamp) << "light " << light << " yielded twice";
                    seen[light] = stamp;
                    ASSERT_FALSE(rht_is_directional(v, light));
                    ASSERT_GT(pdf, 0);
                    ASSERT_EQ(pdf, rht_pmf(v, ctx.p, ctx.n, light)) << "light " << light;
                    ASSERT_EQ(pdf, light_pmf(f.sampler->sampler_view(), ctx, light));
                    ASSERT_EQ(importance,
                              light_importance(t.bounds(t.leaf_of[light]), ctx.p, ctx.n));
                    ASSERT_GT(importance, 0);
                  });
    }
  }
  EXPECT_GT(yields, long(f.contexts.size()) * 64 / 2) << "the descent yields almost nothing";
}

// A light that can contribute at the point (the exact test of every sampler's check) has a
// positive rht_pmf; directional lights have their share.
TEST_P(RhtDescent, ContributingLightsAreReachable) {
  Fixture& f = fixture();
  const RhtView& v = f.view;
  const uint32_t n = uint32_t(f.scene.lights.size());
  const uint32_t stride = n > 3000 ? 7 : 1;
  for (size_t i = 0; i < f.contexts.size(); i += 2) {
    const LightContext& ctx = f.contexts[i];
    for (uint32_t l = uint32_t(i % stride); l < n; l += stride) {
      if (light_can_contribute(f.scene.lights[l], ctx.p, ctx.n)) {
        ASSERT_GT(rht_pmf(v, ctx.p, ctx.n, l), 0) << "context " << i << " light " << l;
      }
    }
  }
}

// Each light is yielded by a share of draws equal to its rht_pmf: per light a binomial count
// (a draw yields a light at most once), z within the Sidak-corrected normal bound over every
// light and context; the lights with few expected yields are pooled, their sum bounded by the
// sum of their standard deviations (the yields of different lights are correlated).
TEST_P(RhtDescent, YieldFrequenciesMatchPmf) {
  Fixture& f = fixture();
  const RhtView& v = f.view;
  const size_t n = f.scene.lights.size();
  const double z_max = 5.5;  // two-sided normal tail 4e-8: Sidak-safe over ~1e5 tests per scene
  for (int c = 0; c < kFreqContexts; ++c) {
    const size_t ci = size_t(c) * f.contexts.size() / kFreqContexts;
    const LightContext& ctx = f.contexts[ci];
    std::vector<double> count(n, 0);
    for (int k = 0; k < kDraws; ++k) {
      const Draw d = draw_numbers(1000 + ci, uint64_t(k));
      rht_descend(v, ctx.p, ctx.n, d.u, d.u_split, d.key, descent_share(v),
                  [&](uint32_t light, float, float) { count[light] += 1; });
    }
    double pooled_obs = 0, pooled_exp = 0, pooled_sd = 0;
    for (uint32_t l = 0; l < n; ++l) {
      if (rht_is_directional(v, l)) continue;
      // The descent runs on the share of draws that do not take a directional light.
      const double p = rht_pmf(v, ctx.p, ctx.n, l) / descent_share(v);
      if (p == 0) {
        ASSERT_EQ(count[l], 0) << "context " << c << " light " << l << " yielded with pmf 0";
        continue;
      }
      ASSERT_LE(p, 1.0 + 1e-6) << "light " << l;
      const double e = kDraws * p, var = kDraws * p * (1 - p);
      if (var < 20) {
        pooled_obs += count[l];
        pooled_exp += e;
        pooled_sd += std::sqrt(var);
        continue;
      }
      ASSERT_LE(std::abs(count[l] - e), z_max * std::sqrt(var) + 1e-9)
          << "context " << c << " light " << l << ": yielded " << count[l] << " of " << kDraws
          << " draws, expected " << e;
    }
    EXPECT_LE(std::abs(pooled_obs - pooled_exp), z_max * pooled_sd + 1)
        << "context " << c << ": rarely yielded lights " << pooled_obs << " vs " << pooled_exp;
  }
}

INSTANTIATE_TEST_SUITE_P(Scenes, RhtDescent, ::testing::ValuesIn(kScenes), [](const auto& info) {
  std::string s = info.param;
  for (auto& ch : s)
    if (ch == '-') ch = '_';
  return s;
});

// The test above can fail: a descent that reports its candidates' pdfs 5% low for one light
// (the error the review feared: sample and pmf agreeing, both off) is seen at some context.
TEST(RhtDescentPower, FrequencyTestSeesAFivePercentError) {
  Fixture f = make_fixture("cornell-boxes-room", {});
  const RhtView& v = f.view;
  int seen = 0;
  for (int c = 0; c < 6; ++c) {
    const LightContext& ctx = f.contexts[size_t(c) * 7];
    std::vector<double> count(f.scene.lights.size(), 0);
    const int draws = 40000;
    for (int k = 0; k < draws; ++k) {
      const Draw d = draw_numbers(5000 + uint64_t(c), uint64_t(k));
      rht_descend(v, ctx.p, ctx.n, d.u, d.u_split, d.key, descent_share(v),
                  [&](uint32_t light, float, float) { count[light] += 1; });
    }
    // The most often yielded light that not every draw yields, its pmf claimed 5% lower.
    uint32_t best = 0;
    double best_count = -1;
    for (uint32_t l = 0; l < count.size(); ++l)
      if (!rht_is_directional(v, l) && count[l] > best_count &&
          rht_pmf(v, ctx.p, ctx.n, l) / descent_share(v) < 0.9) {
        best = l;
        best_count = count[l];
      }
    const double p = 0.95 * rht_pmf(v, ctx.p, ctx.n, best) / descent_share(v);
    const double e = draws * p, sd = std::sqrt(draws * p * (1 - p));
    if (std::abs(count[best] - e) > 5.5 * sd) ++seen;
  }
  EXPECT_GT(seen, 0) << "no context's frequency test sees a 5% error of its most yielded light";
}

// Reservoirs keep each item of their share with probability weight / weight sum, with five
// items per reservoir (the public code's golden-ratio decisions fail this past two items):
// chi-square of the kept items over many independent keys.
TEST(RhtReservoirs, KeepEachItemWithWeightOverSum) {
  const int reservoirs = 3, items = 15, trials = 60000;
  const float w[items] = {1, 5, 0.5f, 2, 9, 3, 3, 0.2f, 7, 1, 4, 6, 0.1f, 2, 8};
  std::vector<double> observed(items, 0), expected(items, 0);
  std::vector<int> slot_of(items, -1);
  for (int t = 0; t < trials; ++t) {
    detail::RhtReservoirs r(reservoirs, mix64(uint64_t(t) * 0x9e3779b97f4a7c15ull + 17));
    float sum[reservoirs] = {0, 0, 0};
    int kept[reservoirs] = {-1, -1, -1};
    int slot[items];
    for (int i = 0; i < items; ++i) {
      slot[i] = r.slot();
      if (r.keeps(w[i], sum[slot[i]])) kept[slot[i]] = i;
    }
    for (int s = 0; s < reservoirs; ++s) {
      ASSERT_GE(kept[s], 0) << "reservoir " << s << " kept nothing";
      observed[size_t(kept[s])] += 1;
      // Expected: this trial's reservoir s keeps item i with probability w_i / sum_s.
      for (int i = 0; i < items; ++i)
        if (slot[i] == s) expected[size_t(i)] += w[i] / sum[s];
    }
    // Each batch of `reservoirs` items is spread one per reservoir.
    for (int b = 0; b < items; b += reservoirs)
      for (int i = b; i < b + reservoirs; ++i)
        for (int j = i + 1; j < b + reservoirs; ++j) ASSERT_NE(slot[i], slot[j]);
  }
  const ChiSquareResult res = chi_square(observed, expected);
  EXPECT_GT(res.p_value, 1e-4) << "chi2 " << res.chi2 << " dof " << res.dof;
}

}  // namespace
