// The GPU side of the check that RLL's end of pass is device code (issue 31): the device
// instantiates cut_end_pass (fold, values, split-collapse, bake, guided factors) and a kernel
// runs it over device copies of a CutStoreEndView's arrays.
#include <vector>

#include "rll/cuda/device_scene.cuh"
#include "rll/cuda/endpass_check.h"
#include "rll/cuda/launch.cuh"

namespace rll {

std::vector<CutPassStats> cut_end_pass_gpu(const CutStoreEndView& v,
                                           const std::vector<uint32_t>& cells) {
  cuda::DeviceMirror d;
  CutStoreEndView e = v;
  e.tree.nodes = d.mirror(v.tree.nodes);
  e.tree.importance = d.mirror(v.tree.importance);
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
  cuda::DeviceArray<uint32_t> d_cells(cells.size());
  d_cells.upload(cells);
  cuda::DeviceArray<CutPassStats> d_stats(cells.size());
  const View<const uint32_t> in = d_cells.view();
  const View<CutPassStats> out = d_stats.view();
  cuda::parallel_for(cells.size(), [=] RLL_HD(size_t i) { out[i] = cut_end_pass(e, in[i]); });
  std::vector<CutPassStats> stats = d_stats.download();
  d.copy_back();
  return stats;
}

}  // namespace rll
