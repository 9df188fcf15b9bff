// What the CUDA backend offers to plain C++ code: whether it was built, the GPUs this machine
// has, and the check that commands needing a GPU make first. Builds without nvcc link absent.cpp.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace rll::cuda {

// True where rll was built with nvcc (the kernels of src/rll/cuda/ exist).
bool cuda_built();

struct GpuInfo {
  std::string name;
  int sm_major = 0, sm_minor = 0;  // compute capability
  int multiprocessors = 0;
  size_t memory_bytes = 0;
  int driver_version = 0, runtime_version = 0;  // CUDA's encoding: 1000 * major + 10 * minor
};

// The CUDA devices, in CUDA's order; empty where CUDA is not built, there is no driver or no
// device (never throws for those).
std::vector<GpuInfo> gpus();

// Throws rll::Error saying why there is no usable GPU and what to do: rll built without CUDA, no
// NVIDIA driver, a driver older than the runtime, no device, or none that runs rll's kernels.
void require_gpu();

}  // namespace rll::cuda
