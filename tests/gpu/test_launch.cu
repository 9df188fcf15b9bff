// The CUDA launch against the CPU loop: the same RLL_HD bodies run through cuda::parallel_for and
// through host_parallel_for give identical fixed-point sums and floats within rounding;
// DeviceArray round trips; a failing kernel surfaces as rll::Error.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "rll/core/device.h"
#include "rll/core/error.h"
#include "rll/core/math.h"
#include "rll/cuda/launch.cuh"

// Extended lambdas may not sit in gtest's private TestBody(), so the kernels are free functions.
namespace rll::gpu_test {

// Reals that are exact in 24-bit fixed point (k / 1024, k of both signs), with their exact sum.
std::vector<double> exact_values(size_t n, int64_t* exact_sum_1024) {
  std::vector<double> v(n);
  uint64_t state = 12345;
  *exact_sum_1024 = 0;
  for (size_t i = 0; i < n; ++i) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    const int64_t k = int64_t(state >> 40) - (int64_t(1) << 23);
    v[i] = double(k) / 1024.0;
    *exact_sum_1024 += k;
  }
  return v;
}

uint64_t gpu_fixed_sum(const std::vector<double>& values) {
  rll::cuda::DeviceArray<double> in(values.size());
  in.upload(values);
  rll::cuda::DeviceArray<uint64_t> sum(1);
  sum.upload(std::vector<uint64_t>{0});
  const View<const double> x = in.view();
  uint64_t* total = sum.view().data;
  rll::cuda::parallel_for(values.size(),
                          [=] RLL_HD(size_t i) { atomic_add(total, to_fixed_point(x[i])); });
  return sum.download()[0];
}

uint64_t cpu_fixed_sum(const std::vector<double>& values) {
  uint64_t total = 0;
  const View<const double> x = view_of(values);
  uint64_t* t = &total;
  host_parallel_for(values.size(), [=] RLL_HD(size_t i) { atomic_add(t, to_fixed_point(x[i])); });
  return total;
}

// A float function of the kind kernels compute (vector algebra, sqrt, exp, sin).
RLL_HD inline float shade(size_t i) {
  const float t = float(i) * 1e-3f;
  const Vec3 d = normalize(Vec3(std::sin(t), std::cos(3 * t), 1.0f + t));
  return dot(d, Vec3(0.3f, 0.5f, 0.8f)) * std::exp(-0.1f * t) + safe_sqrt(t);
}

std::vector<float> gpu_shade(size_t n) {
  rll::cuda::DeviceArray<float> out(n);
  const View<float> o = out.view();
  rll::cuda::parallel_for(n, [=] RLL_HD(size_t i) { o[i] = shade(i); });
  return out.download();
}

std::vector<float> cpu_shade(size_t n) {
  std::vector<float> out(n);
  const View<float> o = view_of(out);
  host_parallel_for(n, [=] RLL_HD(size_t i) { o[i] = shade(i); });
  return out;
}

std::vector<uint32_t> gpu_visits(size_t n) {
  rll::cuda::DeviceArray<uint32_t> count(n);
  count.upload(std::vector<uint32_t>(n, 0));
  const View<uint32_t> c = count.view();
  rll::cuda::parallel_for(n, [=] RLL_HD(size_t i) { atomic_add(&c[i], 1u); });
  return count.download();
}

RLL_HD inline uint32_t scramble(size_t i) {
  uint32_t h = uint32_t(i) * 2654435761u;
  h ^= h >> 16;
  return h * 2246822519u;
}

uint32_t gpu_max(size_t n) {
  rll::cuda::DeviceArray<uint32_t> m(1);
  m.upload(std::vector<uint32_t>{0});
  uint32_t* p = m.view().data;
  rll::cuda::parallel_for(n, [=] RLL_HD(size_t i) { atomic_max(p, scramble(i)); });
  return m.download()[0];
}

