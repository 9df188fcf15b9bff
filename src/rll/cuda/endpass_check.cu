// The GPU side of the check that RLL's end of pass is device code (issue 31): the device
// instantiates cut_end_pass (fold, values, split-collapse, bake, guided factors) and a kernel
// runs it over device copies of a CutStoreEndView's arrays.
#include <functional>
#include <memory>
#include <vector>

#include "rll/cuda/endpass_check.h"
#include "rll/cuda/launch.cuh"

namespace rll {

namespace {

// Device copies of host arrays, kept until this object goes; the writable ones are copied back by
// copy_back.
class DeviceCopies {
 public:
  template <typename T>
  View<T> copy(View<T> host) {
    using U = std::remove_const_t<T>;
    auto device = std::make_shared<cuda::DeviceArray<U>>(host.size);
    device->upload(host.data, host.size);
    if constexpr (!std::is_const_v<T>)
      m_back.push_back([device, host] { device->download(host.data); });
    m_arrays.push_back(device);
    const View<U> v = device->view();
    return {v.data, v.size};
  }
  void copy_back() const {
    for (const auto& f : m_back) f();
  }

 private:
  std::vector<std::shared_ptr<void>> m_arrays;
  std::vector<std::function<void()>> m_back;
};

}  // namespace

std::vector<CutPassStats> cut_end_pass_gpu(const CutStoreEndView& v,
                                           const std::vector<uint32_t>& cells) {
  DeviceCopies d;
  CutStoreEndView e = v;
  e.tree.nodes = d.copy(v.tree.nodes);
  e.tree.importance = d.copy(v.tree.importance);
  e.tree.leaf_of = d.copy(v.tree.leaf_of);
  e.initial = d.copy(v.initial);
  e.initial_ends = d.copy(v.initial_ends);
  e.size = d.copy(v.size);
  e.node = d.copy(v.node);
  e.end = d.copy(v.end);
  e.q = d.copy(v.q);
  e.m2 = d.copy(v.m2);
  e.n = d.copy(v.n);
  e.weight = d.copy(v.weight);
  e.cdf = d.copy(v.cdf);
  e.gl = d.copy(v.gl);
  e.gr = d.copy(v.gr);
  e.learnt = d.copy(v.learnt);
  e.seen = d.copy(v.seen);
  e.eps = d.copy(v.eps);
  e.anchor = d.copy(v.anchor);
  e.pool = d.copy(v.pool);
  e.has_pool = d.copy(v.has_pool);
  e.inv_unit = d.copy(v.inv_unit);
  e.sum = d.copy(v.sum);
  e.sq = d.copy(v.sq);
  e.count = d.copy(v.count);
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
