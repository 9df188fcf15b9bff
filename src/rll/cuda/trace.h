// rll's BVH traced on the GPU (cuda/trace.cu): the traversal of bvh/traverse.h run unchanged by
// CUDA kernels, for tests and the ray-rate benchmark. Plain C++: callers need no nvcc. Every
// function throws rll::Error where CUDA is not built or finds no usable GPU.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "rll/bvh/bvh.h"
#include "rll/scene/hit.h"

namespace rll::cuda {

// A BVH uploaded to the GPU once, for many batches.
class GpuBvh {
 public:
  explicit GpuBvh(const Bvh& bvh);
  ~GpuBvh();
  GpuBvh(const GpuBvh&) = delete;
  GpuBvh& operator=(const GpuBvh&) = delete;
  size_t bytes() const;  // of GPU memory
  struct Impl;
  const Impl& impl() const { return *m_impl; }

 private:
  std::unique_ptr<Impl> m_impl;
};

// Closest hits (a miss: Hit{}, tri == ~0u) and occlusion verdicts (1: occluded) of a batch.
std::vector<Hit> gpu_intersect(const GpuBvh& bvh, const std::vector<Ray>& rays);
std::vector<uint8_t> gpu_occluded(const GpuBvh& bvh, const std::vector<Ray>& rays);

struct TraceRate {
  double rays_per_second = 0;  // the median over the repeats
  double min_rays_per_second = 0, max_rays_per_second = 0;
  size_t device_bytes = 0;  // rays and results
};
// Times `repeats` launches over the batch (uploaded once) with CUDA events: closest hits, or
// occlusion when `shadow`.
TraceRate gpu_trace_rate(const GpuBvh& bvh, const std::vector<Ray>& rays, bool shadow,
                         int repeats = 5);

}  // namespace rll::cuda
