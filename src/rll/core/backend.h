// The primitives that whole-array work between passes is written over (DESIGN 6), so that one
// source runs on either device: a loop over [0, n), the same loop in index order, a stable sort
// of (key, value) pairs, an exclusive scan, a sum, and owned arrays with a scalar read. HostBackend
// is the CPU's (TBB loops and the standard library); rll/cuda/backend.cuh is the GPU's (CUDA
// launches and CUB). Code written over a backend takes it as a template parameter `B` and uses
// only these members; its loop bodies are RLL_HD lambdas capturing views by value.
#pragma once

#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

#include "rll/core/device.h"

namespace rll {

// An array a backend owns: on the host a std::vector (so that host code keeps its containers).
template <typename T>
struct HostBuffer : std::vector<T> {
  using std::vector<T>::vector;
  View<T> view() { return {this->data(), this->size()}; }
  View<const T> view() const { return {this->data(), this->size()}; }
};

struct HostBackend {
  template <typename T>
  using Buffer = HostBuffer<T>;

  // An array of n values, zero (value-initialized).
  template <typename T>
  Buffer<T> buffer(size_t n) const {
    return Buffer<T>(n);
  }
  // body(i) for every i in [0, n), in parallel (the iterations must not depend on each other).
  template <typename Body>
  void parallel_for(size_t n, const Body& body) const {
    host_parallel_for(n, body);
  }
  // body(i) for every i in [0, n): in index order here, in parallel on the GPU. For work whose
  // result the order changes only in ways nobody can observe (CellTable's slots, whose layout
  // the order of inserts moves but whose lookups it does not change), so that the CPU keeps one
  // exact layout for a seed.
  template <typename Body>
  void ordered_for(size_t n, const Body& body) const {
    for (size_t i = 0; i < n; ++i) body(i);
  }
  // Sorts values by keys, stably (equal keys keep their order); both of one length.
  void sort_pairs(View<uint64_t> keys, View<uint32_t> values) const {
    std::vector<std::pair<uint64_t, uint32_t>> p(keys.size);
    for (size_t i = 0; i < keys.size; ++i) p[i] = {keys[i], values[i]};
    std::stable_sort(p.begin(), p.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    for (size_t i = 0; i < keys.size; ++i) {
      keys[i] = p[i].first;
      values[i] = p[i].second;
    }
  }
  // out[i] = in[0] + ... + in[i - 1] (out as long as in); returns the sum of all of in.
  uint64_t exclusive_scan(View<const uint32_t> in, View<uint64_t> out) const {
    uint64_t acc = 0;
    for (size_t i = 0; i < in.size; ++i) {
      out[i] = acc;
      acc += in[i];
    }
    return acc;
  }
  // The sum of the values (exact: integers).
  uint64_t sum(View<const uint32_t> in) const {
    uint64_t acc = 0;
    for (uint32_t x : in) acc += x;
    return acc;
  }
  // A value in the backend's memory, read on the host.
  template <typename T>
  T read(const T* p) const {
    return *p;
  }
};

// The indices i in [0, n) where pred(i) holds, ascending, written to out[0, count) (out at least
// n long when every index may be chosen); returns count. pred is an RLL_HD callable.
template <typename B, typename Pred>
uint32_t select_into(const B& b, size_t n, const Pred& pred, View<uint32_t> out) {
  auto flags = b.template buffer<uint32_t>(n);
  auto at = b.template buffer<uint64_t>(n);
  const View<uint32_t> f = flags.view();
  const View<uint64_t> a = at.view();
  b.parallel_for(n, [=] RLL_HD(size_t i) { f[i] = pred(i) ? 1u : 0u; });
  const uint64_t count = b.exclusive_scan(f, a);
  b.parallel_for(n, [=] RLL_HD(size_t i) {
    if (f[i]) out[a[i]] = uint32_t(i);
  });
  return uint32_t(count);
}

// The same into an array of their own.
template <typename B, typename Pred>
typename B::template Buffer<uint32_t> select_indices(const B& b, size_t n, const Pred& pred) {
  auto all = b.template buffer<uint32_t>(n);
  const uint32_t count = select_into(b, n, pred, all.view());
  auto out = b.template buffer<uint32_t>(count);
  const View<uint32_t> from = all.view(), to = out.view();
  b.parallel_for(count, [=] RLL_HD(size_t i) { to[i] = from[i]; });
  return out;
}

}  // namespace rll
