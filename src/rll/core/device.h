// What differs between the CPU and the GPU, and nothing else (DESIGN 6): the mark for functions
// that run on both, a non-owning view of an array, atomics, and the loop that launches a kernel
// body over [0, n). Every kernel is a plain RLL_HD function over views; the CPU runs it in every
// test through parallel_for here, the GPU runs the same function through the CUDA launch in
// rll/cuda/launch.cuh.
#pragma once

#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <vector>

#if defined(__CUDACC__)
#define RLL_HD __host__ __device__
#define RLL_DEVICE __device__
#else
#define RLL_HD
#define RLL_DEVICE
#endif

// True while compiling device code (nvcc's device pass); host-only branches test it.
#if defined(__CUDA_ARCH__)
#define RLL_DEVICE_CODE 1
#else
#define RLL_DEVICE_CODE 0
#endif

#if defined(__CUDACC__)
#include <cuda/atomic>  // libcu++, shipped with the toolkit
#endif
#if !RLL_DEVICE_CODE
#include <atomic>
#endif

namespace rll {

// A non-owning view of a contiguous array in host or device memory: what kernels read and write
// instead of containers. Trivially copyable, so it travels by value into a CUDA launch.
template <typename T>
struct View {
  T* data = nullptr;
  size_t size = 0;

