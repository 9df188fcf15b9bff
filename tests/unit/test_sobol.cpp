// The Sobol' generator and its Owen scrambling: the direction numbers, the (0,m,2)-nets and 1D
// strata that make the points worth using, and the scrambles' independence across seeds.
#include <gtest/gtest.h>

#include <algorithm>
#include <boost/random/sobol.hpp>
#include <cmath>
#include <set>
#include <vector>

#include "rll/core/rng.h"
#include "rll/core/sobol.h"
#include "support/sphere_chi2.h"
#include "support/statistics.h"

using namespace rll;
using namespace rll::test;

namespace {

// The chi-square tests of this file, as a family at level 1e-3.
constexpr int kChi2Tests = 4;
const double kAlpha = sidak_alpha(1e-3, kChi2Tests);

// Seeds as the renderer passes them (hashes), and a few plain ones.
const uint64_t kSeeds[] = {0, 1, 0x9e3779b97f4a7c15ull, mix64(42), mix64(7) ^ mix64(1234567)};

// The `bits` high bits of a 32-bit fixed-point value.
uint32_t top(uint32_t v, int bits) {
  return bits == 0 ? 0 : v >> (32 - bits);
}

// A plain bit reversal, written independently of the library's.
uint32_t reverse_slowly(uint32_t v) {
  uint32_t r = 0;
  for (int b = 0; b < 32; ++b) r |= ((v >> b) & 1u) << (31 - b);
  return r;
}

// How many of the m+1 shapes of elementary intervals of area 2^-m (2^-a by 2^-(m-a)) the 2^m
// points (x[i], y[i]) fail to fill with exactly one point each: 0 for a (0,m,2)-net in base 2.
int net_failures(const std::vector<uint32_t>& x, const std::vector<uint32_t>& y, int m) {
  std::vector<uint8_t> seen(size_t(1) << m);
  int failures = 0;
  for (int a = 0; a <= m; ++a) {
    std::fill(seen.begin(), seen.end(), 0);
    bool ok = true;
    for (size_t i = 0; i < x.size(); ++i) {
      const uint32_t cell = (top(x[i], a) << (m - a)) | top(y[i], m - a);
      ok &= seen[cell]++ == 0;
    }
    failures += !ok;
  }
  return failures;
}

// How many of the prefixes of length 2^m, m = 0..max_m, of `v` fail to put exactly one value in
// each interval [j/2^m, (j+1)/2^m): 0 for a (0,1)-sequence.
int strata_failures(const std::vector<uint32_t>& v, int max_m) {
  int failures = 0;
  std::vector<uint8_t> seen;
  for (int m = 0; m <= max_m; ++m) {
    seen.assign(size_t(1) << m, 0);
    bool ok = true;
    for (size_t i = 0; i < (size_t(1) << m); ++i) ok &= seen[top(v[i], m)]++ == 0;
    failures += !ok;
  }
  return failures;
}

TEST(Sobol, Dimension0IsVanDerCorput) {
  int mismatches = 0;
  for (uint32_t i = 0; i < (1u << 16); ++i) mismatches += sobol_u32(i, 0) != reverse_slowly(i);
  Pcg32 rng(1);
  for (int t = 0; t < 1000; ++t) {
    const uint32_t i = rng.next_u32();
    mismatches += sobol_u32(i, 0) != reverse_slowly(i);
  }
  EXPECT_EQ(mismatches, 0);
}

TEST(Sobol, Dimensions1And2MatchTheRecurrenceByHand) {
  // Point i XORs in v_k for every set bit k of i (natural order, not Gray code).
  // Dimension 1: polynomial 3 = x + 1 (s = 1), m_1 = 1, so m_k = 2 m_(k-1) ^ m_(k-1):
  // m = 1, 3, 5, 15 and v = 1/2, 3/4, 5/8, 15/16. Points 0..8: 0, v1, v2, v1^v2 = 1/4, v3,
  // v1^v3 = 1/8, v2^v3 = 3/8, v1^v2^v3 = 7/8, v4.
  const double dim1[] = {0, 0.5, 0.75, 0.25, 0.625, 0.125, 0.375, 0.875, 0.9375};
  // Dimension 2: polynomial 7 = x^2 + x + 1 (s = 2, a_1 = 1), m_1 = 1, m_2 = 3, so
  // m_k = 2 m_(k-1) ^ 4 m_(k-2) ^ m_(k-2): m_3 = 6^4^1 = 3, m_4 = 6^12^3 = 9, and
  // v = 1/2, 3/4, 3/8, 9/16. Points 4..7: 3/8, 7/8, 3/4^3/8 = 5/8, 1/8.
  const double dim2[] = {0, 0.5, 0.75, 0.25, 0.375, 0.875, 0.625, 0.125, 0.5625};
  int mismatches = 0;
  for (uint32_t i = 0; i < 9; ++i) {
    mismatches += sobol_u32(i, 1) * 0x1p-32 != dim1[i];
    mismatches += sobol_u32(i, 2) * 0x1p-32 != dim2[i];
  }
  EXPECT_EQ(mismatches, 0);
}

TEST(Sobol, MatchesBoostsGrayCodeEngineInEveryDimension) {
  // Boost computes its own direction numbers from the same table and walks the points in Gray
  // code order from point 1: its n-th vector is point n ^ (n >> 1).
  boost::random::sobol_engine<uint32_t, 32> boost_sobol(kSobolDimensions);
  int mismatches = 0;
  for (uint32_t n = 1; n <= 256; ++n)
    for (uint32_t d = 0; d < kSobolDimensions; ++d)
      mismatches += boost_sobol() != sobol_u32(n ^ (n >> 1), d);
  EXPECT_EQ(mismatches, 0);
}

TEST(Sobol, Dimensions01FormNetsUnscrambledAndScrambled) {
  // The first 2^m points, and the blocks [k 2^m, (k+1) 2^m), for m = 0..12.
  int failures = 0, checked = 0;
  for (int variant = -1; variant < int(std::size(kSeeds)); ++variant)
    for (uint32_t block : {0u, 1u, 3u, 77u}) {
      for (int m = 0; m <= 12; ++m) {
        const uint32_t n = 1u << m;
        std::vector<uint32_t> x(n), y(n);
        for (uint32_t i = 0; i < n; ++i) {
          const uint32_t index = block * n + i;
          x[i] = variant < 0 ? sobol_u32(index, 0) : scrambled_sobol_u32(index, 0, kSeeds[variant]);
          y[i] = variant < 0 ? sobol_u32(index, 1) : scrambled_sobol_u32(index, 1, kSeeds[variant]);
        }
        failures += net_failures(x, y, m);
        checked += m + 1;
      }
    }
  EXPECT_EQ(failures, 0) << "of " << checked << " (seed, block, m, shape) cases";
}

TEST(Sobol, PaddedBlockKeepsTheNetOfItsFirstTwoDimensions) {
  // Dimensions 1024 and 1025 reuse table dimensions 0 and 1 under one index shuffle.
  int failures = 0;
  for (uint64_t seed : kSeeds) {
    for (uint32_t first : {kSobolDimensions, 7 * kSobolDimensions}) {
      const int m = 12;
      std::vector<uint32_t> x(1u << m), y(1u << m);
      for (uint32_t i = 0; i < x.size(); ++i) {
        x[i] = scrambled_sobol_u32(i, first, seed);
        y[i] = scrambled_sobol_u32(i, first + 1, seed);
      }
      for (int k = 0; k <= m; ++k)
        failures += net_failures(std::vector<uint32_t>(x.begin(), x.begin() + (1 << k)),
                                 std::vector<uint32_t>(y.begin(), y.begin() + (1 << k)), k);
    }
  }
  EXPECT_EQ(failures, 0);
}

TEST(Sobol, EveryDimensionIsStratifiedUnscrambledScrambledAndPadded) {
  const int max_m = 10;
  std::vector<uint32_t> dims;
  for (uint32_t d = 0; d < 1100; ++d) dims.push_back(d);
  for (uint32_t d : {2047u, 2048u, 5000u, 123456u, 0x80000007u, 0xffffffffu}) dims.push_back(d);
  std::vector<uint32_t> v(1u << max_m);
  int failures = 0, checked = 0;
  for (uint32_t d : dims)
    for (int variant = -1; variant < 3; ++variant) {
      if (variant < 0 && d >= kSobolDimensions) continue;
      for (uint32_t i = 0; i < v.size(); ++i)
        v[i] = variant < 0 ? sobol_u32(i, d) : scrambled_sobol_u32(i, d, kSeeds[variant + 2]);
      failures += strata_failures(v, max_m);
      checked += max_m + 1;
    }
  EXPECT_EQ(failures, 0) << "of " << checked << " (dimension, seed, m) cases";
}

TEST(SobolOwenScramble, FlippingABitFlipsItAndNothingAbove) {
  // Output bit p (0 = most significant) flips with input bit p and ignores input bits below it:
  // so a value's top k bits decide the output's top k bits, and the map is a bijection.
  Pcg32 rng(2);
  int violations = 0;
  for (int t = 0; t < 20000; ++t) {
    const uint32_t v = rng.next_u32(), seed = rng.next_u32();
    const int p = int(rng.next_bounded(32));
    const uint32_t bit = 0x80000000u >> p;
    const uint32_t a = owen_scramble(v, seed), b = owen_scramble(v ^ bit, seed);
    violations += (a ^ b) >> (31 - p) != 1u;
  }
  EXPECT_EQ(violations, 0);
}

TEST(SobolOwenScramble, PermutesThe16BitPrefixes) {
  int duplicates = 0;
  for (uint32_t seed : {0u, 1u, 0xdeadbeefu, 0x80000000u}) {
    std::vector<uint8_t> seen(1u << 16);
    for (uint32_t h = 0; h < (1u << 16); ++h)
      duplicates += seen[owen_scramble(h << 16, seed) >> 16]++ != 0;
  }
  EXPECT_EQ(duplicates, 0);
}

TEST(SobolOwenScramble, DistinctSeedsGiveDistinctScrambles) {
  // Consecutive seeds included: the scramble hashes its seed.
  size_t collisions = 0;
  for (uint32_t v : {0u, 0x80000000u, 0x12345678u}) {
    std::set<uint32_t> outputs;
    for (uint32_t seed = 0; seed < 4096; ++seed) outputs.insert(owen_scramble(v, seed));
    collisions += 4096 - outputs.size();
  }
  EXPECT_EQ(collisions, 0u);
}

TEST(SobolOwenScramble, ValuesOneBitApartGetIndependentLowerBits) {
  // In a nested uniform scramble, two values that first differ at bit p fall in different
  // subtrees, whose bits below p are flipped independently: each output bit j > p agrees with
  // probability 1/2 over seeds. (Burley's fixed-constant hash misses this by z > 100.)
  const int n = 20000, tests = 31 * 32 / 2;
  const double z_max = 5;  // P(|z| > 5) = 5.7e-7 per pair, 3e-4 for all of them
  Pcg32 rng(3);
  double worst = 0;
  for (int p = 0; p < 31; ++p) {
    int agree[32] = {};
    const uint32_t bit = 0x80000000u >> p;
    for (int t = 0; t < n; ++t) {
      const uint32_t v = rng.next_u32(), seed = rng.next_u32();
      const uint32_t d = owen_scramble(v, seed) ^ owen_scramble(v ^ bit, seed);
      for (int j = p + 1; j < 32; ++j) agree[j] += ((d >> (31 - j)) & 1u) == 0;
    }
    for (int j = p + 1; j < 32; ++j)
      worst = std::max(worst, std::abs(agree[j] - n / 2.0) / std::sqrt(n / 4.0));
  }
  EXPECT_LT(worst, z_max) << "worst |z| of " << tests << " bit pairs";
}

// Chi-square of the 64-bin histogram of coordinate `dim` of point `index` over seeds 0..n-1.
ChiSquareResult across_seeds(uint32_t index, uint32_t dim) {
  const int bins = 64, n = 1 << 14;
  std::vector<double> observed(bins, 0.0);
  for (uint64_t seed = 0; seed < uint64_t(n); ++seed)
    observed[top(scrambled_sobol_u32(index, dim, seed), 6)] += 1;
  return chi_square(observed, std::vector<double>(bins, double(n) / bins));
}

TEST(Sobol, ScrambledValueIsUniformAcrossSeeds) {
  const uint32_t cases[kChi2Tests][2] = {{0, 0}, {5, 3}, {1000, 1030}, {77, 5000}};
  for (const auto& c : cases) {
    const ChiSquareResult r = across_seeds(c[0], c[1]);
    EXPECT_GE(r.p_value, kAlpha) << "index " << c[0] << " dim " << c[1] << ": " << describe(r);
  }
}

// Mean of x*y over `n` points of dimensions (dx, dy) for seed `seed`.
double mean_xy(uint32_t n, uint32_t dx, uint32_t dy, uint64_t seed) {
  double sum = 0;
  for (uint32_t i = 0; i < n; ++i)
    sum += sobol_to_double(scrambled_sobol_u32(i, dx, seed)) *
           sobol_to_double(scrambled_sobol_u32(i, dy, seed));
  return sum / n;
}

TEST(Sobol, SmoothIntegralVarianceIsFarBelowIndependentPoints) {
  // Owen-scrambled nets integrate smooth functions with variance o(1/n); independent points
  // have exactly Var(xy)/n = (1/9 - 1/16)/n.
  const uint32_t n = 256;
  const int seeds = 500;
  const double independent = (1.0 / 9 - 1.0 / 16) / n;
  for (auto [dx, dy] : {std::pair{0u, 1u}, std::pair{2u, 3u}, std::pair{1030u, 1031u}}) {
    double sum_sq = 0;
    for (int s = 0; s < seeds; ++s)
      sum_sq += std::pow(mean_xy(n, dx, dy, mix64(s + 1000)) - 0.25, 2);
    const double variance = sum_sq / seeds;  // the true mean is known: 1/4
    EXPECT_LT(variance * 10, independent)
        << "dims " << dx << "," << dy << ": " << variance << " vs " << independent;
  }
}

TEST(Sobol, ScrambledEstimateIsUnbiased) {
  // The mean over seeds of the 16-point estimate of the integral of x*y is 1/4.
  const int seeds = 4000;
  double sum = 0, sum_sq = 0;
  for (int s = 0; s < seeds; ++s) {
    const double e = mean_xy(16, 4, 5, mix64(s + 77));
    sum += e;
    sum_sq += e * e;
  }
  const double mean = sum / seeds, sd = std::sqrt((sum_sq / seeds - mean * mean) / seeds);
  EXPECT_LT(std::abs(mean - 0.25), 4 * sd) << "mean " << mean << " standard error " << sd;
}

// Pearson correlation of dimension `da` under seed `sa` with dimension `db` under seed `sb`,
// point by point over the first `n` points.
double correlation(uint32_t n, uint32_t da, uint64_t sa, uint32_t db, uint64_t sb) {
  double sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
  for (uint32_t i = 0; i < n; ++i) {
    const double x = sobol_to_double(scrambled_sobol_u32(i, da, sa));
    const double y = sobol_to_double(scrambled_sobol_u32(i, db, sb));
    sx += x, sy += y, sxx += x * x, syy += y * y, sxy += x * y;
  }
  const double cov = sxy / n - sx / n * sy / n;
  return cov / std::sqrt((sxx / n - sx / n * sx / n) * (syy / n - sy / n * sy / n));
}

TEST(Sobol, DifferentSeedsAreDecorrelated) {
  // Root mean square of the correlation over 4096 points, over pairs of consecutive seeds, of
  // hashed seeds and of a dimension and its padded copy: independent sequences give 1/64, these
  // 1.4/64; value scrambles without the index shuffle give 39/64.
  const uint32_t n = 4096;
  const int pairs = 32;
  double sum_sq = 0;
  for (int t = 0; t < pairs; ++t) {
    sum_sq += std::pow(correlation(n, 0, t, 0, t + 1), 2);
    sum_sq += std::pow(correlation(n, 3, mix64(t), 3, mix64(t + 1000)), 2);
    sum_sq += std::pow(correlation(n, 5 * t, mix64(t), 5 * t + kSobolDimensions, mix64(t)), 2);
  }
  EXPECT_LT(std::sqrt(sum_sq / (3 * pairs)) * 64, 2.0);
}

TEST(Sobol, ToFloatKeepsTheHighBitsAndNeverReachesOne) {
  int wrong = 0;
  wrong += u32_to_unit_float(0xffffffffu) >= 1.0f;
  wrong += sobol_to_double(0xffffffffu) >= 1.0;
  wrong += u32_to_unit_float(0x80000000u) != 0.5f;
  wrong += u32_to_unit_float(0x000000ffu) != 0.0f;  // below the 24 bits a float keeps
  wrong += sobol_to_double(0x00000001u) != 0x1p-32;
  EXPECT_EQ(wrong, 0);
}

}  // namespace

namespace {
// The byte tables the renderer reads give the generator matrix's points, for any index.
TEST(Sobol, ByteTablesMatchTheMatrixColumnByColumn) {
  rll::Pcg32 rng(17);
  int mismatches = 0;
  for (uint32_t d = 0; d < rll::kSobolDimensions; d += 7)
    for (int k = 0; k < 200; ++k) {
      const uint32_t index = rng.next_u32();
      mismatches += rll::sobol_u32(index, d) != rll::sobol_u32_reference(index, d);
    }
  EXPECT_EQ(mismatches, 0);
}
}  // namespace