// Index n - 1 stores 1 into each of `slots` with atomic_cas only where it still holds 0; all
// other indices try to store 2 where it holds 5, which never matches.
std::vector<uint64_t> gpu_cas(size_t n) {
  rll::cuda::DeviceArray<uint64_t> slots(1);
  slots.upload(std::vector<uint64_t>{0});
  uint64_t* p = slots.view().data;
  rll::cuda::parallel_for(n, [=] RLL_HD(size_t i) {
    if (i + 1 == n)
      atomic_cas(p, uint64_t(0), uint64_t(1));
    else
      atomic_cas(p, uint64_t(5), uint64_t(2));
  });
  return slots.download();
}

// A kernel that traps at one index: the error is sticky (the CUDA context is lost for the rest of
// the process), so the test runs it in a child process (KernelErrorChild below).
void trapping_kernel() {
  rll::cuda::DeviceArray<int> out(1000);
  const View<int> o = out.view();
  rll::cuda::parallel_for(1000, [=] RLL_HD(size_t i) {
#if RLL_DEVICE_CODE
    if (i == 500) __trap();
#endif
    o[i] = int(i);
  });
  out.download();
}

void spin_kernel(size_t n, uint64_t* sink) {
  rll::cuda::parallel_for(n, [=] RLL_HD(size_t i) {
    uint64_t h = i;
    for (int k = 0; k < 4096; ++k) h = h * 6364136223846793005ull + 1442695040888963407ull;
    if (h == 0) atomic_add(sink, uint64_t(1));  // keeps the loop from being optimised away
  });
}

}  // namespace rll::gpu_test

using namespace rll;
using namespace rll::gpu_test;

TEST(CudaLaunch, FixedPointSumsEqualTheCpuAndTheExactSum) {
  for (size_t n : {1u, 255u, 256u, 257u, 100000u, 1000003u}) {
    int64_t exact_1024 = 0;
    const std::vector<double> values = exact_values(n, &exact_1024);
    const uint64_t gpu = gpu_fixed_sum(values);
    EXPECT_EQ(gpu, cpu_fixed_sum(values)) << n;
    EXPECT_EQ(from_fixed_point(gpu), double(exact_1024) / 1024.0) << n;
    EXPECT_EQ(gpu_fixed_sum(values), gpu) << "a second GPU run differs, n = " << n;
  }
}

TEST(CudaLaunch, FloatBodyMatchesTheCpuWithinRounding) {
  const size_t n = 200000;
  const std::vector<float> gpu = gpu_shade(n), cpu = cpu_shade(n);
  ASSERT_EQ(gpu.size(), n);
  size_t differing = 0;
  for (size_t i = 0; i < n; ++i) {
    EXPECT_NEAR(gpu[i], cpu[i], 2e-6f * (1 + std::abs(cpu[i]))) << i;
    differing += gpu[i] != cpu[i];
  }
  // Not the same numbers by accident: the body varies with i.
  EXPECT_NE(cpu[1], cpu[n - 1]);
  RecordProperty("differing_floats", int(differing));
}

TEST(CudaLaunch, VisitsEveryIndexOnce) {
  for (size_t n : {0u, 1u, 255u, 256u, 257u, 65537u, 3000001u}) {
    const std::vector<uint32_t> c = gpu_visits(n);
    ASSERT_EQ(c.size(), n);
    size_t wrong = 0;
    for (uint32_t v : c) wrong += v != 1;
    EXPECT_EQ(wrong, 0u) << n;
  }
}

TEST(CudaLaunch, AtomicMaxAndCas) {
  const size_t n = 500000;
  uint32_t expected = 0;
  for (size_t i = 0; i < n; ++i) expected = std::max(expected, scramble(i));
  EXPECT_EQ(gpu_max(n), expected);
  EXPECT_EQ(gpu_cas(n), std::vector<uint64_t>{1});
}

