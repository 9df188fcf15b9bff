// Binary search over a sorted range on either device (RLL_HD): std::lower_bound and
// std::upper_bound are host-only, so the kernels' searches (a light's cluster in a cut, a cluster
// in a cell's CDF, a light in a power prefix, where an inner node's children meet in a cut, a
// coarse cell's key) all run this one halving loop, on the CPU and the GPU alike.
#pragma once

#include "rll/core/device.h"

namespace rll {

// The first index i of [lo, hi) at which `past(a[i])` holds, `past` being false and then true
// along the range; hi if it never holds (std::partition_point with the test negated). The halving
// steps are std::lower_bound's, so that its result is theirs also where `past` is not monotone.
template <typename Index, typename T, typename Past>
RLL_HD inline Index first_past(const T* a, Index lo, Index hi, const Past& past) {
  Index n = hi - lo;
  while (n > 0) {
    const Index half = n / 2;
    if (!past(a[lo + half])) {
      lo += half + 1;
      n -= half + 1;
    } else {
      n = half;
    }
  }
  return lo;
}

// std::lower_bound over a[lo, hi): the first element not below x (hi if none).
template <typename Index, typename T, typename U>
RLL_HD inline Index lower_bound_index(const T* a, Index lo, Index hi, const U& x) {
  return first_past(a, lo, hi, [&](const T& e) { return !(e < x); });
}

// std::upper_bound over a[lo, hi): the first element above x (hi if none).
template <typename Index, typename T, typename U>
RLL_HD inline Index upper_bound_index(const T* a, Index lo, Index hi, const U& x) {
  return first_past(a, lo, hi, [&](const T& e) { return x < e; });
}

}  // namespace rll
