// RLL's per-cell state: a cut of K <= M nodes of the light tree (clusters whose light ranges
// partition all lights, stored sorted as node ids and range ends), the learnt mean Q and second
// moment M2 of each cluster's reward, a prior weight per cluster, the sampling CDF baked at the
// end of each pass with the defensive prior folded in, and the reward accumulators of the pass.
// All of it is flat arrays indexed by cell * M + k (structure of arrays, nothing allocated per
// sample).
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "rll/core/binary_io.h"
#include "rll/learn/cell_grid.h"
#include "rll/lighttree/light_tree.h"

namespace rll {

// How Q and M2 follow the rewards. Shrinkage: the mean of the rewards and of the prior estimate
// counted as `prior_samples` rewards (a learning rate that starts at 1/n), forgetting as
// `Forgetting` says. Exponential: the paper's Q := (1-a) Q + a r per reward.
enum class LearningRule { Shrinkage, Exponential };

// How the shrinkage rule forgets (rll.forget). Changes: the mean of all of a cluster's rewards
// (the rate stays 1/n, so a static cell keeps sharpening), cut back to the last 1/alpha rewards
// where a pass's rewards fail the change test (change_test) and, for every cluster, when the
// lights change. Floor: the last 1/alpha rewards at most, for good (v2: the rate settles at the
// floor alpha).
enum class Forgetting { Changes, Floor };

// What a cell samples clusters in proportion to: sqrt(M2), the variance-optimal target of a
// one-sample estimator (DESIGN 2b), or the mean Q (the paper).
enum class LearnTarget { Moment, Mean };

// How a cluster's prior weight and a split's share of Q are estimated: from the light tree's
// importance of the node at the cell's anchor (spatial, visibility-blind), from the node's
// power alone, or equal for every cluster (Fermat's RLL: a uniform defensive term over the
// clusters, Q split half and half).
enum class ClusterWeight { Importance, Power, Uniform };

// The largest M (rll.cut_size) a CutStore accepts (the end of pass's scratch, CutScratch in
// learn/cut_end_pass.h, is sized by each cell's cut, not by this bound).
inline constexpr int kMaxCutSize = 4096;

struct CutSettings {
  int cut_size = 128;      // M, the most clusters of a cell (at most kMaxCutSize)
  int initial_size = 128;  // clusters of a new cell's cut (the shared initial cut), <= M
  // The shrinkage rule's memory after a change (forget=changes) or always (forget=floor): the
  // last 1/alpha rewards; the exponential rule's rate.
  float alpha = 0.02f;
  Forgetting forget = Forgetting::Changes;
  // The change test's threshold (forget=changes): a pass's mean of a cluster's rewards that
  // differs from the running mean by more than change_z standard errors is a change; 0: no test
  // (only a change of the lights forgets).
  float change_z = 5;
  float threshold = 2;     // T: split l_max and collapse p_min if score(l_max) > T value(p_min)
  int splits = 0;        // split-collapse steps per cell and pass (0: the cut stays as it started)
  float epsilon = 0.1f;  // weight of the defensive prior once a cell is trusted
  LearnTarget target = LearnTarget::Moment;
  ClusterWeight prior = ClusterWeight::Importance;
  // True: the CDF is (1-e) V/sum V + e prior (the defensive prior per cell, folded in). False:
  // the CDF holds the learnt distribution alone, the sampler mixing in its own defensive term.
  bool prior_in_cdf = true;
  LearningRule rule = LearningRule::Shrinkage;
  float prior_samples = 4;  // n0 of the shrinkage rule
  // Rewards a cell must have seen before its learnt distribution gets half the weight the
  // defensive term does not take: the cell's defensive weight is
  // e + (1 - e) * trust / (trust + rewards seen).
  float trust = 256;
  // Pooling (rll.pool=L, 0: off): every pass, the rewards of all cells whose anchors fall in
  // one cell L levels coarser are pooled, and that coarse cell learns Q and M2 of its own; a
  // cell's values are then shrunk toward the coarse cell's distribution (scaled to the cell's
  // own total) with the weight of `pool_weight` rewards per cluster, in place of the
  // visibility-blind prior for clusters the cell has not visited. Needs a cut shared by every
  // cell (splits = 0).
  int pool_levels = 0;  // (rll's default is 1: RllSettings)
  float pool_weight = 8;
  // What the coarse cell learns (rll.pool_guess): false (share), Q and M2 of the pooled
  // rewards, its distribution taken as the cell's; true (ratio), of the rewards divided by each
  // cell's own prior share of their cluster, so that the guess is the cell's prior times the
  // coarse cell's factor per cluster (visibility seen by the neighbours, the light's falloff
  // seen at the cell's own anchor).
  bool pool_ratio = false;
  // Pooling in two tiers (rll.pool_up=U, 0: off): a coarse cell's values are themselves shrunk,
  // by the same rule and weight, toward those of the cell U levels coarser still, which pools
  // every cell under it; where the first tier has few rewards of a cluster, the second speaks.
  int pool_up = 0;
  // Tiers of coarse cells: 0 without pooling, 2 with pool_up.
  int pool_tiers() const { return pool_levels > 0 ? 1 + (pool_up > 0) : 0; }
  ClusterWeight split = ClusterWeight::Importance;
  // The value of a cluster never visited: < 0, the visited clusters' estimate of the cell's total
  // shared by prior; >= 0, this constant (Fermat's RLL starts every Q at 0.01).
  float q_init = -1;
  // The guided descent (rll.sampling=guided): the values learnt are each cluster's ratio of its
  // reward to the light tree's importance of its node at the point, and the cell bakes, for
  // every inner node above its cut, the factors by which a descent from the root scales its
  // children's importances (guide_left/right) instead of a table over the clusters.
  bool guided = false;
};

// A cut being edited (split-collapse), outside the flat store.
struct Cut {
  std::vector<uint32_t> nodes;  // tree nodes sorted by range
  std::vector<float> q;         // learnt mean; < 0: never visited (the prior estimate applies)
  std::vector<float> m2;        // learnt second moment (meaningful where q >= 0)
  std::vector<float> n;         // shrinkage rule: rewards (and prior) behind q and m2
  std::vector<float> weight;    // prior weight of each cluster (importance or power)
};

// Refinement of the tree from the root, always splitting the node with the largest
// `priority(node)` (ties: the lower node id), until `size` nodes or only leaves; sorted by light
// range.
std::vector<uint32_t> refine_cut(const LightTree& tree, int size,
                                 double (*priority)(const LightTree&, uint32_t));
// The shared initial cut: refine_cut by light count.
std::vector<uint32_t> initial_cut(const LightTree& tree, int size);

// A pass's rewards of a cluster, n of them with absolute sum `sum` and sum of squares `sq`: their
// mean and second moment (E[r^2] >= E[r]^2 also where squares fell below the sums' resolution).
struct RewardMoments {
  double mean, mean2;
  RLL_HD RewardMoments(double n, double sum, double sq)
      : mean(sum / n), mean2(std::max(sq / n, mean * mean)) {}
};

// The shrinkage rule (LearningRule::Shrinkage) for one cluster: values old_q and old_m2, held
// with the weight of w rewards, and n new rewards of moments r give the weighted means; the
// weight becomes w + n, at most cap.
RLL_HD inline void shrinkage_fold(float& q, float& m2, float& weight, double w, double old_q,
                                  double old_m2, double n, const RewardMoments& r, double cap) {
  q = float((w * old_q + n * r.mean) / (w + n));
  m2 = float((w * old_m2 + n * r.mean2) / (w + n));
  weight = float(std::min(w + n, cap));
}

// The change test of forget=changes: true if n new rewards of moments r differ in mean from
// old_q (held with the weight of w rewards, second moment old_m2) by more than z standard errors
// of the difference. The variance is the larger of the old rewards' and the new ones', so that a
// rare bright reward among zeros (a cluster seen through a gap) does not count as a change, and
// a lamp switching off (new rewards all zero) or on (old ones all zero) does; a relative slack
// of 1e-4 absorbs the rounding of rewards that never vary.
RLL_HD inline bool reward_changed(double old_q, double old_m2, double w, double n,
                                  const RewardMoments& r, double z) {
  const double var = std::max(std::max(old_m2 - old_q * old_q, r.mean2 - r.mean * r.mean), 0.0);
  const double se = std::sqrt(var * (1 / n + 1 / std::max(w, 1.0)));
  return std::abs(r.mean - old_q) > z * se + 1e-4 * (std::abs(old_q) + std::abs(r.mean));
}

// One cluster's fold under the shrinkage rule as CutSettings say: the weight w of the past (the
// cluster's own n if `visited`, else the prior's weight) capped at 1/alpha under forget=floor, or
// where forget=changes finds a change; true if it found one.
RLL_HD inline bool shrinkage_update(const CutSettings& s, float& q, float& m2, float& weight,
                                    double w, bool visited, double old_q, double old_m2, double n,
                                    const RewardMoments& r) {
  const double floor_cap = 1.0 / s.alpha;
  if (s.forget == Forgetting::Floor) {
    shrinkage_fold(q, m2, weight, visited ? std::min(w, floor_cap) : w, old_q, old_m2, n, r,
                   floor_cap);
    return false;
  }
  const bool changed = visited && s.change_z > 0 && w > floor_cap &&
                       reward_changed(old_q, old_m2, w, n, r, s.change_z);
  shrinkage_fold(q, m2, weight, changed ? floor_cap : w, old_q, old_m2, n, r, 1e30);
  return changed;
}

// Pooling: shrinks K values, each held with the weight of n[k] rewards (visited[k] false: none,
// and the value is ignored), toward a distribution `shares` scaled to what the visited values say
// the total is (their sum over their shares, the shares' sum taken as at least a quarter, so that
// one bright, rarely chosen cluster does not inflate every unvisited one): each becomes
// (n v + c guess) / (n + c), an unvisited one the guess (also for c = 0). Unchanged where no
// visited value is positive.
template <class Visited>
RLL_HD void shrink_toward(size_t K, Visited visited, const float* n, const float* shares, double c,
                          float* values) {
  double v_sum = 0, s_sum = 0;
  for (size_t k = 0; k < K; ++k)
    if (visited(k)) {
      v_sum += values[k];
      s_sum += shares[k];
    }
  if (!(v_sum > 0)) return;
  const double total = v_sum / std::max(s_sum, 0.25);
  for (size_t k = 0; k < K; ++k) {
    const double guess = total * shares[k], w = visited(k) ? double(n[k]) : 0.0;
    values[k] = w + c > 0 ? float((w * values[k] + c * guess) / (w + c)) : float(guess);
  }
}

struct Scene;
// The unit of the learning samplers' exact reward sums: the brightest light's largest irradiance,
// so that every scene gets the same relative range of ExactSum (2^-40 to 2^36 of it).
double reward_scale(const Scene& scene);

// Guided descent: for an inner node above a cut whose clusters [k0, k1) lie under it (`ends` the
// cut's range ends), the cluster j after which its two children meet: ends[j] is the first
// child's end, so clusters [k0, j] lie under the first child and [j + 1, k1) under the second.
RLL_HD inline uint32_t children_boundary(const LightTreeView& tree, const LightTreeNode& node,
                                         const uint32_t* ends, uint32_t k0, uint32_t k1) {
  // The first of ends[k0, k1) not below the first child's end (std::lower_bound, on either device).
  const uint32_t target = tree.node(node.child).end;
  uint32_t lo = k0, n = k1 - k0;
  while (n > 0) {
    const uint32_t half = n / 2;
    if (ends[lo + half] < target) {
      lo += half + 1;
      n -= half + 1;
    } else {
      n = half;
    }
  }
  return lo;
}
inline uint32_t children_boundary(const LightTree& tree, const LightTreeNode& node,
                                  const uint32_t* ends, uint32_t k0, uint32_t k1) {
  return children_boundary(tree.view(), node, ends, k0, k1);
}

// True if the nodes partition [0, light_count) into contiguous ranges in order.
bool is_valid_cut(const LightTree& tree, const std::vector<uint32_t>& nodes);

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

// One split-collapse step (DESIGN 2b point 4) on a cut of `size` clusters held in arrays with
// room for size + 1 (nodes, q, m2, n, weight as in Cut; value and score as SplitCollapse says):
// returns 1 for a split with a collapse, 2 for a pure split (size < max_size), 0 if nothing
// changed; `size` follows. `weight_of(node)` is the prior weight of a node entering the cut;
// `share_of(node)` splits a cluster's values between its children.
template <typename WeightOf, typename ShareOf>
RLL_HD int split_collapse_step(const LightTreeView& tree, int max_size, float threshold,
                               uint32_t& size, uint32_t* nodes, float* q, float* m2, float* n,
                               float* weight, float* value, float* score, const WeightOf& weight_of,
                               const ShareOf& share_of) {
  size_t K = size;
  // l_max: the splittable cluster (more than one light) with the largest score.
  long best = -1;
  for (size_t k = 0; k < K; ++k)
    if (!tree.node(nodes[k]).is_leaf() && (best < 0 || score[k] > score[best])) best = long(k);
  if (best < 0 || !(score[best] > 0)) return 0;
  // p_min: among parents whose two children are both in the cut (the minimum over all nodes
  // above the cut is always attained at such a parent), the one with the smallest value, not
  // the parent of l_max: the darkest sibling pair.
  long pmin = -1;
  if (int(K) >= max_size) {
    for (size_t k = 0; k + 1 < K; ++k) {
      if (long(k) == best || long(k + 1) == best) continue;
      const LightTreeNode& a = tree.node(nodes[k]);
      if (a.parent == LightTree::kNone || tree.node(a.parent).child != nodes[k] ||
          nodes[k + 1] != nodes[k] + 1)
        continue;
      if (pmin < 0 || value[k] + value[k + 1] < value[pmin] + value[pmin + 1]) pmin = long(k);
    }
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
           const WeightOf& weight_of, const ShareOf& share_of) const {
    uint32_t K = uint32_t(cut.nodes.size());
    auto resize = [&](size_t to) {
      for (auto* v : {&cut.q, &cut.m2, &cut.n, &cut.weight, &value, &score}) v->resize(to);
      cut.nodes.resize(to);
    };
    resize(K + 1);  // room for a split
    const int r = split_collapse_step(m_tree.view(), m_max, m_t, K, cut.nodes.data(), cut.q.data(),
                                      cut.m2.data(), cut.n.data(), cut.weight.data(), value.data(),
                                      score.data(), weight_of, share_of);
    resize(K);
    return r;
  }

 private:
  const LightTree& m_tree;
  int m_max;
  float m_t;
};

// A sum of non-negative values that is exact and independent of the order of additions, over a
// wide range: values are fixed point with 2^-40 of the unit per step, up to 2^36 units (larger
// values saturate), held in two 64-bit words (units of 2^-8 and 2^-40) so that 2^19 saturated
// values or 2^31 ordinary ones fit in a pass. Resolution and range together span 2^76 (1e23).
struct ExactSum {
  static constexpr double kMax = 0x1p36;
  // Signed 64-bit words in two's complement, added with core/device.h's atomic_add (DESIGN 6).
  uint64_t hi = 0, lo = 0;
  RLL_HD void add(double x) {  // x: the value in units of scale, >= 0
    x = std::min(x, double(kMax));
    double h = std::floor(x * 0x1p8);
    atomic_add(&hi, uint64_t(int64_t(h)));
    atomic_add(&lo, uint64_t(int64_t((x * 0x1p8 - h) * 0x1p32 + 0.5)));
  }
  RLL_HD double value() const {
    return double(int64_t(atomic_load(&hi))) * 0x1p-8 + double(int64_t(atomic_load(&lo))) * 0x1p-40;
  }
  RLL_HD void reset() { hi = lo = 0; }  // between passes
};

// What sampling from a CutStore and recording rewards read and write (DESIGN 6): per cell, the
// cut (clusters' nodes and light ranges, m of them at most) and its baked CDF, the shared
// initial cut, the anchor, the unit of the sums, and the exact sums and counts of this pass.
struct CutStoreView {
  static constexpr double kMaxRootOfSquare = 0x1p18;  // squares saturate at 2^36 too
  uint32_t m = 0;             // clusters per cell at most: the stride of the per-cluster arrays
  View<const uint32_t> size;  // K per cell; 0: no cut yet
  View<const uint32_t> node, end;
  View<const float> cdf;
  View<const float> gl, gr;  // guided descent only (empty otherwise): CutStore::guide_left/right
  View<const float> eps;     // per cell: the defensive weight during this pass
  View<const uint32_t> initial, initial_ends;
  View<CellAnchor> anchor;
  View<const double> inv_unit;  // per cell: 1 / the unit of its sums during this pass
  View<ExactSum> sum, sq;       // per cluster: rewards and their squares
  View<uint32_t> count;         // per cluster: rewards this pass

