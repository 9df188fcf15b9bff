// RLL's per-cell state: a cut of K <= M nodes of the light tree (clusters whose light ranges
// partition all lights, stored sorted as node ids and range ends), the learnt value Q of each
// cluster, a defensive prior per cluster, the sampling CDF frozen during a pass, and the
// reward accumulators of the pass. All of it is flat arrays indexed by cell * M + k
// (structure of arrays, nothing allocated per sample).
#pragma once

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

#include "rll/learn/cell_grid.h"
#include "rll/lights/light_tree.h"

namespace rll {

// How Q follows the rewards. Exponential: the paper's Q := (1-a) Q + a r per reward. Shrinkage:
// a mean of the rewards and of the prior estimate counted as `prior_samples` rewards, over at
// most the last ~1/a rewards; an occluded cluster's Q then halves after prior_samples zero
// rewards instead of after ~0.7/a of them.
enum class LearningRule { Shrinkage, Exponential };

// How a cluster's prior weight and a split's share of Q are estimated: from the light tree's
// importance of the node at the cell's anchor (spatial, visibility-blind), or from the node's
// power alone (the paper).
enum class ClusterWeight { Importance, Power };

struct CutSettings {
  int cut_size = 128;      // M
  float alpha = 0.02f;     // per-sample learning rate of Q
  float threshold = 2;     // T: split l_max and collapse p_min if Q(l_max) > T Q(p_min)
  int splits = 4;          // split-collapse steps per cell and pass
  float epsilon = 0.1f;    // weight of the defensive prior in the cluster CDF
  ClusterWeight prior = ClusterWeight::Importance;
  // True: the CDF is (1-eps) Q/sum Q + eps prior (the defensive prior per cell). False: the CDF
  // holds the learnt distribution alone, the sampler mixing in its own defensive term.
  bool prior_in_cdf = false;
  LearningRule rule = LearningRule::Shrinkage;
  float prior_samples = 4;  // n0 of the shrinkage rule
  // Rewards a cell must have seen before its learnt distribution gets half the weight the
  // defensive term does not take: the cell's defensive weight is
  // eps + (1 - eps) * trust / (trust + rewards seen).
  float trust = 256;
  ClusterWeight split = ClusterWeight::Importance;
};

// A cut being edited (split-collapse), outside the flat store.
struct Cut {
  std::vector<uint32_t> nodes;  // tree nodes sorted by range
  std::vector<float> q;         // learnt value; < 0: never visited (the prior estimate applies)
  std::vector<float> n;         // shrinkage rule: rewards (and prior) behind q
  std::vector<float> weight;    // prior weight of each cluster (importance or power)
};

// The shared initial cut: breadth-first refinement of the tree, always splitting the node with
// the most lights, until M nodes (or every node is a leaf).
std::vector<uint32_t> initial_cut(const LightTree& tree, int cut_size);

// True if the nodes partition [0, light_count) into contiguous ranges in order.
bool is_valid_cut(const LightTree& tree, const std::vector<uint32_t>& nodes);

// Split-collapse on a cut (DESIGN 2), with `qe` the effective Q of every cluster (the learnt
// value, or for a cluster never visited its prior share of the cell's total), kept in step.
class SplitCollapse {
 public:
  SplitCollapse(const LightTree& tree, int max_size, float threshold) : m_tree(tree), m_max(max_size), m_t(threshold) {}
  // One step: returns 1 for a split with a collapse, 2 for a pure split (K < M), 0 if nothing
  // changed. `weight_of(node)` is the prior weight of a node entering the cut; `share_of(node)`
  // splits a cluster's Q between its children.
  template <typename WeightOf, typename ShareOf>
  int step(Cut& cut, std::vector<float>& qe, const WeightOf& weight_of, const ShareOf& share_of) const;

