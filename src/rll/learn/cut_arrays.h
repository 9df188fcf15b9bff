// The cut arrays that the learners of cuts share (rll's CutStore, ltc): per cell, a cut of at most
// m nodes of the light tree (clusters whose light ranges partition all lights, stored sorted as
// node ids and range ends) and its baked sampling CDF, flat at cell * m + k; and one initial cut
// for the cells that have none yet. What a cell learns and how it bakes its CDF is the learner's
// own; drawing a cluster from the table reads only these (lights/rll_view.h, DESIGN 6).
#pragma once

#include <cstdint>
#include <vector>

#include "rll/core/device.h"
#include "rll/lighttree/light_tree.h"

namespace rll {

// The arrays as flat views: const for the draws (CutArraysView), writable for an end of pass that
// runs over views (CutArraysRwView, learn/cut_end_pass.h).
template <typename U, typename F>
struct CutArraysViewOf {
  uint32_t m = 0;  // clusters per cell at most: the stride of the per-cluster arrays
  View<const uint32_t> initial, initial_ends;  // the initial cut: nodes and range ends
  View<U> size;                                // K per cell; 0: no cut yet
  View<U> node, end;
  View<F> cdf;

  RLL_HD bool active(uint32_t cell) const { return size[cell] > 0; }
  RLL_HD size_t base(uint32_t cell) const { return size_t(cell) * m; }
};
using CutArraysView = CutArraysViewOf<const uint32_t, const float>;
using CutArraysRwView = CutArraysViewOf<uint32_t, float>;

// The arrays themselves (a plain struct: each learner keeps them consistent, ends[k] the end of
// node[k]'s light range, as its end of pass writes them).
struct CutArrays {
  uint32_t m = 0;
  std::vector<uint32_t> initial, initial_ends;
  std::vector<uint32_t> size;
  std::vector<uint32_t> node, end;
  std::vector<float> cdf;

  CutArrays() = default;
  // `cells` cells without a cut, of at most `m` clusters each, and the given initial cut.
  CutArrays(const LightTree& tree, uint32_t cells, uint32_t m_, std::vector<uint32_t> initial_)
      : m(m_), initial(std::move(initial_)) {
    for (uint32_t n : initial) initial_ends.push_back(tree.node(n).end);
    const size_t n = size_t(cells) * m;
    size.assign(cells, 0);
    node.assign(n, 0);
    end.assign(n, 0);
    cdf.assign(n, 0.0f);
  }
  uint32_t cells() const { return uint32_t(size.size()); }
  bool active(uint32_t cell) const { return size[cell] > 0; }
  size_t base(uint32_t cell) const { return size_t(cell) * m; }
  const uint32_t* nodes(uint32_t cell) const { return &node[base(cell)]; }
  const uint32_t* ends(uint32_t cell) const { return &end[base(cell)]; }
  const float* cdf_of(uint32_t cell) const { return &cdf[base(cell)]; }

  CutArraysRwView rw_view() { return views_of<CutArraysRwView>(*this); }
  CutArraysView view() const { return views_of<CutArraysView>(*this); }

 private:
  template <typename V, typename A>
  static V views_of(A& a) {
    return {a.m,
            view_of(a.initial),
            view_of(a.initial_ends),
            view_of(a.size),
            view_of(a.node),
            view_of(a.end),
            view_of(a.cdf)};
  }
};

}  // namespace rll
