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

namespace rll::cuda {

// Throws rll::Error "CUDA: <what>: <CUDA's description>" unless e is cudaSuccess.
void check(cudaError_t e, const char* what);

// The owner of an array in device memory (cudaMalloc; no managed memory): move-only. Errors of
// earlier kernels on the default stream surface in upload and download, which synchronize.
template <typename T>
class DeviceArray {
  static_assert(std::is_trivially_copyable_v<T>, "DeviceArray holds bytes copied to the GPU");

 public:
  DeviceArray() = default;
  explicit DeviceArray(size_t n) : m_size(n) {
    if (n > 0) check(cudaMalloc(reinterpret_cast<void**>(&m_data), bytes()), "cudaMalloc");
  }
  ~DeviceArray() {
    if (m_data) cudaFree(m_data);  // no throw from a destructor; a failure here leaks nothing more
  }
  DeviceArray(DeviceArray&& o) noexcept
      : m_data(std::exchange(o.m_data, nullptr)), m_size(std::exchange(o.m_size, 0)) {}
  DeviceArray& operator=(DeviceArray&& o) noexcept {
    if (this != &o) {
      if (m_data) cudaFree(m_data);
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
    if (n > 0) check(cudaMemcpy(m_data, p, bytes(), cudaMemcpyHostToDevice), "upload");
  }
  std::vector<T> download() const {
    std::vector<T> v(m_size);
    download(v.data());
    return v;
  }
  // Copies size() elements into p.
  void download(T* p) const {
    if (m_size > 0) check(cudaMemcpy(p, m_data, bytes(), cudaMemcpyDeviceToHost), "download");
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

}  // namespace rll::cuda
