// The GPU side of the check that the hot functions of scene/ and core/ are device code (issue
// 31): a kernel runs onesource_probe, which calls each of them, over a SceneView in device memory.
#include <cuda_runtime.h>

#include <stdexcept>
#include <string>

#include "rll/cuda/onesource_check.h"

namespace rll {

namespace {

// (rll::Error's header needs fmt, which nvcc does not compile: the caller rethrows.)
void cuda_check(cudaError_t e, const char* what) {
  if (e != cudaSuccess)
    throw std::runtime_error(std::string("CUDA: ") + what + ": " + cudaGetErrorString(e));
}

// Device copies of a SceneView's arrays, freed together.
class DeviceScene {
 public:
  explicit DeviceScene(const SceneView& s) {
    m_view.mesh.positions = upload(s.mesh.positions);
    m_view.mesh.normals = upload(s.mesh.normals);
    m_view.mesh.uvs = upload(s.mesh.uvs);
    m_view.mesh.triangles = upload(s.mesh.triangles);
    m_view.mesh.material = upload(s.mesh.material);
    m_view.mesh.light = upload(s.mesh.light);
    m_view.materials = upload(s.materials);
    m_view.lights = upload(s.lights);
    // All texels in one array, each texture a view of its part.
    size_t texels = 0;
    for (const TexelView& t : s.textures) texels += t.texels.size;
    Rgb* all = static_cast<Rgb*>(allocate(texels * sizeof(Rgb)));
    std::vector<TexelView> textures;
    size_t offset = 0;
    for (const TexelView& t : s.textures) {
      cuda_check(cudaMemcpy(all + offset, t.texels.data, t.texels.size * sizeof(Rgb),
                            cudaMemcpyHostToDevice),
                 "copying texels");
      textures.push_back({{all + offset, t.texels.size}, t.width, t.height});
      offset += t.texels.size;
    }
    m_view.textures = upload(View<const TexelView>{textures.data(), textures.size()});
  }
  DeviceScene(const DeviceScene&) = delete;
  DeviceScene& operator=(const DeviceScene&) = delete;
  ~DeviceScene() {
    for (void* p : m_allocations) cudaFree(p);
  }
  const SceneView& view() const { return m_view; }

  void* allocate(size_t bytes) {
    void* p = nullptr;
    if (bytes > 0) cuda_check(cudaMalloc(&p, bytes), "cudaMalloc");
    m_allocations.push_back(p);
    return p;
  }
  template <typename T>
  View<const T> upload(View<const T> v) {
    T* d = static_cast<T*>(allocate(v.size * sizeof(T)));
    if (v.size > 0)
      cuda_check(cudaMemcpy(d, v.data, v.size * sizeof(T), cudaMemcpyHostToDevice), "cudaMemcpy");
    return {d, v.size};
  }

 private:
  SceneView m_view;
  std::vector<void*> m_allocations;
};

}  // namespace

__global__ void onesource_probe_kernel(SceneView scene, View<const Hit> hits,
                                       View<OneSourceResult> out) {
  const size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
  if (i < hits.size) out[i] = onesource_probe(scene, hits[i], i);
}

std::vector<OneSourceResult> onesource_probe_gpu(const SceneView& scene,
                                                 const std::vector<Hit>& hits) {
  DeviceScene d(scene);
  View<const Hit> d_hits = d.upload(View<const Hit>{hits.data(), hits.size()});
  auto* d_out = static_cast<OneSourceResult*>(d.allocate(hits.size() * sizeof(OneSourceResult)));
  std::vector<OneSourceResult> out(hits.size());
  if (hits.empty()) return out;
  const unsigned block = 128, grid = unsigned((hits.size() + block - 1) / block);
  onesource_probe_kernel<<<grid, block>>>(d.view(), d_hits, {d_out, hits.size()});
  cuda_check(cudaGetLastError(), "launching onesource_probe_kernel");
  cuda_check(
      cudaMemcpy(out.data(), d_out, out.size() * sizeof(OneSourceResult), cudaMemcpyDeviceToHost),
      "copying the probes back");
  return out;
}

}  // namespace rll