 private:
  const LightTree& m_tree;
  int m_max;
  float m_t;
};

template <typename WeightOf, typename ShareOf>
inline int SplitCollapse::step(Cut& cut, std::vector<float>& qe, const WeightOf& weight_of, const ShareOf& share_of) const {
  const size_t K = cut.nodes.size();
  // l_max: the splittable cluster (more than one light) with the largest Q.
  long best = -1;
  for (size_t k = 0; k < K; ++k)
    if (!m_tree.node(cut.nodes[k]).is_leaf() && (best < 0 || qe[k] > qe[best])) best = long(k);
  if (best < 0) return 0;
  // p_min: among parents whose two children are both in the cut (the minimum of Q over all
  // nodes above the cut is always attained at such a parent), the one with the smallest Q,
  // not the parent of l_max.
  long pmin = -1;
  if (int(K) >= m_max) {
    for (size_t k = 0; k + 1 < K; ++k) {
      if (long(k) == best || long(k + 1) == best) continue;
      const LightTreeNode& a = m_tree.node(cut.nodes[k]);
      if (a.parent == LightTree::kNone || m_tree.node(a.parent).child != cut.nodes[k] ||
          cut.nodes[k + 1] != cut.nodes[k] + 1)
        continue;
      if (pmin < 0 || qe[k] + qe[k + 1] < qe[pmin] + qe[pmin + 1]) pmin = long(k);
    }
    if (pmin < 0 || !(qe[best] > m_t * (qe[pmin] + qe[pmin + 1]))) return 0;
    // Collapse: the parent replaces its two children, Q summed.
    uint32_t parent = m_tree.node(cut.nodes[pmin]).parent;
    bool unvisited = cut.q[pmin] < 0 && cut.q[pmin + 1] < 0;
    qe[pmin] += qe[pmin + 1];
    cut.q[pmin] = unvisited ? -1.0f : qe[pmin];
    cut.n[pmin] += cut.n[pmin + 1];
    cut.nodes[pmin] = parent;
    cut.weight[pmin] = weight_of(parent);
    cut.nodes.erase(cut.nodes.begin() + pmin + 1);
    cut.q.erase(cut.q.begin() + pmin + 1);
    cut.n.erase(cut.n.begin() + pmin + 1);
    cut.weight.erase(cut.weight.begin() + pmin + 1);
    qe.erase(qe.begin() + pmin + 1);
    if (best > pmin) --best;
  }
  // Split: l_max's two children replace it, Q shared in proportion to share_of.
  const LightTreeNode& nd = m_tree.node(cut.nodes[best]);
  float s0 = share_of(nd.child), s1 = share_of(nd.child + 1);
  float f0 = s0 + s1 > 0 ? s0 / (s0 + s1) : 0.5f;
  float q = cut.q[best], e = qe[best];
  // The split of Q is a guess: each child keeps half the evidence behind it.
  float n = 0.5f * cut.n[best];
  cut.nodes[best] = nd.child;
  cut.n[best] = n;
  cut.n.insert(cut.n.begin() + best + 1, n);
  cut.q[best] = q >= 0 ? q * f0 : -1.0f;
  qe[best] = e * f0;
  cut.weight[best] = weight_of(nd.child);
  cut.nodes.insert(cut.nodes.begin() + best + 1, nd.child + 1);
  cut.q.insert(cut.q.begin() + best + 1, q >= 0 ? q * (1 - f0) : -1.0f);
  qe.insert(qe.begin() + best + 1, e * (1 - f0));
  cut.weight.insert(cut.weight.begin() + best + 1, weight_of(nd.child + 1));
  return pmin < 0 ? 2 : 1;
}

class CutStore {
 public:
  CutStore(const LightTree& tree, uint32_t cells, const CutSettings& settings, double reward_scale);

  const CutSettings& settings() const { return m_s; }
  int max_size() const { return m_m; }

  // The shared initial cut: the clusters of cells that have no cut of their own yet.
  uint32_t initial_size() const { return uint32_t(m_initial.size()); }
  const uint32_t* initial_ends() const { return m_initial_ends.data(); }
  const uint32_t* initial_nodes() const { return m_initial.data(); }

