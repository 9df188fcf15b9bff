// The CUDA backend where rll was built without nvcc: no GPUs, and a check that says why.
#include "rll/core/error.h"
#include "rll/cuda/cuda.h"

namespace rll::cuda {

bool cuda_built() {
  return false;
}

std::vector<GpuInfo> gpus() {
  return {};
}

void require_gpu() {
  fail(
      "this rll was built without CUDA (nvcc was not found when it was configured): install the "
      "CUDA toolkit (nvcc on PATH or in /usr/local/cuda/bin) and re-run cmake");
}

}  // namespace rll::cuda
