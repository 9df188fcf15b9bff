// The GPU side of the checks that RLL's end of pass is device code (issue 31): cut_end_pass
// (learn/cut_end_pass.h) run by a kernel over device copies of a CutStore's arrays, and the whole
// end of pass (rll_end_pass, lights/rll_end_pass.h) run through the CUDA backend over device
// copies of a sampler's learning arrays; the arrays copied back, so that a test compares them
// with the CPU's run of the same functions (no GPU: cuda/absent.cpp says why not). Plain C++:
// host code includes it.
#pragma once

#include <cstdint>
#include <vector>

#include "rll/learn/cut_end_pass.h"
#include "rll/lights/rll_end_pass.h"
#include "rll/lights/rll_sampler.h"

namespace rll {

// The end of pass of every cell of `cells` on the GPU, over device copies of the host arrays of
// `v`; the arrays the end of pass writes are copied back into v's host arrays. The stats per cell.
std::vector<CutPassStats> cut_end_pass_gpu(const CutStoreEndView& v,
                                           const std::vector<uint32_t>& cells);

// rll_end_pass on the GPU (the CUDA backend) over device copies of v's host arrays and of
// `pool`; every array copied back into v's and `pool` replaced by the device's coarse cells.
// RllLightSampler::end_pass_with takes it.
RllPassCounts rll_end_pass_gpu(const RllLearnView& v, RllPoolState<HostBackend>& pool,
                               uint32_t used_before, bool reset);

// The sampler's state uploaded to the device as `rll render --device cuda` keeps it
// (cuda/device_rll.cuh), one end of pass run there, and the state pulled back.
void rll_end_pass_resident_gpu(RllLightSampler& s);
// The same for lights_changed (the session's light tree refit already): run on the device's copy.
void rll_lights_changed_resident_gpu(RllLightSampler& s, const Scene& scene);

}  // namespace rll
