// The sampling building blocks: DiscreteDistribution, the counter-based SampleStream, the
// orthonormal Frame and the warps from the unit square.
#include <gtest/gtest.h>

#include <numeric>
#include <set>

#include "rll/core/math.h"
#include "rll/core/rng.h"
#include "rll/core/sampling.h"
#include "support/sphere_chi2.h"

using namespace rll;
using namespace rll::test;

namespace {

TEST(DiscreteDistribution, PmfSumsToOneAndFollowsWeights) {
  const std::vector<float> w = {3, 0, 1, 0.5f, 0, 2.5f, 1e-3f};
  DiscreteDistribution d(w);
  ASSERT_EQ(d.size(), w.size());
  EXPECT_FALSE(d.empty());
  EXPECT_NEAR(d.total(), 7.001, 1e-6);
  double sum = 0;
  for (size_t i = 0; i < w.size(); ++i) {
    sum += d.pmf(i);
    EXPECT_NEAR(d.pmf(i), w[i] / 7.001, 1e-7);
  }
  EXPECT_NEAR(sum, 1.0, 1e-6);
}

TEST(DiscreteDistribution, NegativeAndZeroWeights) {
  DiscreteDistribution none(std::vector<float>{0, 0, 0});
  EXPECT_TRUE(none.empty());
  DiscreteDistribution negative(std::vector<float>{-1, 2});
  EXPECT_EQ(negative.pmf(0), 0);  // negative weights count as zero
  EXPECT_EQ(negative.pmf(1), 1);
  DiscreteDistribution empty;
  EXPECT_TRUE(empty.empty());
}

// The index histogram against n * pmf exactly: no integration needed for a discrete sampler.
TEST(DiscreteDistribution, SampledIndicesFollowPmf) {
  std::vector<float> w(50);
  Pcg32 rng(3);
  for (auto& x : w) x = rng.next_float() < 0.2f ? 0.0f : rng.next_float() * rng.next_float();
  DiscreteDistribution d(w);
  const size_t n = 500000;
  std::vector<double> observed(w.size(), 0.0), expected(w.size(), 0.0);
  for (size_t s = 0; s < n; ++s) observed[d.sample(rng.next_double())] += 1;
  for (size_t i = 0; i < w.size(); ++i) expected[i] = double(n) * d.pmf(i);
  ChiSquareResult r = chi_square(observed, expected);  // a chosen zero-weight index fails outright
  EXPECT_GE(r.p_value, chi2_alpha()) << describe(r);
}

// The guide table must not change the inverse-CDF map: over an increasing grid of u the index
// never decreases and each index takes a share of the grid equal to its pmf (within one cell),
// even where thousands of tiny weights share one cutpoint interval with a huge one.
TEST(DiscreteDistribution, GuidedSearchIsTheInverseCdf) {
  std::vector<float> w(12000, 0.0f);
  Pcg32 rng(11);
  for (size_t i = 0; i < w.size(); ++i) w[i] = i % 5 == 0 ? 0.0f : 1e-4f * rng.next_float();
  w[7000] = 50.0f;  // half of the mass in one entry
  w[11999] = 1e-6f;
  DiscreteDistribution d(w);
  const int n = 4000000;
  std::vector<double> count(w.size(), 0.0);
  size_t prev = 0;
  for (int k = 0; k < n; ++k) {
    const size_t i = d.sample((k + 0.5) / n);
    ASSERT_GE(i, prev) << "u " << (k + 0.5) / n;
    prev = i;
    count[i] += 1;
  }
  for (size_t i = 0; i < w.size(); ++i) {
    if (w[i] == 0) {
      ASSERT_EQ(count[i], 0) << i;
      continue;
    }
    ASSERT_NEAR(count[i], d.pmf(i) * n, 1.0 + 1e-3 * d.pmf(i) * n) << i;
  }
}

TEST(DiscreteDistribution, ZeroWeightsAreNeverChosen) {
  // Zeros first, last, in runs; u on every cdf boundary and at the ends of [0, 1).
  const std::vector<float> w = {0, 0, 1, 0, 0, 2, 0, 1, 0, 0};
  DiscreteDistribution d(w);
  std::vector<double> us = {0.0,
                            0.25,
                            0.75,
                            0.5,
                            std::nextafter(1.0, 0.0),
                            std::nextafter(0.25, 0.0),
                            std::nextafter(0.75, 1.0)};
  for (int k = 0; k < 100000; ++k) us.push_back(double(k) / 100000);
  for (double u : us) {
    size_t i = d.sample(u);
    ASSERT_LT(i, w.size());
    ASSERT_GT(w[i], 0) << "u = " << u << " chose index " << i;
  }
}

TEST(DiscreteDistribution, RemappedUIsUniformInUnitInterval) {
  const std::vector<float> w = {1, 0, 3, 0.001f, 2};
  DiscreteDistribution d(w);
  // Every u in a fine grid (including 0 and the largest float below 1) remaps into [0, 1).
  for (int k = 0; k <= 1 << 16; ++k) {
    double u = std::min(std::nextafter(1.0, 0.0), double(k) / (1 << 16)), r = -1;
    d.sample(u, &r);
    ASSERT_GE(r, 0.0) << "u = " << u;
    ASSERT_LT(r, 1.0) << "u = " << u;
  }
  // Given the index, the remapped value is uniform: a histogram of it for index 2.
  const int bins = 20;
  std::vector<double> observed(bins, 0.0);
  Pcg32 rng(11);
  size_t hits = 0;
  for (int s = 0; s < 400000; ++s) {
    double r;
    if (d.sample(rng.next_double(), &r) != 2) continue;
    observed[std::min(bins - 1, int(r * bins))] += 1;
    ++hits;
  }
  std::vector<double> expected(bins, double(hits) / bins);
  ChiSquareResult chi2 = chi_square(observed, expected);
  EXPECT_GE(chi2.p_value, chi2_alpha()) << describe(chi2);
}

TEST(SampleStream, SameKeySameSequence) {
  SampleStream a(42, 1234, 7), b(42, 1234, 7);
  for (int i = 0; i < 100; ++i) ASSERT_EQ(a.next(), b.next());
  EXPECT_EQ(a.dimension(), 100u);
}

TEST(SampleStream, DifferentKeysDiffer) {
  auto first = [](uint64_t seed, uint64_t pixel, uint64_t index) {
    SampleStream s(seed, pixel, index);
    std::vector<float> v(8);
    for (auto& x : v) x = s.next();
    return v;
  };
  const auto base = first(1, 10, 3);
  EXPECT_NE(base, first(2, 10, 3));
  EXPECT_NE(base, first(1, 11, 3));
  EXPECT_NE(base, first(1, 10, 4));
  // No two streams among many keys start alike.
  std::set<std::vector<float>> seen;
  for (uint64_t p = 0; p < 64; ++p)
    for (uint64_t i = 0; i < 64; ++i) seen.insert(first(9, p, i));
  EXPECT_EQ(seen.size(), 64u * 64u);
}

TEST(SampleStream, ValuesAreUniformAcrossPixelsAndDimensions) {
  const int bins = 32;
  std::vector<double> observed(bins, 0.0), pairs(bins * bins, 0.0);
  size_t n = 0, n_pairs = 0;
  for (uint64_t pixel = 0; pixel < 2000; ++pixel)
    for (uint64_t index = 0; index < 8; ++index) {
      SampleStream s(5, pixel, index);
      for (int d = 0; d < 8; ++d) {
        Vec2 u = s.next2();
        ASSERT_GE(u.x, 0.0f);
        ASSERT_LT(u.x, 1.0f);
        observed[size_t(u.x * bins)] += 1;
        observed[size_t(u.y * bins)] += 1;
        pairs[size_t(u.x * bins) * bins + size_t(u.y * bins)] += 1;  // successive dimensions
        n += 2;
        ++n_pairs;
      }
    }
  ChiSquareResult r1 = chi_square(observed, std::vector<double>(bins, double(n) / bins));
  EXPECT_GE(r1.p_value, chi2_alpha()) << describe(r1);
  ChiSquareResult r2 =
      chi_square(pairs, std::vector<double>(bins * bins, double(n_pairs) / (bins * bins)));
  EXPECT_GE(r2.p_value, chi2_alpha()) << describe(r2);
}

void expect_orthonormal(const Frame& f, const Vec3& n) {
  EXPECT_NEAR(length(f.s), 1, 1e-5f);
  EXPECT_NEAR(length(f.t), 1, 1e-5f);
  EXPECT_NEAR(length(f.n), 1, 1e-5f);
  EXPECT_NEAR(dot(f.s, f.t), 0, 1e-5f);
  EXPECT_NEAR(dot(f.s, f.n), 0, 1e-5f);
  EXPECT_NEAR(dot(f.t, f.n), 0, 1e-5f);
  EXPECT_LT(length(cross(f.s, f.t) - f.n), 1e-5f) << "not right-handed";
  EXPECT_LT(length(f.n - n), 1e-6f);
  const Vec3 v(0.3f, -0.5f, 0.8f);
  EXPECT_LT(length(f.to_world(f.to_local(v)) - v), 1e-5f);
  EXPECT_NEAR(f.to_local(n).z, 1, 1e-5f);
}

TEST(Frame, OrthonormalForAnyNormal) {
  std::vector<Vec3> normals = {{0, 0, 1},
                               {0, 0, -1},
                               {1, 0, 0},
                               {0, 1, 0},
                               {0, -1, 0},
                               normalize(Vec3(1e-4f, 0, -1)),
                               normalize(Vec3(0, 1e-7f, -1)),
                               normalize(Vec3(1, 1, 1))};
  Pcg32 rng(21);
  for (int i = 0; i < 2000; ++i)
    normals.push_back(sample_uniform_sphere({rng.next_float(), rng.next_float()}));
  for (const Vec3& n : normals) {
    SCOPED_TRACE(testing::Message() << "n = (" << n.x << ", " << n.y << ", " << n.z << ")");
    expect_orthonormal(Frame(n), n);
  }
}

TEST(Frame, TangentFollowsGivenDirection) {
  const Vec3 n = normalize(Vec3(0.2f, 0.9f, 0.1f));
  Frame f(n, Vec3(1, 0, 0));
  expect_orthonormal(f, n);
  EXPECT_GT(f.s.x, 0.9f);
  // A tangent parallel to the normal falls back to the default frame.
  Frame g(n, n * 3.0f);
  expect_orthonormal(g, n);
}

TEST(Warps, StayInTheirDomains) {
  Pcg32 rng(8);
  for (int i = 0; i < 100000; ++i) {
    Vec2 u{rng.next_float(), rng.next_float()};
    Vec2 d = sample_uniform_disk_concentric(u);
    ASSERT_LE(d.x * d.x + d.y * d.y, 1 + 1e-6f);
    Vec3 h = sample_cosine_hemisphere(u);
    ASSERT_GE(h.z, 0);
    ASSERT_NEAR(length(h), 1, 1e-5f);
    ASSERT_NEAR(length(sample_uniform_sphere(u)), 1, 1e-5f);
  }
}

TEST(Warps, PowerHeuristic) {
  EXPECT_FLOAT_EQ(power_heuristic(1, 1), 0.5f);
  EXPECT_FLOAT_EQ(power_heuristic(3, 1), 0.9f);
  EXPECT_FLOAT_EQ(power_heuristic(2, 0), 1.0f);
  EXPECT_FLOAT_EQ(power_heuristic(0, 0), 0.0f);
  EXPECT_FLOAT_EQ(power_heuristic(kInf, 5), 1.0f);  // a delta strategy takes everything
  EXPECT_FLOAT_EQ(power_heuristic(0.3f, 0.7f) + power_heuristic(0.7f, 0.3f), 1.0f);
}

}  // namespace
