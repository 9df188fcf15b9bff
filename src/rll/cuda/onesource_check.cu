// The GPU side of the check that the hot functions of scene/ and core/ are device code (issue
// 31): a kernel runs onesource_probe, which calls each of them, over a SceneView in device memory.
#include <cuda_runtime.h>

#include <stdexcept>
#include <string>

#include "rll/cuda/device_scene.cuh"
#include "rll/cuda/onesource_check.h"

namespace rll {

__global__ void onesource_probe_kernel(SceneView scene, View<const Hit> hits,
                                       View<OneSourceResult> out) {
  const size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
  if (i < hits.size) out[i] = onesource_probe(scene, hits[i], i);
}

std::vector<OneSourceResult> onesource_probe_gpu(const SceneView& scene,
                                                 const std::vector<Hit>& hits) {
  cuda::DeviceScene d(scene);
  cuda::DeviceArray<Hit> d_hits_array(hits.size());
  d_hits_array.upload(hits);
  const View<const Hit> d_hits = d_hits_array.view();
  cuda::DeviceArray<OneSourceResult> d_out_array(hits.size());
  OneSourceResult* d_out = d_out_array.view().data;
  std::vector<OneSourceResult> out(hits.size());
  if (hits.empty()) return out;
  const unsigned block = 128, grid = unsigned((hits.size() + block - 1) / block);
  onesource_probe_kernel<<<grid, block>>>(d.view(), d_hits, {d_out, hits.size()});
  cuda::check(cudaGetLastError(), "launching onesource_probe_kernel");
  d_out_array.download(out.data());
  return out;
}

}  // namespace rll