  RLL_HD T& operator[](size_t i) const { return data[i]; }
  RLL_HD T* begin() const { return data; }
  RLL_HD T* end() const { return data + size; }
  RLL_HD bool empty() const { return size == 0; }
  // A view of const elements of the same array (a template, so that View<const T> declares no
  // conversion to itself, which nvcc warns about).
  template <typename U = T>
  requires(!std::is_const_v<U>) RLL_HD operator View<const U>() const { return {data, size}; }
};

template <typename T>
View<T> view_of(std::vector<T>& v) {
  return {v.data(), v.size()};
}
template <typename T>
View<const T> view_of(const std::vector<T>& v) {
  return {v.data(), v.size()};
}

// Atomics on plain memory: std::atomic_ref on the CPU, libcu++'s cuda::atomic_ref (device scope)
// on the GPU, with the same memory orders on both. Adds and max are relaxed: integer adds are
// exact and commutative, which is why sums that must not depend on the order of threads (rewards,
// DESIGN 6) are kept in 64-bit fixed point and added with atomic_add. A value that publishes
// other data (a cell table's slot word, which makes the cell's full key and id visible) is written
// by a release (atomic_store, atomic_cas) and read by an acquire (atomic_load, atomic_cas), so
// that the reader's later loads see what the writer wrote before: on the GPU a plain or volatile
// load after a relaxed one may come from another SM's stale L1 line.
#if RLL_DEVICE_CODE
namespace detail {
template <typename T>
using DeviceAtomicRef = ::cuda::atomic_ref<T, ::cuda::thread_scope_device>;
}  // namespace detail
#endif

RLL_HD inline uint64_t atomic_add(uint64_t* p, uint64_t v) {
#if RLL_DEVICE_CODE
  return detail::DeviceAtomicRef<uint64_t>(*p).fetch_add(v, ::cuda::memory_order_relaxed);
#else
  return std::atomic_ref<uint64_t>(*p).fetch_add(v, std::memory_order_relaxed);
#endif
}

RLL_HD inline uint32_t atomic_add(uint32_t* p, uint32_t v) {
#if RLL_DEVICE_CODE
  return detail::DeviceAtomicRef<uint32_t>(*p).fetch_add(v, ::cuda::memory_order_relaxed);
#else
  return std::atomic_ref<uint32_t>(*p).fetch_add(v, std::memory_order_relaxed);
#endif
}

// Stores `desired` if *p equals `expected` (a release: it publishes the thread's earlier writes);
// returns the value *p held before (an acquire also where it differed: the caller reads what the
// winner published).
namespace detail {
template <typename T>
RLL_HD inline T atomic_cas(T* p, T expected, T desired) {
#if RLL_DEVICE_CODE
  detail::DeviceAtomicRef<T>(*p).compare_exchange_strong(
      expected, desired, ::cuda::memory_order_acq_rel, ::cuda::memory_order_acquire);
#else
  std::atomic_ref<T>(*p).compare_exchange_strong(expected, desired, std::memory_order_acq_rel,
                                                 std::memory_order_acquire);
#endif
  return expected;
}
}  // namespace detail
RLL_HD inline uint64_t atomic_cas(uint64_t* p, uint64_t expected, uint64_t desired) {
  return detail::atomic_cas(p, expected, desired);
}
RLL_HD inline uint32_t atomic_cas(uint32_t* p, uint32_t expected, uint32_t desired) {
  return detail::atomic_cas(p, expected, desired);
}

RLL_HD inline uint32_t atomic_max(uint32_t* p, uint32_t v) {
#if RLL_DEVICE_CODE
  return detail::DeviceAtomicRef<uint32_t>(*p).fetch_max(v, ::cuda::memory_order_relaxed);
#else
  std::atomic_ref<uint32_t> a(*p);
  uint32_t old = a.load(std::memory_order_relaxed);
  while (old < v && !a.compare_exchange_weak(old, v, std::memory_order_relaxed)) {
  }
  return old;
#endif
}

// An acquire load: what the thread that stored the value (by a release) wrote before it is
// visible to this thread's later loads.
RLL_HD inline uint64_t atomic_load(const uint64_t* p) {
#if RLL_DEVICE_CODE
  return detail::DeviceAtomicRef<uint64_t>(*const_cast<uint64_t*>(p))
      .load(::cuda::memory_order_acquire);
#else
  return std::atomic_ref<uint64_t>(*const_cast<uint64_t*>(p)).load(std::memory_order_acquire);
#endif
}

RLL_HD inline uint32_t atomic_load(const uint32_t* p) {
#if RLL_DEVICE_CODE
  return detail::DeviceAtomicRef<uint32_t>(*const_cast<uint32_t*>(p))
      .load(::cuda::memory_order_acquire);
#else
  return std::atomic_ref<uint32_t>(*const_cast<uint32_t*>(p)).load(std::memory_order_acquire);
#endif
}

// A release store (the counterpart of atomic_load).
RLL_HD inline void atomic_store(uint32_t* p, uint32_t v) {
#if RLL_DEVICE_CODE
  detail::DeviceAtomicRef<uint32_t>(*p).store(v, ::cuda::memory_order_release);
#else
  std::atomic_ref<uint32_t>(*p).store(v, std::memory_order_release);
#endif
}

// Reals summed exactly and in any order: a value is scaled by 2^kFixedPointBits and rounded to a
// 64-bit integer (a signed sum in two's complement). 2^24 keeps 7 decimal digits below 1 and sums
// up to 5e11 without overflow.
inline constexpr int kFixedPointBits = 24;
RLL_HD inline uint64_t to_fixed_point(double v) {
  double scaled = v * double(uint64_t(1) << kFixedPointBits);
  return uint64_t(int64_t(scaled < 0 ? scaled - 0.5 : scaled + 0.5));
}
RLL_HD inline double from_fixed_point(uint64_t v) {
  return double(int64_t(v)) / double(uint64_t(1) << kFixedPointBits);
}

// The loop that runs a kernel body over [0, n) on the host: a TBB parallel loop (parallel.h).
// The body is an RLL_HD callable taking the index; the GPU launches the same body through
// rll::cuda::parallel_for (rll/cuda/launch.cuh).
void host_parallel_for_impl(size_t n, void* context, void (*call)(void*, size_t, size_t));

template <typename Body>
void host_parallel_for(size_t n, const Body& body) {
  host_parallel_for_impl(n, const_cast<Body*>(&body), [](void* ctx, size_t begin, size_t end) {
    const Body& f = *static_cast<const Body*>(ctx);
    for (size_t i = begin; i < end; ++i) f(i);
  });
}

}  // namespace rll
