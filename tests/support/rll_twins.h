// Two rll samplers of one scene and settings fed the same points and rewards, pass after pass:
// what the tests of RLL's end of pass run another way (another backend, the GPU) compare with
// the CPU's end_pass.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "rll/accel/accel.h"
#include "rll/core/params.h"
#include "rll/core/rng.h"
#include "rll/lights/rll_sampler.h"
#include "support/sampler_contexts.h"
#include "support/test_support.h"

namespace rll::test {

struct RllTwins {
  Scene scene;
  LightTree tree;
  std::unique_ptr<Accel> accel;
  std::vector<LightContext> contexts;
  std::unique_ptr<RllLightSampler> a, b;

  // `sampler`: rll or fermat, with --set assignments.
  RllTwins(const std::string& scene_name, const std::string& sampler,
           const std::vector<std::string>& set) {
    scene = small_builtin_scene(scene_name, 32, 24);
    tree = build_light_tree(scene);
    accel = std::make_unique<Accel>(scene.mesh);
    contexts = make_contexts(scene, *accel, 300, 21);
    // (A table of 4096 cells unless the case sets one: the default's 32768 cells of cuts take
    // most of a test's time to allocate.)
    std::vector<std::string> all = set;
    if (std::none_of(set.begin(), set.end(),
                     [](const std::string& a) { return a.find(".capacity=") != std::string::npos; }))
      all.push_back(sampler + ".capacity=4096");
    const Params p = Params::parse(all);
    const RllSettings s = sampler == "fermat" ? rll_settings_from(p, "fermat", fermat_settings())
                                              : rll_settings_from(p, "rll");
    a = std::make_unique<RllLightSampler>(scene, tree, s);
    b = std::make_unique<RllLightSampler>(scene, tree, s);
  }

