// The GPU side of the check that the light samplers' dispatch is device code (issue 31): the
// device instantiates prepare_point, sample_light, light_pmf and record_nee for every SamplerKind,
// and a kernel runs sampler_probe over device copies of a SamplerView's arrays.
#include <memory>
#include <vector>

#include "rll/cuda/launch.cuh"
#include "rll/cuda/sampler_check.h"

namespace rll {

namespace {

// Device copies of a SamplerView's arrays (rll's included), and the view of them.
class DeviceSamplerView {
 public:
  explicit DeviceSamplerView(const SamplerView& s) : m_view(s) {
    m_view.power.pmf = copy(s.power.pmf);
    m_view.power.cdf = copy(s.power.cdf);
    m_view.power.guide = copy(s.power.guide);
    m_view.tree = copy(s.tree);
    if (s.kind == SamplerKind::Rll) {
      RllView r = *s.rll;
      r.tree = copy(r.tree);
      r.table.slots = copy(r.table.slots);
      r.table.key_of = copy(r.table.key_of);
      r.table.free = copy(r.table.free);
      r.table.next_free = copy(View<uint32_t>{r.table.next_free, 1}).data;
      r.table.failed = copy(View<uint64_t>{r.table.failed, 1}).data;
      CutStoreView& c = r.cuts;
      c.size = copy(c.size);
      c.node = copy(c.node);
      c.end = copy(c.end);
      c.cdf = copy(c.cdf);
      c.gl = copy(c.gl);
      c.gr = copy(c.gr);
      c.eps = copy(c.eps);
      c.initial = copy(c.initial);
      c.initial_ends = copy(c.initial_ends);
      c.anchor = copy(c.anchor);
      c.inv_unit = copy(c.inv_unit);
      c.sum = copy(c.sum);
      c.sq = copy(c.sq);
      c.count = copy(c.count);
      r.last_used = copy(r.last_used);
      r.points = copy(r.points);
      r.power_prefix = copy(r.power_prefix);
      m_view.rll = copy(View<const RllView>{&r, 1}).data;
    }
  }
  const SamplerView& view() const { return m_view; }

 private:
  // A device copy of a host array, kept until this object goes.
  template <typename T>
  View<T> copy(View<T> host) {
    using U = std::remove_const_t<T>;
    auto device = std::make_unique<cuda::DeviceArray<U>>(host.size);
    device->upload(host.data, host.size);
    View<U> v = device->view();
    m_arrays.push_back(std::shared_ptr<void>(
        device.release(), [](void* p) { delete static_cast<cuda::DeviceArray<U>*>(p); }));
    return {v.data, v.size};
  }
  LightTreeView copy(const LightTreeView& t) {
    LightTreeView d = t;
    d.nodes = copy(t.nodes);
    d.importance = copy(t.importance);
    d.leaf_of = copy(t.leaf_of);
    return d;
  }
  SamplerView m_view;
  std::vector<std::shared_ptr<void>> m_arrays;
};

}  // namespace

std::vector<SamplerProbeResult> sampler_probe_gpu(const SamplerView& s,
                                                  const std::vector<SamplerProbe>& probes) {
  const DeviceSamplerView d(s);
  cuda::DeviceArray<SamplerProbe> d_probes(probes.size());
  d_probes.upload(probes);
  cuda::DeviceArray<SamplerProbeResult> d_out(probes.size());
  const SamplerView view = d.view();
  const View<const SamplerProbe> in = d_probes.view();
  const View<SamplerProbeResult> out = d_out.view();
  cuda::parallel_for(probes.size(), [=] RLL_HD(size_t i) { out[i] = sampler_probe(view, in[i]); });
  return d_out.download();
}

}  // namespace rll
