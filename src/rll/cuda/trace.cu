// The GPU side of rll's BVH: upload, and kernels that trace batches of rays through the same
// RLL_HD traversal (bvh/traverse.h) that the CPU runs.
#include <algorithm>

#include "rll/bvh/traverse.h"
#include "rll/cuda/launch.cuh"
#include "rll/cuda/trace.h"

namespace rll::cuda {

struct GpuBvh::Impl {
  DeviceArray<BvhNode> nodes;
  DeviceArray<BvhTriangle> triangles;
  BvhView view() const { return {nodes.view(), triangles.view()}; }
};

GpuBvh::GpuBvh(const Bvh& bvh) : m_impl(std::make_unique<Impl>()) {
  m_impl->nodes = DeviceArray<BvhNode>(bvh.nodes.size());
  m_impl->nodes.upload(bvh.nodes);
  m_impl->triangles = DeviceArray<BvhTriangle>(bvh.triangles.size());
  m_impl->triangles.upload(bvh.triangles);
}

GpuBvh::~GpuBvh() = default;

size_t GpuBvh::bytes() const {
  return m_impl->nodes.bytes() + m_impl->triangles.bytes();
}

namespace {

static_assert(sizeof(Ray) == 32 && sizeof(Hit) == 16);

// A ray as two 16-byte loads on the GPU (cudaMalloc aligns the array to 256 bytes, a Ray is 32).
RLL_HD inline Ray load_ray(View<const Ray> rays, size_t i) {
#if RLL_DEVICE_CODE
  const float4* p = reinterpret_cast<const float4*>(rays.data + i);
  float4 a = __ldg(p), b = __ldg(p + 1);
  Ray r;
  r.o = Vec3(a.x, a.y, a.z);
  r.d = Vec3(a.w, b.x, b.y);
  r.tmin = b.z;
  r.tmax = b.w;
  return r;
#else
  return rays[i];
#endif
}

void launch_intersect(BvhView bvh, View<const Ray> rays, View<Hit> hits) {
  parallel_for(rays.size, [=] RLL_HD(size_t i) {
    Hit h;
    intersect(bvh, load_ray(rays, i), h);
    hits[i] = h;
  });
}

void launch_occluded(BvhView bvh, View<const Ray> rays, View<uint8_t> out) {
  parallel_for(rays.size,
               [=] RLL_HD(size_t i) { out[i] = occluded(bvh, load_ray(rays, i)) ? 1 : 0; });
}

DeviceArray<Ray> upload_rays(const std::vector<Ray>& rays) {
  DeviceArray<Ray> d(rays.size());
  d.upload(rays);
  return d;
}

}  // namespace

std::vector<Hit> gpu_intersect(const GpuBvh& bvh, const std::vector<Ray>& rays) {
  DeviceArray<Ray> d_rays = upload_rays(rays);
  DeviceArray<Hit> d_hits(rays.size());
  launch_intersect(bvh.impl().view(), d_rays.view(), d_hits.view());
  return d_hits.download();
}

std::vector<uint8_t> gpu_occluded(const GpuBvh& bvh, const std::vector<Ray>& rays) {
  DeviceArray<Ray> d_rays = upload_rays(rays);
  DeviceArray<uint8_t> d_out(rays.size());
  launch_occluded(bvh.impl().view(), d_rays.view(), d_out.view());
  return d_out.download();
}

TraceRate gpu_trace_rate(const GpuBvh& bvh, const std::vector<Ray>& rays, bool shadow,
                         int repeats) {
  DeviceArray<Ray> d_rays = upload_rays(rays);
  DeviceArray<Hit> d_hits(shadow ? 0 : rays.size());
  DeviceArray<uint8_t> d_out(shadow ? rays.size() : 0);
  auto launch = [&] {
    if (shadow)
      launch_occluded(bvh.impl().view(), d_rays.view(), d_out.view());
    else
      launch_intersect(bvh.impl().view(), d_rays.view(), d_hits.view());
  };
  launch();  // warm-up: caches, clocks, the module's first load
  check(cudaDeviceSynchronize(), "trace warm-up");
  std::vector<double> rates;
  EventTimer timer;
  for (int k = 0; k < std::max(1, repeats); ++k) {
    timer.start();
    launch();
    float ms = timer.stop_ms();
    rates.push_back(double(rays.size()) / (double(ms) * 1e-3));
  }
  std::sort(rates.begin(), rates.end());
  TraceRate r;
  r.rays_per_second = rates[rates.size() / 2];
  r.min_rays_per_second = rates.front();
  r.max_rays_per_second = rates.back();
  r.device_bytes = d_rays.bytes() + d_hits.bytes() + d_out.bytes();
  return r;
}

}  // namespace rll::cuda