  // One pass: every point looked up in both (one thread, so that both hand out cell ids in one
  // order) and given a few rewards of clusters its cell has in both.
  void feed(Pcg32& rng) {
    for (const LightContext& c : contexts) {
      LightContext ca = c, cb = c;
      const float u = rng.next_float();
      prepare_point(a->sampler_view(), ca, u);
      prepare_point(b->sampler_view(), cb, u);
      ASSERT_EQ(ca.cell, cb.cell);
      if (ca.cell == kNoCell) continue;
      auto clusters = [&](const RllLightSampler& s) {
        return s.cuts().active(ca.cell) ? s.cuts().size(ca.cell) : s.cuts().initial_size();
      };
      const uint32_t K = std::min(clusters(*a), clusters(*b));
      for (int i = 0; i < 4; ++i) {
        const uint32_t k = rng.next_bounded(K);
        const float r = rng.next_float() < 0.4f ? 0.0f : 3 * rng.next_float() * float(k % 5 + 1);
        a->cuts().record(ca.cell, k, r);
        b->cuts().record(ca.cell, k, r);
      }
    }
  }
};

// Equal within `tolerance` relative (0: to the bit).
inline bool near(float x, float y, float tolerance) {
  if (tolerance == 0) return std::bit_cast<uint32_t>(x) == std::bit_cast<uint32_t>(y);
  return x == y || std::abs(x - y) <= tolerance * std::max({1.0f, std::abs(x), std::abs(y)});
}

// The twins' learnt states compared: the same cells under the same keys, every key found in
// both; per cell with the same cut (all of them when `tolerance` is 0, at least 98% otherwise:
// a rounding may decide a split differently), values and tables within `tolerance`; the coarse
// cells of pooling alike. Returns the cells in use.
inline uint32_t expect_same_learning(const RllLightSampler& a, const RllLightSampler& b,
                                     float tolerance) {
  const CutStore& ca = a.cuts();
  const CutStore& cb = b.cuts();
  uint32_t used = 0, same_cut = 0;
  EXPECT_EQ(a.table().used(), b.table().used());
  EXPECT_EQ(a.passes(), b.passes());
  for (uint32_t c = 0; c < a.table().capacity(); ++c) {
    EXPECT_EQ(a.table().key_of(c), b.table().key_of(c)) << "cell " << c;
    if (!a.table().in_use(c)) continue;
    ++used;
    EXPECT_EQ(a.table().find(a.table().key_of(c)), c);
    EXPECT_EQ(b.table().find(a.table().key_of(c)), c);
    EXPECT_EQ(ca.active(c), cb.active(c)) << "cell " << c;
    if (ca.size(c) != cb.size(c) ||
        !std::equal(ca.nodes(c), ca.nodes(c) + ca.size(c), cb.nodes(c)))
      continue;
    ++same_cut;
    for (uint32_t k = 0; k < ca.size(c); ++k) {
      EXPECT_TRUE(near(ca.q(c)[k], cb.q(c)[k], tolerance)) << "cell " << c << " cluster " << k;
      EXPECT_TRUE(near(ca.m2(c)[k], cb.m2(c)[k], tolerance)) << "cell " << c << " cluster " << k;
      EXPECT_TRUE(near(ca.cdf(c)[k], cb.cdf(c)[k], tolerance)) << "cell " << c << " cluster " << k;
      EXPECT_TRUE(near(ca.target_factor(c)[k], cb.target_factor(c)[k], tolerance))
          << "cell " << c << " cluster " << k;
    }
    EXPECT_TRUE(near(ca.defensive_weight(c), cb.defensive_weight(c), tolerance)) << "cell " << c;
    const CellAnchor &x = ca.anchor(c), &y = cb.anchor(c);
    EXPECT_TRUE(near(x.p.x, y.p.x, tolerance) && near(x.p.y, y.p.y, tolerance) &&
                near(x.p.z, y.p.z, tolerance))
        << "cell " << c;
    const float *sa = ca.pool_shares(c), *sb = cb.pool_shares(c);
    EXPECT_EQ(sa == nullptr, sb == nullptr) << "cell " << c;
    if (sa && sb) {
      for (uint32_t k = 0; k < ca.initial_size(); ++k)
        EXPECT_TRUE(near(sa[k], sb[k], tolerance)) << "cell " << c << " share " << k;
    }
  }
  if (tolerance == 0) {
    EXPECT_EQ(same_cut, used);
  } else {
    EXPECT_GE(same_cut, used * 98 / 100);
  }
  const auto &pa = a.pool(), &pb = b.pool();
  EXPECT_EQ(std::vector<uint64_t>(pa.keys.begin(), pa.keys.end()),
            std::vector<uint64_t>(pb.keys.begin(), pb.keys.end()));
  if (pa.q.size() == pb.q.size())
    for (size_t i = 0; i < pa.q.size(); ++i) {
      EXPECT_TRUE(near(pa.q[i], pb.q[i], tolerance)) << "coarse cluster " << i;
      EXPECT_TRUE(near(pa.n[i], pb.n[i], tolerance)) << "coarse cluster " << i;
    }
  const nlohmann::json da = a.describe(), db = b.describe();
  for (const char* k : {"evictions", "failed_inserts", "resets", "cells_used", "pool_cells",
                        "cells_touched_per_pass"})
    EXPECT_EQ(da[k], db[k]) << k;
  if (tolerance == 0) {
    for (const char* k : {"splits_per_pass", "collapses_per_pass", "changes_per_pass",
                          "pool_changes_per_pass"})
      EXPECT_EQ(da[k], db[k]) << k;
  }
  return used;
}

// The settings the end-of-pass tests run: pooling in its variants, growing cuts, the guided
// descent, target=mean, both forgetting rules, a table small enough to evict, Fermat's reset.
struct RllEndPassCase {
  const char* label;
  const char* sampler;
  std::vector<std::string> set;
};
inline std::vector<RllEndPassCase> rll_end_pass_cases() {
  return {{"rll", "rll", {}},
          {"pool2-share", "rll", {"rll.pool=2", "rll.pool_up=0", "rll.pool_guess=share"}},
          {"pool_up2", "rll", {"rll.pool_up=2"}},
          {"splits4", "rll", {"rll.splits=4", "rll.cut_size=48", "rll.initial_cut=16"}},
          {"guided", "rll", {"rll.sampling=guided", "rll.cut_size=32"}},
          {"mean-floor", "rll", {"rll.target=mean", "rll.forget=floor"}},
          {"capacity40", "rll", {"rll.capacity=40"}},
          {"fermat-reset3", "fermat", {"fermat.reset_every=3"}}};
}

// The case's twins through 7 passes, a's end of pass its own, b's by `end_pass`, compared after
// each (expect_same_learning within `tolerance`); a's description at the end.
inline nlohmann::json run_end_pass_case(const RllEndPassCase& c,
                                        const std::function<void(RllLightSampler&)>& end_pass,
                                        float tolerance) {
  SCOPED_TRACE(c.label);
  RllTwins t("cornell-boxes-room", c.sampler, c.set);
  Pcg32 rng(7);
  uint32_t cells = 0;
  for (int pass = 0; pass < 7; ++pass) {
    t.feed(rng);
    t.a->end_pass();
    end_pass(*t.b);
    SCOPED_TRACE(pass);
    cells += expect_same_learning(*t.a, *t.b, tolerance);
    if (testing::Test::HasFailure()) break;
  }
  EXPECT_GT(cells, 0u);
  return t.a->describe();
}

}  // namespace rll::test
