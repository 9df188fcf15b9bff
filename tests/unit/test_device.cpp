// core/device.h on the CPU: the loop that runs kernel bodies, the atomics, fixed-point sums that
// do not depend on the order of threads, and views.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <random>
#include <vector>

#include "rll/core/device.h"
#include "rll/core/parallel.h"

using namespace rll;

namespace {

// Reals exact in 24-bit fixed point (k / 1024, k of both signs), and their exact sum times 1024.
std::vector<double> exact_values(size_t n, uint32_t seed, int64_t* sum_1024) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int64_t> k_of(-(int64_t(1) << 30), int64_t(1) << 30);
  std::vector<double> v(n);
  *sum_1024 = 0;
  for (double& x : v) {
    const int64_t k = k_of(rng);
    x = double(k) / 1024.0;
    *sum_1024 += k;
  }
  return v;
}

uint64_t fixed_sum(const std::vector<double>& values) {
  uint64_t total = 0;
  uint64_t* t = &total;
  const View<const double> x = view_of(values);
  host_parallel_for(values.size(), [=](size_t i) { atomic_add(t, to_fixed_point(x[i])); });
  return total;
}

}  // namespace

TEST(Device, HostParallelForVisitsEveryIndexOnce) {
  for (size_t n : {0u, 1u, 2u, 255u, 256u, 257u, 511u, 1000u, 65537u, 1000003u}) {
    std::vector<uint32_t> count(n, 0);
    const View<uint32_t> c = view_of(count);
    host_parallel_for(n, [=](size_t i) { atomic_add(&c[i], 1u); });
    EXPECT_EQ(std::count(count.begin(), count.end(), 1u), std::ptrdiff_t(n)) << n;
  }
}

TEST(Device, FixedPointSumIsExactInAnyOrderAndThreadCount) {
  int64_t exact_1024 = 0;
  std::vector<double> values = exact_values(200000, 7, &exact_1024);
  const double exact = double(exact_1024) / 1024.0;
  std::vector<double> shuffled = values;
  std::shuffle(shuffled.begin(), shuffled.end(), std::mt19937(3));
  const uint64_t reference = fixed_sum(values);
  EXPECT_EQ(from_fixed_point(reference), exact);
  for (int threads : {1, 2, 3, 8}) {
    ThreadLimit limit(threads);
    EXPECT_EQ(fixed_sum(values), reference) << threads << " threads";
    EXPECT_EQ(fixed_sum(shuffled), reference) << threads << " threads, shuffled";
  }
  std::reverse(values.begin(), values.end());
  EXPECT_EQ(fixed_sum(values), reference);
}

TEST(Device, FixedPointRoundsToNearestBothSigns) {
  const double ulp = 1.0 / double(uint64_t(1) << kFixedPointBits);
  EXPECT_EQ(from_fixed_point(to_fixed_point(0.4 * ulp)), 0.0);
  EXPECT_EQ(from_fixed_point(to_fixed_point(0.6 * ulp)), ulp);
  EXPECT_EQ(from_fixed_point(to_fixed_point(-0.6 * ulp)), -ulp);
  EXPECT_EQ(from_fixed_point(to_fixed_point(-1234.5)), -1234.5);
  EXPECT_EQ(from_fixed_point(to_fixed_point(3.0) + to_fixed_point(-5.25)), -2.25);
}

TEST(Device, AtomicCasStoresOnlyOnMatch) {
  uint64_t a = 5;
  EXPECT_EQ(atomic_cas(&a, uint64_t(4), uint64_t(9)), 5u);
  EXPECT_EQ(a, 5u);
  EXPECT_EQ(atomic_cas(&a, uint64_t(5), uint64_t(9)), 5u);
  EXPECT_EQ(a, 9u);
  uint32_t b = 7;
  EXPECT_EQ(atomic_cas(&b, 6u, 1u), 7u);
  EXPECT_EQ(b, 7u);
  EXPECT_EQ(atomic_cas(&b, 7u, 1u), 7u);
  EXPECT_EQ(b, 1u);
  EXPECT_EQ(atomic_load(&a), 9u);
  EXPECT_EQ(atomic_load(&b), 1u);
}

TEST(Device, AtomicCasClaimsEachSlotOnce) {
  // Every index tries to claim slot i % 64; exactly one per slot succeeds.
  const size_t n = 100000;
  std::vector<uint32_t> owner(64, 0), wins(n, 0);
  const View<uint32_t> o = view_of(owner), w = view_of(wins);
  host_parallel_for(n, [=](size_t i) {
    if (atomic_cas(&o[i % 64], 0u, uint32_t(i + 1)) == 0) w[i] = 1;
  });
  EXPECT_EQ(std::accumulate(wins.begin(), wins.end(), size_t(0)), 64u);
  for (size_t s = 0; s < 64; ++s) {
    ASSERT_NE(owner[s], 0u);
    EXPECT_EQ((owner[s] - 1) % 64, s);
    EXPECT_EQ(wins[owner[s] - 1], 1u);
  }
}

TEST(Device, AtomicMaxKeepsTheLargest) {
  uint32_t m = 10;
  EXPECT_EQ(atomic_max(&m, 3u), 10u);
  EXPECT_EQ(m, 10u);
  EXPECT_EQ(atomic_max(&m, 12u), 10u);
  EXPECT_EQ(m, 12u);

  const size_t n = 300000;
  std::vector<uint32_t> v(n);
  std::mt19937 rng(11);
  for (uint32_t& x : v) x = rng();
  uint32_t result = 0;
  uint32_t* r = &result;
  const View<const uint32_t> x = view_of(v);
  host_parallel_for(n, [=](size_t i) { atomic_max(r, x[i]); });
  EXPECT_EQ(result, *std::max_element(v.begin(), v.end()));
}

TEST(Device, Views) {
  std::vector<int> v{1, 2, 3};
  const View<int> w = view_of(v);
  EXPECT_EQ(w.data, v.data());
  EXPECT_EQ(w.size, 3u);
  EXPECT_FALSE(w.empty());
  w[1] = 20;
  EXPECT_EQ(v[1], 20);
  const View<const int> c = w;  // the conversion to const elements
  EXPECT_EQ(c.data, v.data());
  EXPECT_EQ(c.size, 3u);
  EXPECT_EQ(std::accumulate(c.begin(), c.end(), 0), 24);
  const std::vector<int>& cv = v;
  const View<const int> cc = view_of(cv);
  EXPECT_EQ(cc.end() - cc.begin(), 3);
  EXPECT_TRUE(View<int>{}.empty());
  static_assert(std::is_trivially_copyable_v<View<int>>);
  static_assert(!std::is_convertible_v<View<const int>, View<int>>);
}