  RLL_HD bool active(uint32_t cell) const { return size[cell] > 0; }
};

// Adds one reward to cluster k of `cell` (see CutStore::record).
RLL_HD inline void cut_record(const CutStoreView& v, uint32_t cell, uint32_t k, float reward) {
  const size_t i = size_t(cell) * v.m + k;
  const double x = double(reward) * v.inv_unit[cell];
  if (x > 0) {  // (a zero reward, an occluded sample, only counts)
    v.sum[i].add(x);
    const double c = std::min(x, double(CutStoreView::kMaxRootOfSquare));
    v.sq[i].add(c * c);
  }
  atomic_add(&v.count[i], 1u);
}

// What the end of pass did to one cell (CutStore::end_pass, cut_end_pass).
struct CutPassStats {
  uint32_t splits = 0, collapses = 0;
  uint32_t changes = 0;  // clusters whose rewards failed the change test (forget=changes)
  bool touched = false;
};

struct CutStoreEndView;

class CutStore {
 public:
  CutStore(const LightTree& tree, uint32_t cells, const CutSettings& settings, double reward_scale);
  // The memory a store of `cells` cells of cuts of `cut_size` clusters takes (bytes()).
  // Pooling in `pool_tiers` tiers (0: off) adds, per cell, its coarse shares and at most one
  // coarse cell's Q, M2 and weights per tier.
  static size_t bytes_for(uint32_t cells, int cut_size, bool guided = false, int pool_tiers = 0);

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
  const float* m2(uint32_t cell) const { return &m_m2[size_t(cell) * m_m]; }
  // The weight, in rewards, behind each cluster's q and m2 (its memory: every reward seen, or
  // at most 1/alpha of them since the last change, as rll.forget says).
  const float* memory(uint32_t cell) const { return &m_n[size_t(cell) * m_m]; }
  // Guided descent: the inner nodes above a cell's cut are one per boundary between adjacent
  // clusters j and j + 1 (the node whose children meet there); guide_left(cell)[j] and
  // guide_right(cell)[j] are the factors of that node's first and second child: the mean of
  // their clusters' factors g(k) = (1 - e) rho(k) / mean rho + e, weighted by the prior at the
  // anchor, e the cell's defensive weight and rho the learnt ratio (1 everywhere before the cell
  // has learnt: the light tree itself).
  const float* guide_left(uint32_t cell) const { return &m_gl[size_t(cell) * m_m]; }
  const float* guide_right(uint32_t cell) const { return &m_gr[size_t(cell) * m_m]; }
  // False while the cell has learnt nothing (every value zero): its CDF is then the prior's.
  bool learnt(uint32_t cell) const { return m_learnt[cell] != 0; }
  // The weight of the defensive term for this cell during this pass (1 before it learnt).
  float defensive_weight(uint32_t cell) const { return m_eps[cell]; }
  // Rewards the cell has received in earlier passes (huge for a cell the oracle assigned).
  float rewards_seen(uint32_t cell) const { return m_seen[cell]; }
  // The learnt distribution of the cell's clusters, V(s) / sum V (V = sqrt(M2) or Q), before the
  // defensive prior is mixed in; empty while the cell has learnt nothing. For tests and tools.
  std::vector<double> learnt_shares(uint32_t cell) const;

