#include "rll/learn/cuts.h"

#include <algorithm>
#include <cmath>
#include <queue>

#include "rll/core/error.h"
#include "rll/scene/scene.h"

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
void mix_prior(size_t K, double power_share, const Power& power, const Weight& weight,
               std::vector<double>& out) {
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

std::vector<uint32_t> refine_cut(const LightTree& tree, int size,
                                 double (*priority)(const LightTree&, uint32_t)) {
  // Max-heap by priority; ties by node id for determinism.
  auto cmp = [&](uint32_t a, uint32_t b) {
    const double pa = priority(tree, a), pb = priority(tree, b);
    return pa != pb ? pa < pb : a > b;
  };
  std::priority_queue<uint32_t, std::vector<uint32_t>, decltype(cmp)> heap(cmp);
  std::vector<uint32_t> done;
  heap.push(LightTree::kRoot);
  while (!heap.empty() && int(heap.size() + done.size()) < size) {
    uint32_t n = heap.top();
    heap.pop();
    if (tree.node(n).is_leaf()) {
      done.push_back(n);
      continue;
    }
    heap.push(tree.node(n).child);
    heap.push(tree.node(n).child + 1);
  }
  for (; !heap.empty(); heap.pop()) done.push_back(heap.top());
  std::sort(done.begin(), done.end(),
            [&](uint32_t a, uint32_t b) { return tree.node(a).begin < tree.node(b).begin; });
  return done;
}

std::vector<uint32_t> initial_cut(const LightTree& tree, int cut_size) {
  return refine_cut(tree, cut_size,
                    [](const LightTree& t, uint32_t n) { return double(t.node(n).light_count()); });
}

double reward_scale(const Scene& scene) {
  double s = 0;
  for (const auto& l : scene.lights) {
    double lum = luminance(l.radiance);
    switch (l.type) {
      case LightType::Triangle:
        s = std::max(s, kPi * lum * (l.two_sided ? 2 : 1));
        break;
      case LightType::Point:
        s = std::max(s, 4 * kPi * lum / double(scene.radius * scene.radius));
        break;
      case LightType::Directional:
        s = std::max(s, kPi * lum);
        break;
    }
  }
  return s > 0 ? s : 1.0;
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
  if (s.initial_size < 1 || s.initial_size > m_m)
    fail("rll.initial_cut must be in [1, rll.cut_size = {}] (got {})", m_m, s.initial_size);
  if (!(s.alpha > 0 && s.alpha <= 1)) fail("rll.alpha must be in (0, 1] (got {})", s.alpha);
  if (!(s.epsilon > 0 && s.epsilon <= 1))
    fail("rll.epsilon must be in (0, 1] (got {}): it keeps the estimator unbiased", s.epsilon);
  if (!(s.threshold >= 1)) fail("rll.T must be at least 1 (got {})", s.threshold);
  if (s.splits < 0) fail("rll.splits must not be negative (got {})", s.splits);
  // The accumulators' unit: the brightest light's largest irradiance (ExactSum spans 2^-40 to
  // 2^36 of it).
  m_scale = std::max(reward_scale, 1e-30);
  m_log_keep = std::log1p(-double(s.alpha));
  m_initial = initial_cut(tree, s.initial_size);
  for (uint32_t n : m_initial) m_initial_ends.push_back(tree.node(n).end);

  const size_t n = size_t(cells) * m_m;
  m_size.assign(cells, 0);
  m_node.assign(n, 0);
  m_end.assign(n, 0);
  m_q.assign(n, 0.0f);
  m_m2.assign(n, 0.0f);
  m_n.assign(n, 0.0f);
  m_weight.assign(n, 0.0f);
  m_cdf.assign(n, 0.0f);
  if (s.guided) {
    if (s.splits > 0)
      fail("rll.splits needs rll.sampling=table (the guided descent keeps its cut)");
    m_gl.assign(n, 1.0f);
    m_gr.assign(n, 1.0f);
  }
  m_learnt.assign(cells, 0);
  m_seen.assign(cells, 0.0f);
  m_eps.assign(cells, 1.0f);
  m_anchor.assign(cells, CellAnchor{});
  if (s.pool_levels > 0) {
    if (s.splits > 0) fail("rll.pool needs rll.splits=0 (every cell keeps the shared cut)");
    if (s.guided) fail("rll.pool needs rll.sampling=table");
    m_pool.assign(n, 0.0f);
    m_has_pool.assign(cells, 0);
  }
  m_inv_unit.assign(cells, 1 / m_scale);
  m_sum = std::make_unique<ExactSum[]>(n);
  m_sq = std::make_unique<ExactSum[]>(n);
  m_count = std::make_unique<uint32_t[]>(n);
}

CutStoreView CutStore::view() {
  const size_t n = m_size.size() * size_t(m_m);
  CutStoreView v;
  v.m = uint32_t(m_m);
  v.size = view_of(m_size);
  v.node = view_of(m_node);
  v.end = view_of(m_end);
  v.cdf = view_of(m_cdf);
  v.gl = view_of(m_gl);
  v.gr = view_of(m_gr);
  v.eps = view_of(m_eps);
  v.initial = view_of(m_initial);
  v.initial_ends = view_of(m_initial_ends);
  v.anchor = view_of(m_anchor);
  v.inv_unit = view_of(m_inv_unit);
  v.sum = {m_sum.get(), n};
  v.sq = {m_sq.get(), n};
  v.count = {m_count.get(), n};
  return v;
}

size_t CutStore::bytes_for(uint32_t cells, int cut_size, bool guided, int pool_tiers) {
  const size_t per_cluster_floats = guided ? 7 : pool_tiers > 0 ? 6 + 3 * size_t(pool_tiers) : 5;
  const size_t per_cell =
      size_t(cut_size) * (2 * sizeof(uint32_t) + per_cluster_floats * sizeof(float) +
                          2 * sizeof(ExactSum) + sizeof(uint32_t)) +
      sizeof(uint32_t) + 2 * sizeof(float) + sizeof(uint8_t) + sizeof(double) + sizeof(CellAnchor);
  return size_t(cells) * per_cell;
}

size_t CutStore::bytes() const {
  return bytes_for(uint32_t(m_size.size()), m_m, m_s.guided, m_s.pool_tiers());
}

float CutStore::weight_of(uint32_t cell, uint32_t node) const {
  if (m_s.prior == ClusterWeight::Power) return m_tree.node(node).bounds.power;
  if (m_s.prior == ClusterWeight::Uniform) return 1.0f;
  return m_tree.importance(node, m_anchor[cell].p, m_anchor[cell].n);
}

double CutStore::power_floor() const {
  return m_s.prior == ClusterWeight::Power ? 1.0 - kUniformShare : kPowerShare;
}

void CutStore::prior(const Cut& cut, std::vector<double>& out) const {
  if (m_s.prior == ClusterWeight::Uniform) {  // Fermat's: no floor, every cluster alike
    out.assign(cut.nodes.size(), 1.0 / double(cut.nodes.size()));
    return;
  }
  mix_prior(
      cut.nodes.size(), power_floor(),
      [&](size_t k) { return double(m_tree.node(cut.nodes[k]).bounds.power); },
      [&](size_t k) { return double(cut.weight[k]); }, out);
}

void CutStore::values(const Cut& cut, const std::vector<double>& pri,
                      std::vector<float>& out) const {
  const size_t K = cut.nodes.size();
  const bool moment = m_s.target == LearnTarget::Moment;
  out.resize(K);
  // What the visited clusters say the cell's total is: their values over their prior share (a
  // share below a quarter is taken as a quarter, so that one bright, rarely chosen cluster
  // does not inflate every unvisited one).
  double v_sum = 0, p_sum = 0;
  for (size_t k = 0; k < K; ++k) {
    if (cut.q[k] < 0) continue;
    out[k] = moment ? std::sqrt(std::max(cut.m2[k], 0.0f)) : cut.q[k];
    v_sum += out[k];
    p_sum += pri[k];
  }
  if (m_s.guided) {
    // Ratios to the tree's importance: a cluster never visited gets the visited clusters' mean
    // ratio, weighted by prior.
    double wv = 0;
    for (size_t k = 0; k < K; ++k)
      if (cut.q[k] >= 0) wv += pri[k] * out[k];
    const float mean = p_sum > 0 ? float(wv / p_sum) : 0.0f;
    for (size_t k = 0; k < K; ++k)
      if (cut.q[k] < 0) out[k] = mean;
    return;
  }
  const double total = v_sum / std::max(p_sum, 0.25);
  for (size_t k = 0; k < K; ++k)
    if (cut.q[k] < 0) out[k] = m_s.q_init >= 0 ? m_s.q_init : float(total * pri[k]);
}

void CutStore::values(uint32_t cell, const Cut& cut, const std::vector<double>& pri,
                      std::vector<float>& out) const {
  values(cut, pri, out);
  if (m_has_pool.empty() || !m_has_pool[cell]) return;
  const size_t K = cut.nodes.size();
  shrink_toward(
      K, [&](size_t k) { return cut.q[k] >= 0; }, cut.n.data(), &m_pool[size_t(cell) * m_m],
      m_s.pool_weight, out.data());
}

void CutStore::add_pass_rewards(uint32_t cell, double* sum, double* sq, uint64_t* count) const {
  const size_t base = size_t(cell) * m_m;
  const double unit = 1 / m_inv_unit[cell];
  thread_local std::vector<double> pri;
  if (m_s.pool_ratio) cell_prior(cell, pri);
  for (size_t k = 0; k < m_initial.size(); ++k) {
    const uint32_t n = m_count[base + k];
    if (n == 0) continue;
    const double u = m_s.pool_ratio ? unit / pri[k] : unit;
    count[k] += n;
    sum[k] += m_sum[base + k].value() * u;
    sq[k] += m_sq[base + k].value() * u * u;
  }
}

void CutStore::cell_prior(uint32_t cell, std::vector<double>& out) const {
  thread_local Cut cut;
  if (active(cell)) {
    load(cell, cut);
  } else {  // no cut yet (new in this pass): the initial cut's, at the cell's anchor
    cut.nodes = m_initial;
    cut.weight.resize(m_initial.size());
    for (size_t k = 0; k < m_initial.size(); ++k) cut.weight[k] = weight_of(cell, m_initial[k]);
  }
  prior(cut, out);
}

void CutStore::set_pool(uint32_t cell, const float* shares) {
  if (m_has_pool.empty()) return;
  m_has_pool[cell] = shares != nullptr;
  if (shares) std::copy_n(shares, m_initial.size(), &m_pool[size_t(cell) * m_m]);
}

std::vector<double> CutStore::learnt_shares(uint32_t cell) const {
  if (!active(cell) || !learnt(cell)) return {};
  Cut cut;
  load(cell, cut);
  std::vector<double> pri;
  std::vector<float> val;
  prior(cut, pri);
  values(cell, cut, pri, val);
  double sum = 0;
  for (float v : val) sum += v;
  std::vector<double> out(val.size());
  for (size_t k = 0; k < val.size(); ++k) out[k] = val[k] / sum;
  return out;
}

void CutStore::load(uint32_t cell, Cut& cut) const {
  const size_t base = size_t(cell) * m_m, K = m_size[cell];
  auto take = [&](const auto& from, auto& to) {
    to.assign(from.begin() + long(base), from.begin() + long(base + K));
  };
  take(m_node, cut.nodes);
  take(m_q, cut.q);
  take(m_m2, cut.m2);
  take(m_n, cut.n);
  take(m_weight, cut.weight);
}

void CutStore::store(uint32_t cell, const Cut& cut) {
  thread_local std::vector<double> pri;
  thread_local std::vector<float> val;
  const size_t base = size_t(cell) * m_m, K = cut.nodes.size();
  m_size[cell] = uint32_t(K);
  prior(cut, pri);
  values(cell, cut, pri, val);
  // The baked table: P(s) = (1 - e) V(s) / sum V + e prior(s), e the cell's defensive weight
  // (folded in here when the prior lives in the CDF); without any learnt value, the prior alone.
  double v_sum = 0;
  for (size_t k = 0; k < K; ++k) v_sum += val[k];
  m_learnt[cell] = v_sum > 0;
  // (trust = 0: the configured weight from the start, also for a cell without rewards yet.)
  const float distrust = m_s.trust > 0 ? m_s.trust / (m_s.trust + m_seen[cell]) : 0.0f;
  m_eps[cell] = v_sum > 0 ? m_s.epsilon + (1 - m_s.epsilon) * distrust : 1.0f;
  const double eps = v_sum > 0 ? (m_s.prior_in_cdf ? m_eps[cell] : 0.0) : 1.0;
  double acc = 0;
  for (size_t k = 0; k < K; ++k) {
    acc += (1 - eps) * (v_sum > 0 ? val[k] / v_sum : 0.0) + eps * pri[k];
    m_cdf[base + k] = float(acc);
    m_end[base + k] = m_tree.node(cut.nodes[k]).end;
    m_node[base + k] = cut.nodes[k];
    m_q[base + k] = cut.q[k];
    m_m2[base + k] = cut.m2[k];
    m_n[base + k] = cut.n[k];
    m_weight[base + k] = cut.weight[k];
  }
  for (size_t k = 0; k < K; ++k)
    m_cdf[base + k] = float(std::min(1.0, double(m_cdf[base + k]) / acc));
  m_cdf[base + K - 1] = 1.0f;
  if (m_s.guided) bake_guide(cell, cut, pri, val, v_sum > 0 ? m_eps[cell] : 1.0);
}

void CutStore::bake_guide(uint32_t cell, const Cut& cut, const std::vector<double>& pri,
                          const std::vector<float>& val, double eps) {
  const size_t base = size_t(cell) * m_m, K = cut.nodes.size();
  // g(k) = (1 - e) rho(k) / mean rho + e: the learnt ratios relative to their prior-weighted
  // mean, mixed with 1 (the tree's own step) by the defensive weight, so that g >= e > 0.
  thread_local std::vector<double> g;
  g.resize(K);
  double wsum = 0, wv = 0;
  for (size_t k = 0; k < K; ++k) {
    wsum += pri[k];
    wv += pri[k] * val[k];
  }
  const double mean = wsum > 0 ? wv / wsum : 0.0;
  for (size_t k = 0; k < K; ++k) g[k] = mean > 0 ? (1 - eps) * double(val[k]) / mean + eps : 1.0;
  // Every inner node above the cut, by recursion from the root: its children's factors are the
  // prior-weighted means of their clusters' g (the unweighted mean where no cluster has prior).
  struct Sums {
    double w = 0, wg = 0, g = 0, count = 0;
    double factor() const { return w > 0 ? wg / w : g / count; }
  };
  const uint32_t* ends = &m_end[base];
  auto visit = [&](auto&& self, uint32_t node, uint32_t k0, uint32_t k1) -> Sums {
    if (k1 - k0 == 1) return {pri[k0], pri[k0] * g[k0], g[k0], 1};
    const LightTreeNode& nd = m_tree.node(node);
    const uint32_t j = children_boundary(m_tree, nd, ends, k0, k1);
    Sums a = self(self, nd.child, k0, j + 1), b = self(self, nd.child + 1, j + 1, k1);
    m_gl[base + j] = float(a.factor());
    m_gr[base + j] = float(b.factor());
    return {a.w + b.w, a.wg + b.wg, a.g + b.g, a.count + b.count};
  };
  visit(visit, LightTree::kRoot, 0u, uint32_t(K));
}

void CutStore::clear(uint32_t cell) {
  const size_t base = size_t(cell) * m_m;
  m_size[cell] = 0;
  m_learnt[cell] = 0;
  m_seen[cell] = 0;
  m_eps[cell] = 1;
  if (!m_has_pool.empty()) m_has_pool[cell] = 0;
  m_inv_unit[cell] = 1 / m_scale;
  for (int k = 0; k < m_m; ++k) {
    m_sum[base + k].reset();
    m_sq[base + k].reset();
    m_count[base + k] = 0;
  }
}

void CutStore::assign(uint32_t cell, const std::vector<uint32_t>& nodes,
                      const std::vector<float>& q) {
  Cut cut;
  cut.nodes = nodes;
  cut.q = q;
  cut.m2.resize(nodes.size());
  cut.n.assign(nodes.size(), 1.0f / m_s.alpha);
  cut.weight.resize(nodes.size());
  for (size_t k = 0; k < nodes.size(); ++k) {
    cut.weight[k] = weight_of(cell, nodes[k]);
    cut.m2[k] = q[k] * q[k];  // known exactly: the mean is the target whatever rll.target says
  }
  m_seen[cell] = 1e30f;  // only the configured defensive weight
  store(cell, cut);
}

void CutStore::refresh(uint32_t cell) {
  if (!active(cell)) return;
  thread_local Cut cut;
  load(cell, cut);
  for (size_t k = 0; k < cut.nodes.size(); ++k) cut.weight[k] = weight_of(cell, cut.nodes[k]);
  store(cell, cut);
}

CutStore::PassStats CutStore::end_pass(uint32_t cell) {
  PassStats st;
  thread_local Cut cut;
  const size_t base = size_t(cell) * m_m;
  uint64_t n_total = 0;
  const size_t K_now = active(cell) ? m_size[cell] : m_initial.size();
  for (size_t k = 0; k < K_now; ++k) n_total += m_count[base + k];
  if (active(cell) && n_total == 0) return st;  // nothing new: the cut and CDF stand
  if (active(cell)) {
    load(cell, cut);
  } else {
    cut.nodes = m_initial;
    cut.q.assign(m_initial.size(), -1.0f);
    cut.m2.assign(m_initial.size(), 0.0f);
    cut.n.assign(m_initial.size(), 0.0f);
    cut.weight.resize(m_initial.size());
    for (size_t k = 0; k < m_initial.size(); ++k) cut.weight[k] = weight_of(cell, m_initial[k]);
  }
  const size_t K = cut.nodes.size();

  // Fold this pass's rewards into Q and M2. Shrinkage: a running mean over at most 1/alpha
  // rewards, started from the prior estimate counted as prior_samples rewards. Exponential: the
  // paper's rule Q := (1-a) Q + a r once per reward, each reward replaced by the pass mean,
  // gives Q := b Q + (1-b) mean with b = (1-a)^n. Either way the result does not depend on the
  // order the threads delivered the rewards in.
  if (n_total > 0) {
    st.touched = true;
    m_seen[cell] += float(n_total);
    thread_local std::vector<double> pri;
    thread_local std::vector<float> val;
    prior(cut, pri);
    values(cell, cut, pri, val);
    const bool moment = m_s.target == LearnTarget::Moment;
    const double unit = 1 / m_inv_unit[cell];
    double largest = 0;
    for (size_t k = 0; k < K; ++k) {
      uint32_t n = m_count[base + k];
      if (n == 0) continue;
      const RewardMoments r(n, m_sum[base + k].value() * unit,
                            m_sq[base + k].value() * unit * unit);
      // The prior estimate of a cluster never visited: its effective value, without variance.
      double old_q = cut.q[k] >= 0 ? cut.q[k] : val[k];
      double old_m2 = cut.q[k] >= 0 ? cut.m2[k] : double(val[k]) * val[k];
      if (m_s.rule == LearningRule::Exponential) {
        double bk = std::exp(double(n) * m_log_keep);
        cut.q[k] = float(bk * old_q + (1 - bk) * r.mean);
        cut.m2[k] = float(bk * old_m2 + (1 - bk) * r.mean2);
      } else {
        double w =
            cut.q[k] >= 0 ? std::min(double(cut.n[k]), 1.0 / m_s.alpha) : double(m_s.prior_samples);
        shrinkage_fold(cut.q[k], cut.m2[k], cut.n[k], w, old_q, old_m2, n, r, 1.0 / m_s.alpha);
      }
      largest = std::max(largest, std::sqrt(double(cut.m2[k])));
      m_sum[base + k].reset();
      m_sq[base + k].reset();
      m_count[base + k] = 0;
    }
    // The next pass's unit: the largest learnt sqrt(M2).
    if (largest > 0 && std::isfinite(largest)) m_inv_unit[cell] = 1 / largest;
    // Split-collapse on the new values: split by the cluster's share of the cell's variance
    // (the standard deviation of its reward) under target=moment, by value (the paper's Q)
    // under target=mean. (The prior is unchanged: folding touches no node or weight.)
    values(cell, cut, pri, val);
    thread_local std::vector<float> score;
    score.resize(K);
    for (size_t k = 0; k < K; ++k)
      score[k] =
          !moment ? val[k]
          : cut.q[k] >= 0
              ? float(std::sqrt(std::max(0.0, double(cut.m2[k]) - double(cut.q[k]) * cut.q[k])))
              : val[k];
    SplitCollapse sc(m_tree, m_m, m_s.threshold);
    auto prior_weight = [&](uint32_t node) { return weight_of(cell, node); };
    auto share = [&](uint32_t node) {
      if (m_s.split == ClusterWeight::Uniform) return 1.0f;  // half and half
      return m_s.split == ClusterWeight::Power
                 ? m_tree.node(node).bounds.power
                 : m_tree.importance(node, m_anchor[cell].p, m_anchor[cell].n);
    };
    for (int i = 0; i < m_s.splits; ++i) {
      int r = sc.step(cut, val, score, prior_weight, share);
      if (r == 0) break;
      ++st.splits;
      if (r == 1) ++st.collapses;
    }
  }
  store(cell, cut);
  return st;
}

void CutStore::save_cell(uint32_t cell, BinaryWriter& w) const {
  const size_t base = size_t(cell) * m_m;
  const uint32_t K = m_size[cell];
  w.put(K);
  w.put_array(&m_node[base], K);
  w.put_array(&m_q[base], K);
  w.put_array(&m_m2[base], K);
  w.put_array(&m_n[base], K);
  w.put_array(&m_weight[base], K);
  w.put_array(&m_cdf[base], K);
  w.put(m_learnt[cell]);
  w.put(m_seen[cell]);
  w.put(m_eps[cell]);
  w.put(m_anchor[cell]);
  w.put(m_inv_unit[cell]);
}

void CutStore::load_cell(uint32_t cell, BinaryReader& r) {
  auto damaged = [&](const char* what) {
    fail("cannot read '{}': the file is damaged (cell {}: {})", r.name(), cell, what);
  };
  const size_t base = size_t(cell) * m_m;
  const uint32_t K = r.get<uint32_t>();
  if (K > uint32_t(m_m)) damaged("a cut larger than rll.cut_size");
  clear(cell);
  r.get_array(&m_node[base], K);
  r.get_array(&m_q[base], K);
  r.get_array(&m_m2[base], K);
  r.get_array(&m_n[base], K);
  r.get_array(&m_weight[base], K);
  r.get_array(&m_cdf[base], K);
  m_learnt[cell] = r.get<uint8_t>();
  m_seen[cell] = r.get<float>();
  m_eps[cell] = r.get<float>();
  m_anchor[cell] = r.get<CellAnchor>();
  m_inv_unit[cell] = r.get<double>();
  if (K > 0) {
    const std::vector<uint32_t> nodes(m_node.begin() + long(base), m_node.begin() + long(base + K));
    if (!is_valid_cut(m_tree, nodes)) damaged("its cut is not a cut of this scene's light tree");
    float last = 0;
    for (size_t k = 0; k < K; ++k) {
      m_end[base + k] = m_tree.node(nodes[k]).end;
      const size_t i = base + k;
      // q < 0 marks a cluster never visited; every other value is finite and non-negative.
      if (!std::isfinite(m_q[i]) || !(m_m2[i] >= 0) || !std::isfinite(m_m2[i]) || !(m_n[i] >= 0) ||
          !std::isfinite(m_n[i]) || !(m_weight[i] >= 0) || !std::isfinite(m_weight[i]))
        damaged("a learnt value is negative or not finite");
      if (!(m_cdf[i] >= last && m_cdf[i] <= 1)) damaged("its CDF is not increasing in [0, 1]");
      last = m_cdf[i];
    }
    if (last != 1.0f) damaged("its CDF does not end at 1");
  }
  const CellAnchor& a = m_anchor[cell];
  if (!(m_eps[cell] >= 0 && m_eps[cell] <= 1) || !(m_seen[cell] >= 0) ||
      !std::isfinite(m_seen[cell]) || !(m_inv_unit[cell] > 0) || !std::isfinite(m_inv_unit[cell]) ||
      m_learnt[cell] > 1 || !std::isfinite(a.p.x + a.p.y + a.p.z + a.n.x + a.n.y + a.n.z))
    damaged("a cell value is out of range");
  m_size[cell] = K;
  if (m_s.guided && K > 0) {
    thread_local Cut cut;
    thread_local std::vector<double> pri;
    thread_local std::vector<float> val;
    load(cell, cut);
    prior(cut, pri);
    values(cut, pri, val);
    bake_guide(cell, cut, pri, val, m_learnt[cell] ? m_eps[cell] : 1.0);
  }
}

}  // namespace rll
