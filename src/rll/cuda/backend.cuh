// The GPU's side of core/backend.h (nvcc only): arrays in device memory, CUDA launches, and CUB
// (part of the CUDA toolkit) for the sort, the scan and the sum. Everything runs on the default
// stream in order; the scalar reads wait for the work before them. Each CUB call counts as one
// launch, each read as one synchronisation (cuda::device_work); the arrays come from the
// device's memory cache (launch.cuh), so that an end of pass like the last takes no cudaMalloc.
#pragma once

#include <cuda_runtime.h>

#include <cstdint>
#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_reduce.cuh>
#include <cub/device/device_scan.cuh>
#include <cuda/std/functional>

#include "rll/core/backend.h"
#include "rll/cuda/launch.cuh"

namespace rll::cuda {

struct CudaBackend {
  template <typename T>
  using Buffer = DeviceArray<T>;

  // An array of n zero values in device memory.
  template <typename T>
  Buffer<T> buffer(size_t n) const {
    Buffer<T> a(n);
    if (n > 0) {
      check(cudaMemsetAsync(a.view().data, 0, a.bytes()), "cudaMemsetAsync");
      count::launch();
    }
    return a;
  }
  template <typename Body>
  void parallel_for(size_t n, const Body& body) const {
    cuda::parallel_for(n, body);
  }
  // In parallel (core/backend.h says for what).
  template <typename Body>
  void ordered_for(size_t n, const Body& body) const {
    cuda::parallel_for(n, body);
  }
  // CUB's radix sort, stable as the host's std::stable_sort.
  void sort_pairs(View<uint64_t> keys, View<uint32_t> values) const {
    if (keys.size < 2) return;
    Buffer<uint64_t> keys_out(keys.size);
    Buffer<uint32_t> values_out(keys.size);
    size_t bytes = 0;
    check(cub::DeviceRadixSort::SortPairs(nullptr, bytes, keys.data, keys_out.view().data,
                                          values.data, values_out.view().data, keys.size),
          "cub::DeviceRadixSort::SortPairs");
    Buffer<unsigned char> temp(bytes);
    check(cub::DeviceRadixSort::SortPairs(temp.view().data, bytes, keys.data, keys_out.view().data,
                                          values.data, values_out.view().data, keys.size),
          "cub::DeviceRadixSort::SortPairs");
    check(cudaMemcpyAsync(keys.data, keys_out.view().data, keys_out.bytes(),
                          cudaMemcpyDeviceToDevice),
          "cudaMemcpyAsync");
    check(cudaMemcpyAsync(values.data, values_out.view().data, values_out.bytes(),
                          cudaMemcpyDeviceToDevice),
          "cudaMemcpyAsync");
    count::launch(3);
  }
  // CUB's exclusive scan, summed in 64 bits (the initial value's type); the total read back.
  uint64_t exclusive_scan(View<const uint32_t> in, View<uint64_t> out) const {
    if (in.size == 0) return 0;
    size_t bytes = 0;
    const ::cuda::std::plus<uint64_t> plus;
    check(cub::DeviceScan::ExclusiveScan(nullptr, bytes, in.data, out.data, plus, uint64_t(0),
                                         in.size),
          "cub::DeviceScan::ExclusiveScan");
    Buffer<unsigned char> temp(bytes);
    check(cub::DeviceScan::ExclusiveScan(temp.view().data, bytes, in.data, out.data, plus,
                                         uint64_t(0), in.size),
          "cub::DeviceScan::ExclusiveScan");
    count::launch();
    return read(&out[in.size - 1]) + read(&in[in.size - 1]);
  }
  // CUB's reduction, in 64 bits.
  uint64_t sum(View<const uint32_t> in) const {
    if (in.size == 0) return 0;
    Buffer<uint64_t> total(1);
    size_t bytes = 0;
    const ::cuda::std::plus<uint64_t> plus;
    check(cub::DeviceReduce::Reduce(nullptr, bytes, in.data, total.view().data, in.size, plus,
                                    uint64_t(0)),
          "cub::DeviceReduce::Reduce");
    Buffer<unsigned char> temp(bytes);
    check(cub::DeviceReduce::Reduce(temp.view().data, bytes, in.data, total.view().data, in.size,
                                    plus, uint64_t(0)),
          "cub::DeviceReduce::Reduce");
    count::launch();
    return read(total.view().data);
  }
  template <typename T>
  T read(const T* p) const {
    T v;
    check(cudaMemcpy(&v, p, sizeof(T), cudaMemcpyDeviceToHost), "cudaMemcpy");
    count::sync();
    count::to_host(sizeof(T));
    return v;
  }
};

}  // namespace rll::cuda
