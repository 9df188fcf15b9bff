// The CUDA backend's per-kernel resource budgets (issue 43, DESIGN 6), all of them, in one place:
// what test_kernel_budgets.cpp holds every kernel of the build's sm_90 code to, as ptxas reports
// it when rll_device compiles (scripts/ptxas-report.sh keeps the report in
// <build>/kernel_resources/). bench/RESULTS.md has each kernel's figures.
#pragma once

namespace rll::budgets {

// The code the budgets are for (CMakeLists.txt's CMAKE_CUDA_ARCHITECTURES: 90-real).
inline constexpr const char* kArch = "sm_90";

// Every kernel: its stack frame (local arrays, spills and callees' frames: ptxas's cumulative
// stack size where it gives one). A frame of F bytes makes the driver reserve F times the threads
// the GPU can hold of local memory (14 KB frames took about 4 GB at the first end of pass).
inline constexpr int kMaxStackBytes = 1024;

// The wavefront's path stages (the kernels of WavefrontDriver: camera rays to accumulation):
// registers per thread, so that two 256-thread blocks fit an SM (65,536 registers), and no spill
// to local memory.
inline constexpr int kMaxPathStageRegisters = 128;
inline constexpr int kMaxPathStageSpillBytes = 0;

// Path stages over the register budget for now, each held to what it uses today so that it does
// not grow; the test says when one is back within the budget (then its line goes). NeeSample: 134
// registers (sm_90, CUDA 13.0), not from the light sampler (a kernel running every sampler's
// sample and pmf, sampler_probe_gpu, takes 77) but from the candidates' set-up and BSDF
// evaluation held together with the choice (render/path_vertex.h's resample_nee); splitting the
// stage, as pbrt-v4 splits material evaluation, is the wavefront driver's to do (issue 43).
struct RegisterAllowance {
  const char* stage;  // as kWavefrontStageNames names it
  int registers;
};
inline constexpr RegisterAllowance kRegisterAllowances[] = {{"nee_sample", 134}};

}  // namespace rll::budgets
