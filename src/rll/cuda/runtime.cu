// The CUDA backend's host side: errors as rll::Error, the device list, the GPU check, the timer.
#include <fmt/format.h>

#include <atomic>
#include <map>
#include <mutex>

#include "rll/core/error.h"
#include "rll/cuda/cuda.h"
#include "rll/cuda/launch.cuh"

namespace rll::cuda {

namespace {
// The compute capability that rll's kernels are built for (sm_90 and its PTX): older GPUs cannot
// run them.
constexpr int kMinSmMajor = 9;

std::string version_text(int v) {
  return fmt::format("{}.{}", v / 1000, v % 1000 / 10);
}
}  // namespace

void check(cudaError_t e, const char* what) {
  if (e == cudaSuccess) return;
  // A failed call also sets the runtime's last error, which the next launch's check would report
  // as its own (a failed cudaMalloc made the following kernel launch fail with "out of memory"):
  // the error is reported here, once. Sticky errors (a trapped kernel) stay whatever is done.
  cudaGetLastError();
  fail("CUDA: {}: {}", what, cudaGetErrorString(e));
}

namespace detail {
void size_mismatch(const char* what, size_t expected, size_t got) {
  fail("CUDA: {}: the device array holds {} elements, the host side {}", what, expected, got);
}
}  // namespace detail

namespace {
struct Counters {
  std::atomic<uint64_t> syncs{0}, launches{0}, allocations{0}, to_host{0}, to_device{0};
};
Counters& counters() {
  static Counters c;
  return c;
}
}  // namespace

DeviceWork device_work() {
  const Counters& c = counters();
  return {c.syncs.load(), c.launches.load(), c.allocations.load(), c.to_host.load(),
          c.to_device.load()};
}

namespace count {
void sync() {
  counters().syncs.fetch_add(1, std::memory_order_relaxed);
}
void launch(uint64_t n) {
  counters().launches.fetch_add(n, std::memory_order_relaxed);
}
void allocation() {
  counters().allocations.fetch_add(1, std::memory_order_relaxed);
}
void to_host(uint64_t bytes) {
  counters().to_host.fetch_add(bytes, std::memory_order_relaxed);
}
void to_device(uint64_t bytes) {
  counters().to_device.fetch_add(bytes, std::memory_order_relaxed);
}
}  // namespace count

namespace detail {
namespace {
// Released blocks by size; leaked at exit (CUDA may be torn down before static destructors).
struct MemoryCache {
  std::mutex mutex;
  std::multimap<size_t, void*> free;
};
MemoryCache& cache() {
  static MemoryCache* c = new MemoryCache;
  return *c;
}
}  // namespace

void* device_allocate(size_t bytes) {
  MemoryCache& c = cache();
  {
    std::lock_guard lock(c.mutex);
    const auto it = c.free.lower_bound(bytes);
    if (it != c.free.end() && it->first <= 2 * bytes) {
      void* p = it->second;
      c.free.erase(it);
      return p;
    }
  }
  void* p = nullptr;
  if (cudaMalloc(&p, bytes) != cudaSuccess) {
    cudaGetLastError();
    // The cache's blocks back to CUDA, then once more.
    std::lock_guard lock(c.mutex);
    for (const auto& [size, block] : c.free) cudaFree(block);
    c.free.clear();
    check(cudaMalloc(&p, bytes), "cudaMalloc");
  }
  count::allocation();
  return p;
}

void device_release(void* p, size_t bytes) noexcept {
  MemoryCache& c = cache();
  std::lock_guard lock(c.mutex);
  // The block's size as allocated is at least `bytes` (a reused block may be up to twice as
  // large); keyed by `bytes`, it is reused only for what fits in `bytes`.
  c.free.emplace(bytes, p);
}
}  // namespace detail

EventPool::~EventPool() {
  for (cudaEvent_t e : m_events) cudaEventDestroy(e);
}

void EventPool::start(size_t key, cudaStream_t s) {
  if (2 * m_used == m_events.size()) {
    for (int k = 0; k < 2; ++k) {
      cudaEvent_t e = nullptr;
      check(cudaEventCreate(&e), "cudaEventCreate");
      m_events.push_back(e);
    }
    m_keys.push_back(0);
  }
  m_keys[m_used] = key;
  check(cudaEventRecord(m_events[2 * m_used], s), "cudaEventRecord");
}

void EventPool::stop(cudaStream_t s) {
  check(cudaEventRecord(m_events[2 * m_used + 1], s), "cudaEventRecord");
  ++m_used;
}

float EventPool::elapsed_ms(size_t i) const {
  float ms = 0;
  check(cudaEventElapsedTime(&ms, m_events[2 * i], m_events[2 * i + 1]), "cudaEventElapsedTime");
  return ms;
}

EventTimer::EventTimer() {
  check(cudaEventCreate(&m_start), "cudaEventCreate");
  check(cudaEventCreate(&m_stop), "cudaEventCreate");
}

EventTimer::~EventTimer() {
  cudaEventDestroy(m_start);
  cudaEventDestroy(m_stop);
}

void EventTimer::start(cudaStream_t s) {
  check(cudaEventRecord(m_start, s), "cudaEventRecord");
}

float EventTimer::stop_ms(cudaStream_t s) {
  check(cudaEventRecord(m_stop, s), "cudaEventRecord");
  check(cudaEventSynchronize(m_stop), "cudaEventSynchronize");
  count::sync();
  float ms = 0;
  check(cudaEventElapsedTime(&ms, m_start, m_stop), "cudaEventElapsedTime");
  return ms;
}

bool cuda_built() {
  return true;
}

std::vector<GpuInfo> gpus() {
  int driver = 0, runtime = 0, count = 0;
  if (cudaDriverGetVersion(&driver) != cudaSuccess || driver == 0) return {};
  cudaRuntimeGetVersion(&runtime);
  if (cudaGetDeviceCount(&count) != cudaSuccess) {
    cudaGetLastError();  // the failure is the answer; leave no error behind for later calls
    return {};
  }
  std::vector<GpuInfo> result;
  for (int d = 0; d < count; ++d) {
    cudaDeviceProp p{};
    if (cudaGetDeviceProperties(&p, d) != cudaSuccess) continue;
    result.push_back(
        {p.name, p.major, p.minor, p.multiProcessorCount, p.totalGlobalMem, driver, runtime});
  }
  return result;
}

void require_gpu() {
  int driver = 0, runtime = 0, count = 0;
  cudaRuntimeGetVersion(&runtime);
  if (cudaDriverGetVersion(&driver) != cudaSuccess || driver == 0)
    fail(
        "no NVIDIA driver found: GPU work needs a machine with an NVIDIA GPU and its driver (CUDA "
        "{} or newer); use the CPU renderer here",
        version_text(runtime));
  if (driver < runtime)
    fail(
        "the NVIDIA driver supports CUDA {}, older than the CUDA {} runtime rll was built with: "
        "update the driver, or build rll with an older CUDA toolkit",
        version_text(driver), version_text(runtime));
  const cudaError_t e = cudaGetDeviceCount(&count);
  if (e != cudaSuccess || count == 0) {
    cudaGetLastError();
    fail(
        "no CUDA device found ({}): GPU work needs a machine with an NVIDIA GPU; use the CPU "
        "renderer here",
        e != cudaSuccess ? cudaGetErrorString(e) : "the driver lists none");
  }
  const std::vector<GpuInfo> all = gpus();
  for (const GpuInfo& g : all)
    if (g.sm_major >= kMinSmMajor) return;
  if (all.empty()) fail("CUDA: the properties of the {} device(s) could not be read", count);
  fail(
      "no CUDA device runs rll's kernels: they are built for compute capability {}.0 and newer "
      "(sm_90), and {} has {}.{}",
      kMinSmMajor, all.front().name, all.front().sm_major, all.front().sm_minor);
}

}  // namespace rll::cuda
