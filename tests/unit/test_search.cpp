// core/search.h: the one binary search of the kernels (cut ranges, CDFs, power prefixes, pool
// keys) against std::lower_bound / std::upper_bound, with the edges a cut meets: an empty range,
// the first and the last element, a sub-range, runs of equal values.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "rll/core/rng.h"
#include "rll/core/search.h"

using namespace rll;

TEST(Search, EdgesOfACutsEnds) {
  const std::vector<uint32_t> ends = {3, 5, 5, 9, 12};  // clusters [0,3) [3,5) [5,5) [5,9) [9,12)
  const uint32_t* e = ends.data();
  const uint32_t K = uint32_t(ends.size());
  // The cluster of a light: the first end above it.
  EXPECT_EQ(upper_bound_index(e, 0u, K, 0u), 0u);  // the first light: the first cluster
  EXPECT_EQ(upper_bound_index(e, 0u, K, 2u), 0u);
  EXPECT_EQ(upper_bound_index(e, 0u, K, 3u), 1u);   // an end belongs to the next cluster
  EXPECT_EQ(upper_bound_index(e, 0u, K, 5u), 3u);   // past the run of equal ends
  EXPECT_EQ(upper_bound_index(e, 0u, K, 11u), 4u);  // the last light: the last cluster
  EXPECT_EQ(upper_bound_index(e, 0u, K, 12u), K);   // past every end
  EXPECT_EQ(lower_bound_index(e, 0u, K, 5u), 1u);   // the first of the run
  EXPECT_EQ(lower_bound_index(e, 0u, K, 0u), 0u);
  EXPECT_EQ(lower_bound_index(e, 0u, K, 13u), K);
  // Empty ranges give their start, wherever it is.
  for (uint32_t at = 0; at <= K; ++at) {
    EXPECT_EQ(upper_bound_index(e, at, at, 7u), at);
    EXPECT_EQ(lower_bound_index(e, at, at, 7u), at);
  }
  // A sub-range: results stay inside it.
  EXPECT_EQ(lower_bound_index(e, 2u, 4u, 0u), 2u);
  EXPECT_EQ(lower_bound_index(e, 2u, 4u, 100u), 4u);
  EXPECT_EQ(upper_bound_index(e, 1u, 3u, 5u), 3u);
  // One element.
  EXPECT_EQ(upper_bound_index(e, 4u, 5u, 11u), 4u);
  EXPECT_EQ(upper_bound_index(e, 4u, 5u, 12u), 5u);
  // first_past with its own test.
  EXPECT_EQ(first_past(e, 0u, K, [](uint32_t x) { return x >= 9; }), 3u);
  EXPECT_EQ(first_past(e, 0u, K, [](uint32_t x) { return x > 100; }), K);
  EXPECT_EQ(first_past(e, 0u, K, [](uint32_t) { return true; }), 0u);
}

// A float CDF searched with a double u, as a cell's table is: each entry compared as a double.
TEST(Search, FloatCdfWithDoubleKey) {
  const std::vector<float> cdf = {0.25f, 0.25f, 0.5f, 1.0f};
  const double just_below = double(0.5f) - 0x1p-40;  // below 0.5f, which a float cannot say
  EXPECT_EQ(upper_bound_index(cdf.data(), size_t(0), cdf.size(), just_below), 2u);
  EXPECT_EQ(upper_bound_index(cdf.data(), size_t(0), cdf.size(), 0.5), 3u);
  EXPECT_EQ(upper_bound_index(cdf.data(), size_t(0), cdf.size(), 0.0), 0u);
}

TEST(Search, AgreesWithTheStandardLibrary) {
  Pcg32 rng(7, 11);
  for (int trial = 0; trial < 300; ++trial) {
    const size_t n = rng.next_u32() % 20;
    std::vector<uint64_t> a(n);
    for (auto& x : a) x = rng.next_u32() % 12;  // many equal values
    std::sort(a.begin(), a.end());
    const size_t lo = n ? rng.next_u32() % (n + 1) : 0;
    const size_t hi = lo + (n - lo ? rng.next_u32() % (n - lo + 1) : 0);
    for (uint64_t x = 0; x < 14; ++x) {
      EXPECT_EQ(lower_bound_index(a.data(), lo, hi, x),
                size_t(std::lower_bound(a.begin() + lo, a.begin() + hi, x) - a.begin()));
      EXPECT_EQ(upper_bound_index(a.data(), lo, hi, x),
                size_t(std::upper_bound(a.begin() + lo, a.begin() + hi, x) - a.begin()));
    }
  }
}
