// A light sampler's view with its arrays in device memory (nvcc only): what the GPU wavefront and
// the GPU checks hand to the samplers' device functions.
#pragma once

#include "rll/cuda/device_scene.cuh"
#include "rll/lights/rll_view.h"
#include "rll/lights/sampler_view.h"

namespace rll::cuda {

// A light tree's arrays in device memory.
inline LightTreeView mirror_tree(DeviceMirror& m, const LightTreeView& t) {
  LightTreeView d = t;
  d.nodes = m.mirror(t.nodes);
  d.steps = m.mirror(t.steps);
  d.leaf_of = m.mirror(t.leaf_of);
  return d;
}

// A light sampler's view with its arrays in device memory; what the kernels write (RLL's cell
// table, point sums, rewards) copied back to the sampler's own arrays on demand.
class DeviceSampler {
 public:
  void upload(const SamplerView& h) {
    m_memory.clear();
    m_view = h;
    switch (h.kind) {
      case SamplerKind::Power:
        m_view.power.pmf = m_memory.mirror(h.power.pmf);
        m_view.power.cdf = m_memory.mirror(h.power.cdf);
        m_view.power.guide = m_memory.mirror(h.power.guide);
        break;
      case SamplerKind::Tree:
        m_view.tree = mirror_tree(m_memory, h.tree);
        break;
      case SamplerKind::Rht:
        m_view.rht.tree = mirror_tree(m_memory, h.rht.tree);
        break;
      case SamplerKind::Rll: {
        RllView r = *h.rll;
        r.tree = mirror_tree(m_memory, r.tree);
        r.table.slots = m_memory.mirror(r.table.slots);
        r.table.key_of = m_memory.mirror(r.table.key_of);
        r.table.free = m_memory.mirror(r.table.free);
        r.table.next_free = m_memory.mirror_one(r.table.next_free);
        r.table.failed = m_memory.mirror_one(r.table.failed);
        CutStoreView& c = r.cuts;
        c.size = m_memory.mirror(c.size);
        c.node = m_memory.mirror(c.node);
        c.end = m_memory.mirror(c.end);
        c.cdf = m_memory.mirror(c.cdf);
        c.gl = m_memory.mirror(c.gl);
        c.gr = m_memory.mirror(c.gr);
        c.vis = m_memory.mirror(c.vis);
        c.eps = m_memory.mirror(c.eps);
        c.initial = m_memory.mirror(c.initial);
        c.initial_ends = m_memory.mirror(c.initial_ends);
        c.anchor = m_memory.mirror(c.anchor);
        c.inv_unit = m_memory.mirror(c.inv_unit);
        c.sum = m_memory.mirror(c.sum);
        c.sq = m_memory.mirror(c.sq);
        c.count = m_memory.mirror(c.count);
        c.up = m_memory.mirror(c.up);
        c.up_count = m_memory.mirror(c.up_count);
        c.refined = m_memory.mirror(c.refined);
        r.last_used = m_memory.mirror(r.last_used);
        r.points = m_memory.mirror(r.points);
        r.power_prefix = m_memory.mirror(r.power_prefix);
        m_view.rll = m_memory.mirror(View<const RllView>{&r, 1}).data;
        break;
      }
      case SamplerKind::Uniform:
      case SamplerKind::Host:  // (refused before: require_device_version)
      case SamplerKind::None:
        break;
    }
  }
  void copy_back() const { m_memory.copy_back(); }
  const SamplerView& view() const { return m_view; }
  size_t bytes() const { return m_memory.bytes(); }

 private:
  DeviceMirror m_memory;
  SamplerView m_view;
};

}  // namespace rll::cuda