TEST(CudaDeviceArray, RoundTrips) {
  std::vector<Vec3> v(1001);
  for (size_t i = 0; i < v.size(); ++i) v[i] = Vec3(float(i), -float(i), 0.5f * float(i));
  rll::cuda::DeviceArray<Vec3> a(v.size());
  EXPECT_EQ(a.size(), v.size());
  EXPECT_EQ(a.bytes(), v.size() * sizeof(Vec3));
  a.upload(v);
  EXPECT_EQ(a.download(), v);
  std::vector<Vec3> back(v.size());
  a.download(back.data());
  EXPECT_EQ(back, v);
  a.upload(v.data() + 0, v.size());

  rll::cuda::DeviceArray<Vec3> b = std::move(a);
  EXPECT_EQ(a.size(), 0u);
  EXPECT_EQ(a.view().data, nullptr);
  EXPECT_EQ(b.download(), v);
  const rll::cuda::DeviceArray<Vec3>& cb = b;
  const View<const Vec3> cv = cb.view();
  EXPECT_EQ(cv.size, v.size());

  rll::cuda::DeviceArray<int> empty;
  EXPECT_TRUE(empty.download().empty());
  EXPECT_TRUE(empty.view().empty());
}

TEST(CudaDeviceArray, SizeMismatchIsAnError) {
  rll::cuda::DeviceArray<int> a(10);
  try {
    a.upload(std::vector<int>(11));
    FAIL() << "expected an rll::Error";
  } catch (const Error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("upload"), std::string::npos) << m;
    EXPECT_NE(m.find("10"), std::string::npos) << m;
    EXPECT_NE(m.find("11"), std::string::npos) << m;
  }
}

TEST(CudaDeviceArray, OutOfMemoryIsAnError) {
  try {
    rll::cuda::DeviceArray<double> huge(size_t(1) << 50);  // 8 PiB
    FAIL() << "expected an rll::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("CUDA: cudaMalloc"), std::string::npos) << e.what();
  }
}

TEST(CudaEventTimer, MeasuresWithinTheWallTime) {
  rll::cuda::DeviceArray<uint64_t> sink(1);
  sink.upload(std::vector<uint64_t>{0});
  spin_kernel(1 << 16, sink.view().data);  // warm up
  sink.download();
  rll::cuda::EventTimer timer;
  const auto t0 = std::chrono::steady_clock::now();
  timer.start();
  spin_kernel(1 << 22, sink.view().data);
  const float ms = timer.stop_ms();
  const double wall_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_GT(ms, 0.0f);
  EXPECT_LE(ms, wall_ms * 1.01 + 0.05);
}

// Run by KernelError.SurfacesAsRllError in a child process; disabled in the normal run.
TEST(KernelErrorChild, DISABLED_Trap) {
  try {
    trapping_kernel();
  } catch (const Error& e) {
    std::printf("caught rll::Error: %s\n", e.what());
    std::fflush(stdout);
    std::_Exit(42);
  }
  std::_Exit(1);
}

TEST(KernelError, SurfacesAsRllError) {
  char self[4096] = {};
  const ssize_t len = readlink("/proc/self/exe", self, sizeof(self) - 1);
  ASSERT_GT(len, 0);
  const std::string command = std::string("'") + self +
                              "' --gtest_also_run_disabled_tests "
                              "--gtest_filter=KernelErrorChild.DISABLED_Trap 2>&1";
  FILE* child = popen(command.c_str(), "r");
  ASSERT_NE(child, nullptr);
  std::string output;
  char buffer[512];
  while (size_t got = std::fread(buffer, 1, sizeof(buffer), child)) output.append(buffer, got);
  const int status = pclose(child);
  ASSERT_TRUE(WIFEXITED(status)) << output;
  EXPECT_EQ(WEXITSTATUS(status), 42) << "the trap did not surface as rll::Error:\n" << output;
  EXPECT_NE(output.find("caught rll::Error: CUDA: download: "), std::string::npos) << output;
}