  // Called when a cell is created, from any thread: its anchor for prior weights.
  void set_anchor(uint32_t cell, const CellAnchor& a) { m_anchor[cell] = a; }
  const CellAnchor& anchor(uint32_t cell) const { return m_anchor[cell]; }

  // Adds one reward to cluster k of `cell` (an index in the cell's cut, or in the initial cut
  // for a cell without one). Thread-safe and never loses an update: sums are exact, so the
  // result does not depend on the order threads deliver rewards in. The unit of a cell's sums
  // is its own largest learnt sqrt(M2) (the brightest light's largest irradiance until it has
  // one), fixed during a pass: rewards from 2^-40 to 2^36 of it and squares from 2^-20 to 2^18
  // are resolved, whatever other lights of the scene emit.
  void record(uint32_t cell, uint32_t k, float reward) { cut_record(view(), cell, k, reward); }
  // The arrays for sampling and cut_record; valid while the store lives (between passes, until
  // end_pass, clear, assign or load_cell change a cell's cut).
  CutStoreView view();

  using PassStats = CutPassStats;
  // What the end of pass reads and writes (learn/cut_end_pass.h): every per-cell array. Valid
  // while the store lives; the const methods pass it only to functions that read.
  CutStoreEndView end_view();
  // End of pass for one cell (cells are independent: call in parallel). A cell without a cut
  // gets the initial one; rewards are folded into Q and M2, split-collapse runs, the CDF is
  // baked.
  PassStats end_pass(uint32_t cell);
  // Light powers or positions changed: recompute prior weights and the CDF of a cell.
  void refresh(uint32_t cell);
  // Pooling: adds the pass's rewards of `cell` (under the shared cut's indices) in absolute
  // units to sum, sq and count (each K = initial_size() long); with pool_ratio, each divided by
  // the cell's prior share of its cluster (cell_prior).
  void add_pass_rewards(uint32_t cell, double* sum, double* sq, uint64_t* count) const;
  // The normalized prior of every cluster of the cell's cut, as its baked table mixes it in (of
  // the initial cut at the cell's anchor while it has no cut).
  void cell_prior(uint32_t cell, std::vector<double>& out) const;
  // Pooling: the coarse distribution the cell's values are shrunk toward (K shares; nullptr:
  // none, the prior as without pooling). Called between passes, before end_pass.
  void set_pool(uint32_t cell, const float* shares);
  // Pooling: the shares set_pool gave the cell (initial_size() of them), nullptr if none.
  const float* pool_shares(uint32_t cell) const {
    return !m_has_pool.empty() && m_has_pool[cell] ? &m_pool[size_t(cell) * m_m] : nullptr;
  }
  // Forgets a cell (eviction).
  void clear(uint32_t cell);
  // Gives a cell a cut with known values (the oracle; value = mean): prior weights from the
  // cell's anchor, and only the configured defensive weight.
  void assign(uint32_t cell, const std::vector<uint32_t>& nodes, const std::vector<float>& q);

