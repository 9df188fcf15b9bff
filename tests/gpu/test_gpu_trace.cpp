// rll's BVH traced by the GPU kernels (cuda/trace.cu) against the same traversal on the CPU:
// the same closest hits and occlusion verdicts on a million rays per scene.
#include <gtest/gtest.h>

#include <cstdio>

#include "rll/bvh/bvh.h"
#include "rll/bvh/rays.h"
#include "rll/bvh/traverse.h"
#include "rll/core/device.h"
#include "rll/cuda/cuda.h"
#include "rll/cuda/trace.h"
#include "rll/scene/builtin.h"

using namespace rll;

namespace {

// The GPU contracts multiply-adds into FMAs, the host does not: a ray through an edge may pick
// the neighbouring triangle, or graze past, on one of them. At most this share may differ.
constexpr double kMaxDisagreement = 1e-4;

class GpuTrace : public testing::TestWithParam<std::string> {};

TEST_P(GpuTrace, AgreesWithTheCpuTraversal) {
  if (cuda::gpus().empty()) GTEST_SKIP() << "no GPU";
  Scene scene = make_builtin_scene(GetParam());
  scene.finalize();
  Bvh bvh = build_bvh(scene.mesh);
  std::vector<Ray> rays = test_rays(scene, 1'000'000, 5);
  size_t n = rays.size();
  std::vector<Hit> cpu_hits(n);
  std::vector<uint8_t> cpu_occluded(n);
  BvhView view = bvh.view();
  host_parallel_for(n, [&](size_t i) {
    intersect(view, rays[i], cpu_hits[i]);
    cpu_occluded[i] = occluded(view, rays[i]);
  });
  cuda::GpuBvh gpu(bvh);
  std::vector<Hit> gpu_hits = cuda::gpu_intersect(gpu, rays);
  std::vector<uint8_t> gpu_occ = cuda::gpu_occluded(gpu, rays);
  ASSERT_EQ(gpu_hits.size(), n);
  ASSERT_EQ(gpu_occ.size(), n);
  size_t closest_differ = 0, occluded_differ = 0, same_triangle = 0, hits = 0;
  for (size_t i = 0; i < n; ++i) {
    const Hit &a = cpu_hits[i], &b = gpu_hits[i];
    bool a_hit = a.tri != ~0u;
    hits += a_hit;
    same_triangle += a_hit && a.tri == b.tri;
    closest_differ += !hits_agree(a, b);
    occluded_differ += cpu_occluded[i] != gpu_occ[i];
  }
  std::printf(
      "%s: %zu rays, %zu hit; closest differ %.2e (other triangle %.2e), occluded differ "
      "%.2e\n",
      GetParam().c_str(), n, hits, double(closest_differ) / double(n),
      double(hits - same_triangle) / double(n), double(occluded_differ) / double(n));
  EXPECT_GT(hits, n / 4);  // the comparison is not vacuous
  EXPECT_LE(double(closest_differ) / double(n), kMaxDisagreement);
  EXPECT_LE(double(occluded_differ) / double(n), kMaxDisagreement);
}

INSTANTIATE_TEST_SUITE_P(Scenes, GpuTrace,
                         testing::Values("cornell-boxes-room", "arch-interior", "many-lights-open"),
                         [](const auto& info) {
                           std::string n = info.param;
                           for (char& c : n)
                             if (c == '-') c = '_';
                           return n;
                         });

}  // namespace
