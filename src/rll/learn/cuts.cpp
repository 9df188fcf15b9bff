#include "rll/learn/cuts.h"

#include <algorithm>
#include <cmath>
#include <queue>

#include "rll/core/error.h"

namespace rll {

namespace {
// Shares of the prior that follow power, and that are uniform over the clusters with power,
// so that every cluster with power keeps a probability the float CDF can represent, even where
// the importance at the anchor is zero (a cluster's power can be 1e-7 of a sky dome's).
constexpr double kPowerShare = 0.04;
constexpr double kUniformShare = 0.01;

// prior = (1 - power_share - uniform) * weight + power_share * power + uniform / count, with
// power(k) and weight(k) given by the caller.
template <typename Power, typename Weight>
void mix_prior(size_t K, double power_share, const Power& power, const Weight& weight, std::vector<double>& out) {
  double psum = 0, wsum = 0;
  size_t with_power = 0;
  for (size_t k = 0; k < K; ++k) {
    double p = std::max(0.0, double(power(k)));
    psum += p;
    wsum += std::max(0.0, double(weight(k)));
    with_power += p > 0;
  }
  out.resize(K);
  if (!(psum > 0)) {  // nothing emits: uniform
    std::fill(out.begin(), out.end(), 1.0 / double(K));
    return;
  }
  const double ps = wsum > 0 ? power_share : 1.0 - kUniformShare;
  const double ws = (1 - ps - kUniformShare) / (wsum > 0 ? wsum : 1.0);
  const double us = kUniformShare / double(with_power);
  for (size_t k = 0; k < K; ++k) {
    double p = std::max(0.0, double(power(k)));
    out[k] = ws * std::max(0.0, double(weight(k))) + ps * p / psum + (p > 0 ? us : 0.0);
  }
}
}  // namespace

std::vector<uint32_t> initial_cut(const LightTree& tree, int cut_size) {
  // Max-heap by light count; ties by node id for determinism.
  auto cmp = [&](uint32_t a, uint32_t b) {
    uint32_t ca = tree.node(a).light_count(), cb = tree.node(b).light_count();
    return ca != cb ? ca < cb : a > b;
  };
  std::priority_queue<uint32_t, std::vector<uint32_t>, decltype(cmp)> heap(cmp);
  std::vector<uint32_t> done;
  heap.push(LightTree::kRoot);
  while (!heap.empty() && int(heap.size() + done.size()) < cut_size) {
    uint32_t n = heap.top();
    heap.pop();
    if (tree.node(n).is_leaf()) {
      done.push_back(n);
      continue;
    }
    heap.push(tree.node(n).child);
    heap.push(tree.node(n).child + 1);
  }
  while (!heap.empty()) {
    done.push_back(heap.top());
    heap.pop();
  }
  std::sort(done.begin(), done.end(), [&](uint32_t a, uint32_t b) { return tree.node(a).begin < tree.node(b).begin; });
  return done;
}

bool is_valid_cut(const LightTree& tree, const std::vector<uint32_t>& nodes) {
  uint32_t next = 0;
  for (uint32_t n : nodes) {
    if (n >= tree.node_count() || tree.node(n).begin != next) return false;
    next = tree.node(n).end;
  }
  return next == tree.light_count() && !nodes.empty();
}

// --- CutStore -----------------------------------------------------------------------------------

CutStore::CutStore(const LightTree& tree, uint32_t cells, const CutSettings& s, double reward_scale)
    : m_tree(tree), m_s(s), m_m(s.cut_size) {
  if (m_m < 2 || m_m > 4096) fail("rll.cut_size must be in [2, 4096] (got {})", m_m);
  if (!(s.alpha > 0 && s.alpha <= 1)) fail("rll.alpha must be in (0, 1] (got {})", s.alpha);
  if (!(s.epsilon > 0 && s.epsilon <= 1))
    fail("rll.epsilon must be in (0, 1] (got {}): it keeps the estimator unbiased", s.epsilon);
  if (!(s.threshold >= 1)) fail("rll.T must be at least 1 (got {})", s.threshold);
  if (s.splits < 0) fail("rll.splits must not be negative (got {})", s.splits);
  // Fixed point with 2^-24 of the reward scale per step.
  m_scale = std::max(reward_scale, 1e-30) * 0x1p-24;
  m_log_keep = std::log1p(-double(s.alpha));
  m_initial = initial_cut(tree, m_m);
  for (uint32_t n : m_initial) m_initial_ends.push_back(tree.node(n).end);

  const size_t n = size_t(cells) * m_m;
  m_size.assign(cells, 0);
  m_node.assign(n, 0);
  m_end.assign(n, 0);
  m_q.assign(n, 0.0f);
  m_n.assign(n, 0.0f);
  m_weight.assign(n, 0.0f);
  m_cdf.assign(n, 0.0f);
  m_total.assign(cells, -1.0f);
  m_learnt.assign(cells, 0);
  m_seen.assign(cells, 0.0f);
  m_eps.assign(cells, 1.0f);
  m_anchor.assign(cells, CellAnchor{});
  m_sum = std::make_unique<std::atomic<int64_t>[]>(n);
  m_count = std::make_unique<std::atomic<uint32_t>[]>(n);
  m_cell_sum = std::make_unique<std::atomic<int64_t>[]>(cells);
  for (size_t i = 0; i < n; ++i) {
    m_sum[i].store(0, std::memory_order_relaxed);
    m_count[i].store(0, std::memory_order_relaxed);
  }
  for (uint32_t c = 0; c < cells; ++c) m_cell_sum[c].store(0, std::memory_order_relaxed);
}

size_t CutStore::bytes() const {
  const size_t n = m_node.size();
  return n * (2 * sizeof(uint32_t) + 4 * sizeof(float) + sizeof(int64_t) + sizeof(uint32_t)) +
         m_size.size() * (sizeof(uint32_t) + sizeof(float) + sizeof(int64_t) + sizeof(CellAnchor));
}

float CutStore::weight_of(uint32_t cell, uint32_t node) const {
  if (m_s.prior == ClusterWeight::Power) return m_tree.node(node).bounds.power;
  return m_tree.importance(node, m_anchor[cell].p, m_anchor[cell].n);
}

double CutStore::power_floor() const { return m_s.prior == ClusterWeight::Power ? 1.0 - kUniformShare : kPowerShare; }

void CutStore::prior(const Cut& cut, std::vector<double>& out) const {
  mix_prior(
      cut.nodes.size(), power_floor(), [&](size_t k) { return double(m_tree.node(cut.nodes[k]).bounds.power); },
      [&](size_t k) { return double(cut.weight[k]); }, out);
}

void CutStore::record(uint32_t cell, uint32_t k, float reward, float weighted) {
  auto fixed = [&](float v) {
    double x = double(v) / m_scale;
    return int64_t(std::min(x, 0x1p52) + 0.5);  // saturate: sums of 2048 maximal rewards still fit
  };
  const size_t i = size_t(cell) * m_m + k;
  m_sum[i].fetch_add(fixed(reward), std::memory_order_relaxed);
  m_count[i].fetch_add(1, std::memory_order_relaxed);
  m_cell_sum[cell].fetch_add(fixed(weighted), std::memory_order_relaxed);
}

void CutStore::load(uint32_t cell, Cut& cut) const {
  const size_t base = size_t(cell) * m_m, K = m_size[cell];
  cut.nodes.assign(m_node.begin() + long(base), m_node.begin() + long(base + K));
  cut.q.assign(m_q.begin() + long(base), m_q.begin() + long(base + K));
  cut.n.assign(m_n.begin() + long(base), m_n.begin() + long(base + K));
  cut.weight.assign(m_weight.begin() + long(base), m_weight.begin() + long(base + K));
}

void CutStore::store(uint32_t cell, const Cut& cut) {
  thread_local std::vector<double> pri;
  const size_t base = size_t(cell) * m_m, K = cut.nodes.size();
  m_size[cell] = uint32_t(K);
  prior(cut, pri);
  // P(s) = (1 - eps) Q(s) / sum Q + eps prior(s); Q of unvisited clusters is the cell's total
  // shared by the prior; without any learnt value yet, the prior alone.
  const double total = std::max(0.0f, m_total[cell]);
  double q_sum = 0;
  auto q_eff = [&](size_t k) { return cut.q[k] >= 0 ? double(cut.q[k]) : total * pri[k]; };
  for (size_t k = 0; k < K; ++k) q_sum += q_eff(k);
  m_learnt[cell] = q_sum > 0;
  m_eps[cell] = q_sum > 0 ? m_s.epsilon + (1 - m_s.epsilon) * m_s.trust / (m_s.trust + m_seen[cell]) : 1.0f;
  const double eps = q_sum > 0 ? (m_s.prior_in_cdf ? m_s.epsilon : 0.0) : 1.0;
  double acc = 0;
  for (size_t k = 0; k < K; ++k) {
    acc += (1 - eps) * (q_sum > 0 ? q_eff(k) / q_sum : 0.0) + eps * pri[k];
    m_cdf[base + k] = float(acc);
    m_end[base + k] = m_tree.node(cut.nodes[k]).end;
    m_node[base + k] = cut.nodes[k];
    m_q[base + k] = cut.q[k];
    m_n[base + k] = cut.n[k];
    m_weight[base + k] = cut.weight[k];
  }
  for (size_t k = 0; k < K; ++k) m_cdf[base + k] = float(std::min(1.0, double(m_cdf[base + k]) / acc));
  m_cdf[base + K - 1] = 1.0f;
}

void CutStore::clear(uint32_t cell) {
  const size_t base = size_t(cell) * m_m;
  m_size[cell] = 0;
  m_total[cell] = -1;
  m_learnt[cell] = 0;
  m_seen[cell] = 0;
  m_eps[cell] = 1;
  for (int k = 0; k < m_m; ++k) {
    m_sum[base + k].store(0, std::memory_order_relaxed);
    m_count[base + k].store(0, std::memory_order_relaxed);
  }
  m_cell_sum[cell].store(0, std::memory_order_relaxed);
}

void CutStore::assign(uint32_t cell, const std::vector<uint32_t>& nodes, const std::vector<float>& q) {
  Cut cut;
  cut.nodes = nodes;
  cut.q = q;
  cut.n.assign(nodes.size(), 1.0f / m_s.alpha);
  cut.weight.resize(nodes.size());
  double total = 0;
  for (size_t k = 0; k < nodes.size(); ++k) {
    cut.weight[k] = weight_of(cell, nodes[k]);
    total += std::max(0.0f, q[k]);
  }
  m_total[cell] = float(total);
  m_seen[cell] = 1e30f;  // known exactly: only the configured defensive weight
  store(cell, cut);
}

void CutStore::refresh(uint32_t cell) {
  if (!active(cell)) return;
  thread_local Cut cut;
  load(cell, cut);
  for (size_t k = 0; k < cut.nodes.size(); ++k) cut.weight[k] = weight_of(cell, cut.nodes[k]);
  store(cell, cut);
}

CutStore::PassStats CutStore::end_pass(uint32_t cell, uint32_t parent) {
  PassStats st;
  thread_local Cut cut;
  const size_t base = size_t(cell) * m_m;
  uint64_t n_total = 0;
  const size_t K_now = active(cell) ? m_size[cell] : m_initial.size();
  for (size_t k = 0; k < K_now; ++k) n_total += m_count[base + k].load(std::memory_order_relaxed);
  if (active(cell) && n_total == 0) return st;  // nothing new: the cut and CDF stand
  if (active(cell)) {
    load(cell, cut);
  } else if (parent != ~0u && active(parent) && m_learnt[parent]) {
    // Coarse to fine: a new cell inherits what the coarser cell around it has learnt (its Q
    // are averages over a region that contains this cell), with its own prior weights.
    load(parent, cut);
    for (size_t k = 0; k < cut.nodes.size(); ++k) cut.weight[k] = weight_of(cell, cut.nodes[k]);
    m_total[cell] = m_total[parent];
    m_seen[cell] = m_seen[parent];
  } else {
    cut.nodes = m_initial;
    cut.q.assign(m_initial.size(), -1.0f);
    cut.n.assign(m_initial.size(), 0.0f);
    cut.weight.resize(m_initial.size());
    for (size_t k = 0; k < m_initial.size(); ++k) cut.weight[k] = weight_of(cell, m_initial[k]);
  }
  const size_t K = cut.nodes.size();

  // Fold this pass's rewards. Applying the paper's rule Q := (1-a) Q + a r once per reward,
  // each reward replaced by the pass mean, gives Q := b Q + (1-b) mean with b = (1-a)^n: the
  // same whatever order the threads delivered the rewards in. (A plain running mean was tried
  // and lost 3x: the rule's long memory of the prior estimate is a useful shrinkage.)
  if (n_total > 0) {
    st.touched = true;
    m_seen[cell] += float(n_total);
    double estimate = double(m_cell_sum[cell].load(std::memory_order_relaxed)) * m_scale / double(n_total);
    double b = std::exp(double(n_total) * m_log_keep);
    m_total[cell] = m_total[cell] < 0 ? float(estimate) : float(b * m_total[cell] + (1 - b) * estimate);
    thread_local std::vector<double> pri;
    prior(cut, pri);
    for (size_t k = 0; k < K; ++k) {
      uint32_t n = m_count[base + k].load(std::memory_order_relaxed);
      if (n == 0) continue;
      double mean = double(m_sum[base + k].load(std::memory_order_relaxed)) * m_scale / n;
      double old = cut.q[k] >= 0 ? cut.q[k] : m_total[cell] * pri[k];
      if (m_s.rule == LearningRule::Exponential) {
        double bk = std::exp(double(n) * m_log_keep);
        cut.q[k] = float(bk * old + (1 - bk) * mean);
      } else {
        double w = cut.q[k] >= 0 ? std::min(double(cut.n[k]), 1.0 / m_s.alpha) : double(m_s.prior_samples);
        cut.q[k] = float((w * old + n * mean) / (w + n));
        cut.n[k] = float(std::min(w + n, 1.0 / m_s.alpha));
      }
    }
    for (size_t k = 0; k < K; ++k) {
      m_sum[base + k].store(0, std::memory_order_relaxed);
      m_count[base + k].store(0, std::memory_order_relaxed);
    }
    m_cell_sum[cell].store(0, std::memory_order_relaxed);
    SplitCollapse sc(m_tree, m_m, m_s.threshold);
    thread_local std::vector<float> qe;
    qe.resize(K);
    for (size_t k = 0; k < K; ++k) qe[k] = cut.q[k] >= 0 ? cut.q[k] : float(std::max(0.0f, m_total[cell]) * pri[k]);
    auto prior_weight = [&](uint32_t node) { return weight_of(cell, node); };
    auto share = [&](uint32_t node) {
      return m_s.split == ClusterWeight::Power ? m_tree.node(node).bounds.power
                                               : m_tree.importance(node, m_anchor[cell].p, m_anchor[cell].n);
    };
    for (int i = 0; i < m_s.splits; ++i) {
      int r = sc.step(cut, qe, prior_weight, share);
      if (r == 0) break;
      ++st.splits;
      if (r == 1) ++st.collapses;
    }
  }
  store(cell, cut);
  return st;
}

}  // namespace rll