  bool active(uint32_t cell) const { return m_size[cell] > 0; }
  uint32_t size(uint32_t cell) const { return m_size[cell]; }
  const uint32_t* ends(uint32_t cell) const { return &m_end[size_t(cell) * m_m]; }
  const uint32_t* nodes(uint32_t cell) const { return &m_node[size_t(cell) * m_m]; }
  const float* cdf(uint32_t cell) const { return &m_cdf[size_t(cell) * m_m]; }
  const float* q(uint32_t cell) const { return &m_q[size_t(cell) * m_m]; }
  // False while the cell has learnt nothing (every Q zero): its CDF is then the prior's.
  bool learnt(uint32_t cell) const { return m_learnt[cell] != 0; }
  // The weight of the defensive term for this cell during this pass (1 before it learnt).
  float defensive_weight(uint32_t cell) const { return m_eps[cell]; }

  // Called when a cell is created, from any thread: its anchor for prior weights.
  void set_anchor(uint32_t cell, const CellAnchor& a) { m_anchor[cell] = a; }

  // Adds one reward to cluster k of `cell`; `weighted` is the sample's contribution divided by
  // its full pmf (an estimate of the cell's total). Thread-safe and never loses an update: sums
  // are fixed-point integers, so the result does not depend on the order of additions.
  void record(uint32_t cell, uint32_t k, float reward, float weighted);

  struct PassStats {
    uint32_t splits = 0, collapses = 0;
    bool touched = false;
  };
  // End of pass for one cell (cells are independent: call in parallel). A cell without a cut
  // gets the initial one; rewards are folded into Q, split-collapse runs, the CDF is rebuilt.
  // `parent`: a coarser cell around this one whose learnt state a new cell starts from (kNone:
  // the initial cut with the prior).
  PassStats end_pass(uint32_t cell, uint32_t parent = ~0u);
  const CellAnchor& anchor(uint32_t cell) const { return m_anchor[cell]; }
  // Light powers or positions changed: recompute prior weights and the CDF of a cell.
  void refresh(uint32_t cell);
  // Forgets a cell (eviction).
  void clear(uint32_t cell);
  // Gives a cell a cut with known values (the oracle): prior weights from the cell's anchor.
  void assign(uint32_t cell, const std::vector<uint32_t>& nodes, const std::vector<float>& q);

  size_t bytes() const;

 private:
  void load(uint32_t cell, Cut& cut) const;
  void store(uint32_t cell, const Cut& cut);
  float weight_of(uint32_t cell, uint32_t node) const;
  // The normalized prior of every cluster: mostly weight, with a floor proportional to power.
  void prior(const Cut& cut, std::vector<double>& out) const;
  double power_floor() const;

  const LightTree& m_tree;
  CutSettings m_s;
  int m_m;
  double m_scale;     // fixed point: reward units per integer step
  double m_log_keep;  // log(1 - alpha)

  std::vector<uint32_t> m_initial, m_initial_ends;

  std::vector<uint32_t> m_size;  // K per cell; 0: no cut yet
  std::vector<uint32_t> m_node, m_end;
  std::vector<float> m_q, m_n, m_weight, m_cdf;
  std::vector<uint8_t> m_learnt;  // per cell: sum of Q > 0
  std::vector<float> m_seen;      // per cell: rewards received so far
  std::vector<float> m_eps;       // per cell: defensive weight, frozen during a pass
  std::vector<float> m_total;  // per cell: learnt estimate of the total contribution (< 0: none)
  std::vector<CellAnchor> m_anchor;
  std::unique_ptr<std::atomic<int64_t>[]> m_sum;       // per cluster: fixed-point reward sum
  std::unique_ptr<std::atomic<uint32_t>[]> m_count;    // per cluster: rewards this pass
  std::unique_ptr<std::atomic<int64_t>[]> m_cell_sum;  // per cell: fixed-point weighted sum
};

}  // namespace rll
