// The GPU side of the checks that RLL's end of pass is device code (issue 31): the device
// instantiates cut_end_pass (fold, values, split-collapse, bake, guided factors) and the whole
// end of pass over the CUDA backend (rll_end_pass: anchors, pooling with CUB's sort, eviction,
// the table's rebuild), run over device copies of the host's arrays.
#include <vector>

#include "rll/cuda/backend.cuh"
#include "rll/cuda/device_rll.cuh"
#include "rll/cuda/device_scene.cuh"
#include "rll/cuda/endpass_check.h"
#include "rll/cuda/launch.cuh"

namespace rll {

namespace {

// A CutStoreEndView with its arrays mirrored in `d` (the writable ones copied back by
// d.copy_back()).
CutStoreEndView mirror_end_view(cuda::DeviceMirror& d, const CutStoreEndView& v) {
  CutStoreEndView e = v;
  e.tree.nodes = d.mirror(v.tree.nodes);
  e.tree.steps = d.mirror(v.tree.steps);
  e.tree.leaf_of = d.mirror(v.tree.leaf_of);
  e.initial = d.mirror(v.initial);
  e.initial_ends = d.mirror(v.initial_ends);
  e.size = d.mirror(v.size);
  e.node = d.mirror(v.node);
  e.end = d.mirror(v.end);
  e.q = d.mirror(v.q);
  e.m2 = d.mirror(v.m2);
  e.n = d.mirror(v.n);
  e.weight = d.mirror(v.weight);
  e.cdf = d.mirror(v.cdf);
  e.gl = d.mirror(v.gl);
  e.gr = d.mirror(v.gr);
  e.vis = d.mirror(v.vis);
  e.learnt = d.mirror(v.learnt);
  e.seen = d.mirror(v.seen);
  e.eps = d.mirror(v.eps);
  e.anchor = d.mirror(v.anchor);
  e.pool = d.mirror(v.pool);
  e.has_pool = d.mirror(v.has_pool);
  e.inv_unit = d.mirror(v.inv_unit);
  e.sum = d.mirror(v.sum);
  e.sq = d.mirror(v.sq);
  e.count = d.mirror(v.count);
  e.up = d.mirror(v.up);
  e.up_count = d.mirror(v.up_count);
  e.refined = d.mirror(v.refined);
  return e;
}

template <typename T>
cuda::DeviceArray<T> to_device(const std::vector<T>& v) {
  cuda::DeviceArray<T> a(v.size());
  a.upload(v);
  return a;
}

template <typename T>
HostBuffer<T> to_host(const cuda::DeviceArray<T>& a) {
  HostBuffer<T> h(a.size());
  a.download(h.data());
  return h;
}

}  // namespace

std::vector<CutPassStats> cut_end_pass_gpu(const CutStoreEndView& v,
                                           const std::vector<uint32_t>& cells) {
  cuda::DeviceMirror d;
  const CutStoreEndView e = mirror_end_view(d, v);
  // Each cell's scratch, its slice of one arena at a scan of the rooms (taken on the host, from
  // the host's arrays, which hold what the device's do).
  std::vector<uint64_t> at(cells.size() + 1, 0);
  for (size_t i = 0; i < cells.size(); ++i) at[i + 1] = at[i] + cut_scratch_room(v, cells[i]);
  cuda::DeviceArray<double> scratch_d(at.back() * CutScratchArena::kDoubles);
  cuda::DeviceArray<float> scratch_f(at.back() * CutScratchArena::kFloats);
  const CutScratchArena arena{scratch_d.view(), scratch_f.view()};
  const cuda::DeviceArray<uint64_t> d_at = to_device(at);
  const cuda::DeviceArray<uint32_t> d_cells = to_device(cells);
  cuda::DeviceArray<CutPassStats> d_stats(cells.size());
  const View<const uint32_t> in = d_cells.view();
  const View<const uint64_t> offset = d_at.view();
  const View<CutPassStats> out = d_stats.view();
  cuda::parallel_for(cells.size(), [=] RLL_HD(size_t i) {
    out[i] = cut_end_pass(e, in[i], arena.slice(offset[i], uint32_t(offset[i + 1] - offset[i])));
  });
  std::vector<CutPassStats> stats = d_stats.download();
  d.copy_back();
  return stats;
}

RllPassCounts rll_end_pass_gpu(const RllLearnView& v, RllPoolState<HostBackend>& pool,
                               uint32_t used_before, bool reset) {
  cuda::DeviceMirror d;
  RllLearnView e = v;
  e.cuts = mirror_end_view(d, v.cuts);
  e.table.slots = d.mirror(v.table.slots);
  e.table.key_of = d.mirror(v.table.key_of);
  e.table.free = {};  // (the rebuild writes free_room; a pass's inserts read free)
  e.table.next_free = d.mirror_one(v.table.next_free);
  e.table.failed = d.mirror_one(v.table.failed);
  e.free_room = d.mirror(v.free_room);
  e.last_used = d.mirror(v.last_used);
  e.points = d.mirror(v.points);
  RllPoolState<cuda::CudaBackend> device_pool{to_device<uint64_t>(pool.keys),
                                              to_device<float>(pool.q), to_device<float>(pool.m2),
                                              to_device<float>(pool.n)};
  RllScratch<cuda::CudaBackend> scratch;
  const RllPassCounts counts =
      rll_end_pass(cuda::CudaBackend{}, e, device_pool, scratch, used_before, reset);
  d.copy_back();
  pool.keys = to_host(device_pool.keys);
  pool.q = to_host(device_pool.q);
  pool.m2 = to_host(device_pool.m2);
  pool.n = to_host(device_pool.n);
  return counts;
}

void rll_end_pass_resident_gpu(RllLightSampler& s) {
  cuda::DeviceRll state(s);
  s.end_pass();
  s.sync();
}

void rll_lights_changed_resident_gpu(RllLightSampler& s, const Scene& scene) {
  cuda::DeviceRll state(s);
  s.lights_changed(scene);
  s.sync();
}

}  // namespace rll
