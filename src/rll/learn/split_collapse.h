// Split-collapse (DESIGN 2b point 4): a cut grows where its clusters' rewards vary most and
// shrinks where sibling clusters are darkest. The choice of the cluster to split and of the pair
// to collapse is written once here, for the learnt cuts (split_collapse_step, on either device)
// and for the oracle's cuts (lights/oracle_sampler.cpp), which re-estimates the children it
// splits instead of sharing its parent's values.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "rll/core/device.h"
#include "rll/learn/cut.h"
#include "rll/lighttree/light_tree.h"

namespace rll {

namespace detail {
// Array edits of a cut held in per-cluster arrays with room for one more entry.
template <typename T>
RLL_HD inline void erase_at(T* a, size_t size, size_t i) {
  for (size_t k = i; k + 1 < size; ++k) a[k] = a[k + 1];
}
template <typename T>
RLL_HD inline void insert_at(T* a, size_t size, size_t i, T v) {
  for (size_t k = size; k > i; --k) a[k] = a[k - 1];
  a[i] = v;
}
}  // namespace detail

// l_max: the splittable cluster (more than one light) of the cut's K with the largest score (ties:
// the first); -1 if every cluster is a leaf.
RLL_HD inline long split_choice(const LightTreeView& tree, size_t K, const uint32_t* nodes,
                                const float* score) {
  long best = -1;
  for (size_t k = 0; k < K; ++k)
    if (!tree.node(nodes[k]).is_leaf() && (best < 0 || score[k] > score[best])) best = long(k);
  return best;
}

// p_min: among parents whose two children are both in the cut (the minimum over all nodes above
// the cut is always attained at such a parent), the one with the smallest value, not the parent
// of l_max (`best`): the darkest sibling pair, as the index of its first child; -1 if none.
RLL_HD inline long collapse_choice(const LightTreeView& tree, size_t K, const uint32_t* nodes,
                                   const float* value, long best) {
  long pmin = -1;
  for (size_t k = 0; k + 1 < K; ++k) {
    if (long(k) == best || long(k + 1) == best) continue;
    const LightTreeNode& a = tree.node(nodes[k]);
    if (a.parent == LightTree::kNone || tree.node(a.parent).child != nodes[k] ||
        nodes[k + 1] != nodes[k] + 1)
      continue;
    if (pmin < 0 || value[k] + value[k + 1] < value[pmin] + value[pmin + 1]) pmin = long(k);
  }
  return pmin;
}

// One split-collapse step (DESIGN 2b point 4) on a cut of `size` clusters held in arrays with
// room for size + 1 (nodes, q, m2, n, weight as in Cut; value and score as SplitCollapse says):
// returns 1 for a split with a collapse, 2 for a pure split (size < max_size), 0 if nothing
// changed; `size` follows, and `split_at` (if given) the index of the split's first child.
// `weight_of(node)` is the prior weight of a node entering the cut; `share_of(node)` splits a
// cluster's values between its children.
template <typename WeightOf, typename ShareOf>
RLL_HD int split_collapse_step(const LightTreeView& tree, int max_size, float threshold,
                               uint32_t& size, uint32_t* nodes, float* q, float* m2, float* n,
                               float* weight, float* value, float* score, const WeightOf& weight_of,
                               const ShareOf& share_of, long* split_at = nullptr) {
  size_t K = size;
  long best = split_choice(tree, K, nodes, score);
  if (best < 0 || !(score[best] > 0)) return 0;
  long pmin = -1;
  if (int(K) >= max_size) {
    pmin = collapse_choice(tree, K, nodes, value, best);
    if (pmin < 0 || !(score[best] > threshold * (value[pmin] + value[pmin + 1]))) return 0;
    // Collapse: the parent replaces its two children. Values add; the second moment is the one
    // the parent has when its two halves are drawn in proportion to sqrt(M2):
    // sqrt(M2_parent) = sqrt(M2_a) + sqrt(M2_b).
    const uint32_t parent = tree.node(nodes[pmin]).parent;
    const size_t a = size_t(pmin), b = a + 1;
    const bool unvisited = q[a] < 0 && q[b] < 0;
    const float qa = std::max(q[a], 0.0f), qb = std::max(q[b], 0.0f);
    const float sa = std::sqrt(std::max(m2[a], 0.0f)), sb = std::sqrt(std::max(m2[b], 0.0f));
    value[a] += value[b];
    score[a] += score[b];
    q[a] = unvisited ? -1.0f : qa + qb;
    m2[a] = unvisited ? 0.0f : (sa + sb) * (sa + sb);
    n[a] += n[b];
    nodes[a] = parent;
    weight[a] = weight_of(parent);
    detail::erase_at(nodes, K, b);
    detail::erase_at(q, K, b);
    detail::erase_at(m2, K, b);
    detail::erase_at(n, K, b);
    detail::erase_at(weight, K, b);
    detail::erase_at(value, K, b);
    detail::erase_at(score, K, b);
    --K;
    if (best > pmin) --best;
  }
  // Split: l_max's two children replace it, values shared in proportion to share_of (a guess:
  // each child keeps half the evidence behind it; sqrt(M2) is shared like Q).
  const LightTreeNode& nd = tree.node(nodes[best]);
  const float s0 = share_of(nd.child), s1 = share_of(nd.child + 1);
  const float f0 = s0 + s1 > 0 ? s0 / (s0 + s1) : 0.5f, f1 = 1 - f0;
  const size_t i = size_t(best);
  if (split_at) *split_at = best;
  const float qi = q[i], m2i = m2[i], v = value[i], sc = score[i];
  const float ni = 0.5f * n[i];
  nodes[i] = nd.child;
  detail::insert_at(nodes, K, i + 1, nd.child + 1);
  q[i] = qi >= 0 ? qi * f0 : -1.0f;
  detail::insert_at(q, K, i + 1, qi >= 0 ? qi * f1 : -1.0f);
  m2[i] = m2i * f0 * f0;
  detail::insert_at(m2, K, i + 1, m2i * f1 * f1);
  n[i] = ni;
  detail::insert_at(n, K, i + 1, ni);
  weight[i] = weight_of(nd.child);
  detail::insert_at(weight, K, i + 1, weight_of(nd.child + 1));
  value[i] = v * f0;
  detail::insert_at(value, K, i + 1, v * f1);
  score[i] = sc * f0;
  detail::insert_at(score, K, i + 1, sc * f1);
  size = uint32_t(K + 1);
  return pmin < 0 ? 2 : 1;
}

// Split-collapse on a Cut being edited outside the store (split_collapse_step over its vectors).
// `value[k]` is the effective target value of cluster k (sqrt(M2) or Q, or for a cluster never
// visited its prior estimate): a collapsed pair gets the sum, a split shares it. `score[k]`
// chooses the cluster to split: its share of the cell's variance (the standard deviation of its
// reward) or its value. Both are kept in step.
class SplitCollapse {
 public:
  SplitCollapse(const LightTree& tree, int max_size, float threshold)
      : m_tree(tree), m_max(max_size), m_t(threshold) {}
  // One step, as split_collapse_step.
  template <typename WeightOf, typename ShareOf>
  int step(Cut& cut, std::vector<float>& value, std::vector<float>& score,
           const WeightOf& weight_of, const ShareOf& share_of, long* split_at = nullptr) const {
    uint32_t K = uint32_t(cut.nodes.size());
    auto resize = [&](size_t to) {
      for (auto* v : {&cut.q, &cut.m2, &cut.n, &cut.weight, &value, &score}) v->resize(to);
      cut.nodes.resize(to);
    };
    resize(K + 1);  // room for a split
    const int r = split_collapse_step(m_tree.view(), m_max, m_t, K, cut.nodes.data(), cut.q.data(),
                                      cut.m2.data(), cut.n.data(), cut.weight.data(), value.data(),
                                      score.data(), weight_of, share_of, split_at);
    resize(K);
    return r;
  }

 private:
  const LightTree& m_tree;
  int m_max;
  float m_t;
};

}  // namespace rll
