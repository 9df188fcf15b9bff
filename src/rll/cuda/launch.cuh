// The CUDA side of core/device.h (nvcc only): device memory, the launch that runs an RLL_HD kernel
// body over [0, n) with one thread per index, and a timer. The CPU runs the same bodies through
// rll::host_parallel_for.
#pragma once

#include <cuda_runtime.h>

#include <cstddef>
#include <type_traits>
#include <utility>
#include <vector>

#include "rll/core/device.h"
#include "rll/wavefront/stages.h"

namespace rll::cuda {

// Throws rll::Error "CUDA: <what>: <CUDA's description>" unless e is cudaSuccess.
void check(cudaError_t e, const char* what);

// What this process asked of the GPU through this backend so far (DeviceWork, wavefront/
// stages.h): the reads that wait for it, the launches (kernels, CUB calls, fills and copies on the
// device), the allocations (device and pinned memory) and the bytes copied each way. Counted by
// DeviceArray, parallel_for, CudaBackend (backend.cuh), DeviceMirror (device_scene.cuh) and the
// wavefront's backend (wavefront.cu); a renderer reports the difference between two readings.
DeviceWork device_work();
namespace count {
void sync();
void launch(uint64_t n = 1);
void allocation();
void to_host(uint64_t bytes);
void to_device(uint64_t bytes);
}  // namespace count

namespace detail {
// Device memory through a cache (runtime.cu), as CUB's caching allocator and pbrt-v4 keep it: a
// released block waits for the next request it fits (up to twice its size) instead of going
// back to CUDA, so that the arrays a pass or a frame takes and frees (the end of pass's scratch,
// a sampler's tables uploaded again) cost no cudaMalloc, and no cudaFree, which waits for the
// whole device. Only cudaMalloc is counted as an allocation. Everything runs on the default
// stream in order, so a block reused by later work is never in use by earlier work. When
// cudaMalloc fails, the cache is emptied and the request tried again.
void* device_allocate(size_t bytes);
void device_release(void* p, size_t bytes) noexcept;
}  // namespace detail

// The owner of an array in device memory (cudaMalloc through the cache above; no managed memory):
// move-only. Errors of earlier kernels on the default stream surface in upload and download,
// which synchronize.
template <typename T>
class DeviceArray {
  static_assert(std::is_trivially_copyable_v<T>, "DeviceArray holds bytes copied to the GPU");

 public:
  DeviceArray() = default;
  explicit DeviceArray(size_t n) : m_size(n) {
    if (n > 0) m_data = static_cast<T*>(detail::device_allocate(bytes()));
  }
  ~DeviceArray() {
    if (m_data) detail::device_release(m_data, bytes());
  }
  DeviceArray(DeviceArray&& o) noexcept
      : m_data(std::exchange(o.m_data, nullptr)), m_size(std::exchange(o.m_size, 0)) {}
  DeviceArray& operator=(DeviceArray&& o) noexcept {
    if (this != &o) {
      if (m_data) detail::device_release(m_data, bytes());
      m_data = std::exchange(o.m_data, nullptr);
      m_size = std::exchange(o.m_size, 0);
    }
    return *this;
  }
  DeviceArray(const DeviceArray&) = delete;
  DeviceArray& operator=(const DeviceArray&) = delete;

  // Copies size() elements from the host; the sizes must match (resize by assigning a new array).
  void upload(const std::vector<T>& v) { upload(v.data(), v.size()); }
  void upload(const T* p, size_t n) {
    check_size(n, "upload");
    if (n == 0) return;
    check(cudaMemcpy(m_data, p, bytes(), cudaMemcpyHostToDevice), "upload");
    count::to_device(bytes());
  }
  std::vector<T> download() const {
    std::vector<T> v(m_size);
    download(v.data());
    return v;
  }
  // Copies size() elements into p.
  void download(T* p) const {
    if (m_size == 0) return;
    check(cudaMemcpy(p, m_data, bytes(), cudaMemcpyDeviceToHost), "download");
    count::sync();
    count::to_host(bytes());
  }

  View<T> view() { return {m_data, m_size}; }
  View<const T> view() const { return {m_data, m_size}; }
  size_t size() const { return m_size; }
  size_t bytes() const { return m_size * sizeof(T); }

 private:
  void check_size(size_t n, const char* what) const;

  T* m_data = nullptr;
  size_t m_size = 0;
};

namespace detail {
// Says which sizes did not match (in runtime.cu, so that this header needs no formatting library).
[[noreturn]] void size_mismatch(const char* what, size_t expected, size_t got);

inline constexpr unsigned kBlockSize = 256;

template <typename Body>
__global__ void parallel_for_kernel(size_t n, Body body) {
  const size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
  if (i < n) body(i);
}
}  // namespace detail

template <typename T>
void DeviceArray<T>::check_size(size_t n, const char* what) const {
  if (n != m_size) detail::size_mismatch(what, m_size, n);
}

// Calls body(i) for every i in [0, n) on the GPU, one thread per index. body is an RLL_HD
// callable (a __host__ __device__ lambda, --extended-lambda) copied by value into the kernel, so
// it holds views, never containers. Asynchronous: launch errors throw here, errors while running
// at the next synchronizing call (download, EventTimer::stop_ms).
template <typename Body>
void parallel_for(size_t n, const Body& body, cudaStream_t s = 0) {
  if (n == 0) return;
  const size_t blocks = (n + detail::kBlockSize - 1) / detail::kBlockSize;
  if (blocks > size_t(0x7fffffff)) check(cudaErrorInvalidValue, "parallel_for over 2^31 blocks");
  detail::parallel_for_kernel<<<unsigned(blocks), detail::kBlockSize, 0, s>>>(n, body);
  check(cudaGetLastError(), "kernel launch");
  count::launch();
}

// Times GPU work between start and stop_ms on a stream (CUDA events: the GPU's own clock).
class EventTimer {
 public:
  EventTimer();
  ~EventTimer();
  EventTimer(const EventTimer&) = delete;
  EventTimer& operator=(const EventTimer&) = delete;

  void start(cudaStream_t s = 0);
  // Waits for the work recorded since start and returns its time in milliseconds.
  float stop_ms(cudaStream_t s = 0);

 private:
  cudaEvent_t m_start = nullptr;
  cudaEvent_t m_stop = nullptr;
};

// Times of GPU work recorded without waiting (pbrt-v4's way): mark(key) records an event pair's
// start on the stream, done() its end; read() after something waited for the stream (the pass's
// one synchronisation) adds each pair's milliseconds to its key and frees the pairs for reuse.
// The pairs are created as needed and kept (no creation per frame once the pool is large enough).
class EventPool {
 public:
  EventPool() = default;
  ~EventPool();
  EventPool(const EventPool&) = delete;
  EventPool& operator=(const EventPool&) = delete;

  void start(size_t key, cudaStream_t s = 0);
  void stop(cudaStream_t s = 0);
  // Forgets the pairs recorded since the last read (a render that ended early left them).
  void discard() { m_used = 0; }
  // Calls add(key, ms) for every pair recorded since the last read (their work must be done).
  template <typename Add>
  void read(const Add& add) {
    for (size_t i = 0; i < m_used; ++i) add(m_keys[i], elapsed_ms(i));
    m_used = 0;
  }

 private:
  float elapsed_ms(size_t i) const;

  std::vector<cudaEvent_t> m_events;  // 2 per pair: start, stop
  std::vector<size_t> m_keys;
  size_t m_used = 0;
};

}  // namespace rll::cuda