  size_t bytes() const;

  // A cell's learnt state between passes (cut, values, prior weights, CDF, anchor), for saved
  // sampler states. load_cell checks what it reads against the tree and throws rll::Error
  // naming the file if the state could not have been written by save_cell.
  void save_cell(uint32_t cell, BinaryWriter& w) const;
  void load_cell(uint32_t cell, BinaryReader& r);

 private:
  CutStoreEndView end_view() const;

  const LightTree& m_tree;
  CutSettings m_s;
  int m_m;
  double m_scale;     // the unit of a cell's sums before it has learnt anything
  double m_log_keep;  // log(1 - alpha)

  std::vector<uint32_t> m_initial, m_initial_ends;

  std::vector<uint32_t> m_size;  // K per cell; 0: no cut yet
  std::vector<uint32_t> m_node, m_end;
  std::vector<float> m_q, m_m2, m_n, m_weight, m_cdf;
  std::vector<float> m_gl, m_gr;  // guided descent only (empty otherwise)
  std::vector<uint8_t> m_learnt;  // per cell: sum of values > 0
  std::vector<float> m_seen;      // per cell: rewards received so far
  std::vector<float> m_eps;       // per cell: defensive weight, frozen during a pass
  std::vector<CellAnchor> m_anchor;
  std::vector<float> m_pool;                // pooling: per cluster, the coarse cell's share
  std::vector<uint8_t> m_has_pool;          // pooling: per cell, m_pool holds shares
  std::vector<double> m_inv_unit;           // per cell: 1 / the unit of its sums during this pass
  std::unique_ptr<ExactSum[]> m_sum, m_sq;  // per cluster: rewards and their squares
  std::unique_ptr<uint32_t[]> m_count;      // per cluster: rewards this pass
};

}  // namespace rll
