// RLL's learning state resident in device memory (nvcc only, issue 31 item 4): the device's copy
// of a learner (lights/resident.h: rll and fermat while they learn), owned by the GPU renderer
// (cuda/wavefront.cu), which the render session owns. Every array of the learner's state (cell
// table, free list, last use, point sums, cuts with their values, tables, anchors and reward
// sums) uploaded once, the coarse cells of pooling and the end of pass's scratch kept there; the
// learner's end of pass runs there (rll_end_pass over the CUDA backend) and only its counters come
// back per pass. When the lights change (an animated scene's frames), the refit light tree and
// the light powers are copied into the device's arrays and the priors and tables are made anew
// there (rll_lights_changed). The learner is lent to it and pulls the arrays back when the host
// reads them (a saved state, --stats, Python, a CPU render); the copy hands them back when it
// goes first.
#pragma once

#include <cuda_runtime.h>

#include <unordered_map>

#include "rll/core/error.h"
#include "rll/cuda/backend.cuh"
#include "rll/cuda/device_scene.cuh"
#include "rll/lights/resident.h"
#include "rll/lights/rll_end_pass.h"

namespace rll::cuda {

class DeviceRll final : public DeviceCopy {
 public:
  // Uploads the learner's state (taken back first from any copy that holds it) and holds it.
  explicit DeviceRll(ResidentLearner& learner) {
    const ResidentState state = learner.resident_state();
    const RllView& h = *state.view;
    // The learning view first: its writable arrays are mirrored to be copied back; the sampling
    // view's arrays are the same host arrays and take the same device arrays.
    m_learn = state.learn;
    const RllLearnView host_learn = m_learn;
    CutStoreEndView& e = m_learn.cuts;
    e.tree.nodes = once(e.tree.nodes);
    e.tree.steps = once(e.tree.steps);
    e.tree.leaf_of = once(e.tree.leaf_of);
    e.initial = once(e.initial);
    e.initial_ends = once(e.initial_ends);
    e.size = once(e.size);
    e.node = once(e.node);
    e.end = once(e.end);
    e.q = once(e.q);
    e.m2 = once(e.m2);
    e.n = once(e.n);
    e.weight = once(e.weight);
    e.cdf = once(e.cdf);
    e.gl = once(e.gl);
    e.gr = once(e.gr);
    e.vis = once(e.vis);
    e.learnt = once(e.learnt);
    e.seen = once(e.seen);
    e.eps = once(e.eps);
    e.anchor = once(e.anchor);
    e.pool = once(e.pool);
    e.has_pool = once(e.has_pool);
    e.inv_unit = once(e.inv_unit);
    e.sum = once(e.sum);
    e.sq = once(e.sq);
    e.count = once(e.count);
    e.up = once(e.up);
    e.up_count = once(e.up_count);
    e.refined = once(e.refined);
    m_learn.table.slots = once(m_learn.table.slots);
    m_learn.table.key_of = once(m_learn.table.key_of);
    m_learn.free_room = once(m_learn.free_room);
    m_learn.table.free = {m_learn.free_room.data, host_learn.table.free.size};
    m_learn.table.next_free = once(View<uint32_t>{host_learn.table.next_free, 1}).data;
    m_learn.table.failed = once(View<uint64_t>{host_learn.table.failed, 1}).data;
    m_learn.last_used = once(m_learn.last_used);
    m_learn.points = once(m_learn.points);
    // The sampling view over the same device arrays.
    RllView& r = m_view;
    r = h;
    r.tree = e.tree;
    r.table = m_learn.table;
    CutStoreView& c = r.cuts;
    c.size = e.size;
    c.node = e.node;
    c.end = e.end;
    c.cdf = e.cdf;
    c.gl = e.gl;
    c.gr = e.gr;
    c.vis = e.vis;
    c.eps = e.eps;
    c.initial = e.initial;
    c.initial_ends = e.initial_ends;
    c.anchor = e.anchor;
    c.inv_unit = e.inv_unit;
    c.sum = e.sum;
    c.sq = e.sq;
    c.count = e.count;
    c.up = e.up;
    c.up_count = e.up_count;
    c.refined = e.refined;
    r.last_used = m_learn.last_used;
    r.points = m_learn.points;
    r.power_prefix = once(h.power_prefix);
    m_device_view = DeviceArray<RllView>(1);
    m_device_view.upload(&m_view, 1);
    const RllPoolState<HostBackend>& pool = *state.pool;
    m_pool = {upload(pool.keys), upload(pool.q), upload(pool.m2), upload(pool.n)};
    lend(learner);
  }
  // Hands the state back to the learner that holds it here.
  ~DeviceRll() {
    if (m_learner) m_learner->sync();
  }
  DeviceRll(const DeviceRll&) = delete;
  DeviceRll& operator=(const DeviceRll&) = delete;

