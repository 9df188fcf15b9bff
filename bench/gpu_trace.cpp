// rll_gpu_trace: rays per second of rll's BVH on the GPU (cuda/trace.cu) at 1920x1080, for
// camera rays, one incoherent bounce of cosine-distributed rays from their hits, and shadow rays
// from those hits to random points on random lights; median of 5 timed launches each, the rays
// and the BVH uploaded once. Built-in scene names on the command line replace the default three.
// Exits 77 without a GPU.
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "rll/bvh/bvh.h"
#include "rll/bvh/rays.h"
#include "rll/bvh/traverse.h"
#include "rll/core/device.h"
#include "rll/core/parallel.h"
#include "rll/cuda/cuda.h"
#include "rll/cuda/trace.h"
#include "rll/scene/builtin.h"

using namespace rll;

namespace {

constexpr int kWidth = 1920, kHeight = 1080, kRepeats = 5;

void print_rate(const char* what, size_t rays, const cuda::TraceRate& r) {
  std::printf("  %-22s %9zu rays  %8.1f M rays/s  (min %.1f, max %.1f)\n", what, rays,
              r.rays_per_second * 1e-6, r.min_rays_per_second * 1e-6, r.max_rays_per_second * 1e-6);
}

void bench_scene(const std::string& name) {
  Scene scene = make_builtin_scene(name);
  scene.finalize();
  Bvh bvh = build_bvh(scene.mesh);
  cuda::GpuBvh gpu(bvh);
  std::printf(
      "%s: %zu triangles, BVH build %.3f s (host, %d threads), %zu nodes, depth %d, "
      "%.1f MB on the GPU\n",
      name.c_str(), scene.mesh.triangles.size(), bvh.build_seconds, hardware_threads(),
      bvh.nodes.size(), bvh.depth, double(gpu.bytes()) * 1e-6);
  std::vector<Ray> primary = camera_rays(scene, kWidth, kHeight, 1);
  // The primary hits on the CPU, through the same traversal (the unit tests check this path).
  std::vector<Hit> hits(primary.size());
  BvhView view = bvh.view();
  host_parallel_for(primary.size(), [&](size_t i) { intersect(view, primary[i], hits[i]); });
  std::vector<Ray> bounce = bounce_rays(scene.mesh, primary, hits, 2);
  std::vector<Ray> shadow = shadow_rays(scene, hits, 3);
  print_rate("camera closest", primary.size(), cuda::gpu_trace_rate(gpu, primary, false, kRepeats));
  print_rate("bounce closest", bounce.size(), cuda::gpu_trace_rate(gpu, bounce, false, kRepeats));
  print_rate("bounce any hit", bounce.size(), cuda::gpu_trace_rate(gpu, bounce, true, kRepeats));
  print_rate("shadow", shadow.size(), cuda::gpu_trace_rate(gpu, shadow, true, kRepeats));
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  try {
    std::vector<cuda::GpuInfo> gpus = cuda::gpus();
    if (gpus.empty()) {
      std::printf("rll_gpu_trace: no GPU (or rll built without CUDA): skipped\n");
      return 77;
    }
    std::printf("device: %s (sm_%d%d, %d SMs, %.1f GB)\n", gpus[0].name.c_str(), gpus[0].sm_major,
                gpus[0].sm_minor, gpus[0].multiprocessors, double(gpus[0].memory_bytes) * 1e-9);
    std::vector<std::string> scenes(argv + 1, argv + argc);
    if (scenes.empty()) scenes = {"cornell-boxes-room", "arch-interior", "many-lights-open"};
    for (const std::string& name : scenes) bench_scene(name);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rll_gpu_trace: %s\n", e.what());
    return 1;
  }
  return 0;
}
