// The GPU tests' main: skipped (exit 77, ctest's SKIP_RETURN_CODE) where rll was built without
// CUDA or the machine has no CUDA device, so that `make test` passes on machines without a GPU.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include "rll/core/error.h"
#include "rll/cuda/cuda.h"

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  if (rll::cuda::gpus().empty()) {
    try {
      rll::cuda::require_gpu();
    } catch (const rll::Error& e) {
      fmt::print("GPU tests skipped: {}\n", e.what());
    }
    return 77;
  }
  return RUN_ALL_TESTS();
}