  // Whether it holds `learner`'s state (not since the learner took it back).
  bool holds(const ResidentLearner& learner) const { return m_learner == &learner; }
  // The learner's state is here (made from it, or taken back by the host since and changed
  // there by nothing but what this copy still holds).
  void lend(ResidentLearner& learner) {
    learner.lend_to(*this);
    m_learner = &learner;
  }

  // The sampler's view with its arrays here.
  SamplerView sampler_view() const {
    SamplerView v;
    v.kind = SamplerKind::Rll;
    v.tree = m_view.tree;
    v.rll = m_device_view.view().data;
    v.prepares = v.learns = true;  // (a learning sampler's state: a frozen one is uploaded whole)
    return v;
  }

  // The lights moved or switched (the tree refit on the host, same shape): the tree's arrays and
  // the powers copied into the device's, every prior and table made anew there.
  void lights_changed(const LightTreeView& tree, View<const double> power_prefix) override {
    refill(m_learn.cuts.tree.nodes, tree.nodes);
    refill(m_learn.cuts.tree.steps, tree.steps);
    refill(m_learn.cuts.tree.leaf_of, tree.leaf_of);
    refill(m_view.power_prefix, power_prefix);
    rll_lights_changed(CudaBackend{}, m_learn, m_pool, m_scratch);
  }

  // The learner's end of pass here (it keeps its statistics and moves to the next pass, whose
  // pass number, jitter and free cells the sampling view then takes: view_changed).
  RllPassCounts end_pass(const RllLearnView& host, uint32_t used_before, bool reset) override {
    m_learn.keyer = host.keyer;  // this pass's
    return rll_end_pass(CudaBackend{}, m_learn, m_pool, m_scratch, used_before, reset);
  }
  void view_changed(const RllView& h) override {
    m_view.pass = h.pass;
    m_view.keyer = h.keyer;
    m_view.table.free.size = h.table.free.size;
    m_learn.table.free.size = h.table.free.size;
    m_device_view.upload(&m_view, 1);
  }

  // Copies every array back into the learner's host arrays, the coarse cells into `pool`.
  void pull(RllPoolState<HostBackend>& pool) override {
    m_learner = nullptr;
    m_memory.copy_back();
    pool.keys = download(m_pool.keys);
    pool.q = download(m_pool.q);
    pool.m2 = download(m_pool.m2);
    pool.n = download(m_pool.n);
  }

  void forget() override { m_learner = nullptr; }

  size_t bytes() const {
    return m_memory.bytes() + m_device_view.bytes() + m_scratch.bytes() + m_pool.keys.bytes() +
           m_pool.q.bytes() + m_pool.m2.bytes() + m_pool.n.bytes();
  }

 private:
  // A device copy of a host array, one per host array (writable ones copied back by pull).
  template <typename T>
  View<T> once(View<T> v) {
    if (v.size == 0) return {nullptr, 0};
    const void* key = v.data;
    if (const auto it = m_device_of.find(key); it != m_device_of.end())
      return {static_cast<T*>(it->second), v.size};
    const View<T> d = m_memory.mirror(v);
    m_device_of[key] = const_cast<std::remove_const_t<T>*>(d.data);
    return d;
  }
  // Copies a host array over the device array that mirrors one of its size.
  template <typename T>
  static void refill(View<const T> device, View<const T> host) {
    if (device.size != host.size)
      fail("rll: the light tree changed shape ({} entries, {} on the GPU): not a refit", host.size,
           device.size);
    if (host.size > 0)
      check(cudaMemcpy(const_cast<T*>(device.data), host.data, host.size * sizeof(T),
                       cudaMemcpyHostToDevice),
            "cudaMemcpy");
  }
  template <typename T>
  static DeviceArray<T> upload(const HostBuffer<T>& h) {
    DeviceArray<T> d(h.size());
    d.upload(h);
    return d;
  }
  template <typename T>
  static HostBuffer<T> download(const DeviceArray<T>& d) {
    HostBuffer<T> h(d.size());
    d.download(h.data());
    return h;
  }

  DeviceMirror m_memory;
  std::unordered_map<const void*, void*> m_device_of;
  RllLearnView m_learn;  // the end of pass's view, over device arrays
  RllView m_view;        // the sampling view, over the same arrays (a host copy of the struct)
  DeviceArray<RllView> m_device_view;
  RllPoolState<CudaBackend> m_pool;
  RllScratch<CudaBackend> m_scratch;
  ResidentLearner* m_learner = nullptr;  // whose state this is, until it takes it back
};

}  // namespace rll::cuda
