// Device copies of the host's flat views (nvcc only): a mirror of any view's array, and the
// scene's views mirrored whole. A view of const elements is uploaded; a view of writable ones is
// uploaded and can be copied back, so that what kernels wrote reaches the host's owner.
#pragma once

#include <cuda_runtime.h>

#include <cstddef>
#include <type_traits>
#include <vector>

#include "rll/cuda/launch.cuh"
#include "rll/scene/scene_view.h"

namespace rll::cuda {

class DeviceMirror {
 public:
  DeviceMirror() = default;
  DeviceMirror(const DeviceMirror&) = delete;
  DeviceMirror& operator=(const DeviceMirror&) = delete;

  // A device copy of the host array `v` (an empty view stays empty).
  template <typename T>
  View<T> mirror(View<T> v) {
    using Plain = std::remove_const_t<T>;
    static_assert(std::is_trivially_copyable_v<Plain>, "a mirrored array is copied as bytes");
    if (v.size == 0) return {nullptr, 0};
    Plain* d = static_cast<Plain*>(allocate(v.size * sizeof(T)));
    check(cudaMemcpy(d, v.data, v.size * sizeof(T), cudaMemcpyHostToDevice), "upload");
    count::to_device(v.size * sizeof(T));
    if constexpr (!std::is_const_v<T>) m_back.push_back({v.data, d, v.size * sizeof(T)});
    return {d, v.size};
  }
  // One element, as a pointer (null stays null).
  template <typename T>
  T* mirror_one(T* p) {
    return p ? mirror(View<T>{p, 1}).data : nullptr;
  }
  // Copies every writable array back to the host array it mirrors (waits for the kernels).
  void copy_back() const {
    for (const Back& b : m_back) {
      check(cudaMemcpy(b.host, b.device, b.bytes, cudaMemcpyDeviceToHost), "download");
      count::sync();
      count::to_host(b.bytes);
    }
  }
  // Raw device memory, freed with the mirror.
  void* allocate(size_t bytes) {
    m_arrays.emplace_back(bytes);
    m_bytes += bytes;
    return m_arrays.back().view().data;
  }
  size_t bytes() const { return m_bytes; }
  // Frees everything.
  void clear() {
    m_arrays.clear();
    m_back.clear();
    m_bytes = 0;
  }

 private:
  struct Back {
    void* host;
    const void* device;
    size_t bytes;
  };
  std::vector<DeviceArray<unsigned char>> m_arrays;
  std::vector<Back> m_back;
  size_t m_bytes = 0;
};

// A SceneView whose arrays live in device memory.
class DeviceScene {
 public:
  explicit DeviceScene(const SceneView& s) {
    m_view.mesh.positions = m_memory.mirror(s.mesh.positions);
    m_view.mesh.normals = m_memory.mirror(s.mesh.normals);
    m_view.mesh.uvs = m_memory.mirror(s.mesh.uvs);
    m_view.mesh.triangles = m_memory.mirror(s.mesh.triangles);
    m_view.mesh.material = m_memory.mirror(s.mesh.material);
    m_view.mesh.light = m_memory.mirror(s.mesh.light);
    m_view.materials = m_memory.mirror(s.materials);
    m_view.lights = m_memory.mirror(s.lights);
    // Each texture's texels, then the texture views pointing at them.
    std::vector<TexelView> textures;
    for (const TexelView& t : s.textures)
      textures.push_back({m_memory.mirror(t.texels), t.width, t.height});
    m_view.textures = m_memory.mirror(View<const TexelView>{textures.data(), textures.size()});
  }
  const SceneView& view() const { return m_view; }
  size_t bytes() const { return m_memory.bytes(); }

 private:
  DeviceMirror m_memory;
  SceneView m_view;
};

}  // namespace rll::cuda
