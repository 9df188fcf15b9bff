#include "rll/learn/cut_store.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "rll/core/error.h"
#include "rll/learn/cut_end_pass.h"
#include "rll/learn/cut_params.h"

namespace rll {

// --- CutStore -----------------------------------------------------------------------------------

CutStore::CutStore(const LightTree& tree, uint32_t cells, const CutSettings& s, double reward_scale,
                   const std::string& prefix)
    : m_tree(tree), m_s(s), m_m(s.cut_size) {
  check_cut_settings(s, prefix);
  // The accumulators' unit: the brightest light's largest irradiance (ExactSum spans 2^-40 to
  // 2^36 of it).
  m_scale = std::max(reward_scale, 1e-30);
  m_log_keep = std::log1p(-double(s.alpha));
  m_cuts = CutArrays(tree, cells, uint32_t(m_m), initial_cut(tree, s.initial_size));

  const size_t n = size_t(cells) * m_m;
  m_q.assign(n, 0.0f);
  m_m2.assign(n, 0.0f);
  m_n.assign(n, 0.0f);
  m_weight.assign(n, 0.0f);
  m_vis.assign(n, 1.0f);
  if (s.guided) {
    m_gl.assign(n, 1.0f);
    m_gr.assign(n, 1.0f);
  }
  m_learnt.assign(cells, 0);
  m_seen.assign(cells, 0.0f);
  m_eps.assign(cells, 1.0f);
  m_anchor.assign(cells, CellAnchor{});
  if (s.pool_levels > 0) {
    m_pool.assign(n, 0.0f);
    m_has_pool.assign(cells, 0);
  }
  m_inv_unit.assign(cells, 1 / m_scale);
  m_sum = std::make_unique<ExactSum[]>(n);
  m_sq = std::make_unique<ExactSum[]>(n);
  m_count = std::make_unique<uint32_t[]>(n);
  if (s.refine > 0) {
    m_up = std::make_unique<ExactSum[]>(n);
    m_up_count.assign(n, 0);
    m_refined.assign(cells, 0);
  }
}

CutStoreView CutStore::view() {
  const size_t n = m_cuts.node.size();
  CutStoreView v;
  static_cast<CutArraysView&>(v) = std::as_const(m_cuts).view();
  v.gl = view_of(m_gl);
  v.gr = view_of(m_gr);
  v.vis = view_of(m_vis);
  v.eps = view_of(m_eps);
  v.anchor = view_of(m_anchor);
  v.inv_unit = view_of(m_inv_unit);
  v.sum = {m_sum.get(), n};
  v.sq = {m_sq.get(), n};
  v.count = {m_count.get(), n};
  v.up = {m_up.get(), m_up ? n : 0};
  v.up_count = view_of(m_up_count);
  v.refined = view_of(std::as_const(m_refined));
  return v;
}

size_t CutStore::bytes_for(uint32_t cells, int cut_size, bool guided, int pool_tiers, bool refine) {
  // q, m2, n, weight, cdf and the target factor; guided: its two factors; pooling: its shares
  // and each tier's coarse Q, M2 and weight.
  const size_t per_cluster_floats = guided ? 8 : pool_tiers > 0 ? 7 + 3 * size_t(pool_tiers) : 6;
  const size_t per_cell =
      size_t(cut_size) * (2 * sizeof(uint32_t) + per_cluster_floats * sizeof(float) +
                          2 * sizeof(ExactSum) + sizeof(uint32_t)) +
      sizeof(uint32_t) + 2 * sizeof(float) + sizeof(uint8_t) + sizeof(double) + sizeof(CellAnchor);
  const size_t per_cell_refine =
      refine ? size_t(cut_size) * (sizeof(ExactSum) + sizeof(uint32_t)) + sizeof(uint8_t) : 0;
  return size_t(cells) * (per_cell + per_cell_refine);
}

size_t CutStore::bytes() const {
  return bytes_for(m_cuts.cells(), m_m, m_s.guided, m_s.pool_tiers(), m_s.refine > 0);
}

CutStoreEndView CutStore::end_view() {
  CutStoreEndView v;
  static_cast<CutArraysRwView&>(v) = m_cuts.rw_view();
  v.s = m_s;
  v.tree = m_tree.view();
  v.scale = m_scale;
  v.log_keep = m_log_keep;
  v.q = view_of(m_q);
  v.m2 = view_of(m_m2);
  v.n = view_of(m_n);
  v.weight = view_of(m_weight);
  v.gl = view_of(m_gl);
  v.gr = view_of(m_gr);
  v.vis = view_of(m_vis);
  v.learnt = view_of(m_learnt);
  v.seen = view_of(m_seen);
  v.eps = view_of(m_eps);
  v.anchor = view_of(m_anchor);
  v.pool = view_of(m_pool);
  v.has_pool = view_of(m_has_pool);
  v.inv_unit = view_of(m_inv_unit);
  const size_t n = m_cuts.node.size();
  v.sum = {m_sum.get(), n};
  v.sq = {m_sq.get(), n};
  v.count = {m_count.get(), n};
  v.up = {m_up.get(), m_up ? n : 0};
  v.up_count = view_of(m_up_count);
  v.refined = view_of(m_refined);
  return v;
}

CutStoreEndView CutStore::end_view() const {
  return const_cast<CutStore*>(this)->end_view();  // (only for functions that read)
}

void CutStore::add_pass_rewards(uint32_t cell, double* sum, double* sq, uint64_t* count) const {
  cut_pass_rewards(end_view(), cell, sum, sq, count, HostCutScratch(initial_size()));
}

void CutStore::cell_prior(uint32_t cell, std::vector<double>& out) const {
  out.resize(active(cell) ? size(cell) : initial_size());
  cut_cell_prior(end_view(), cell, out.data(), HostCutScratch(initial_size()));
}

void CutStore::set_pool(uint32_t cell, const float* shares) {
  if (m_has_pool.empty()) return;
  m_has_pool[cell] = shares != nullptr;
  if (shares) std::copy_n(shares, initial_size(), &m_pool[size_t(cell) * m_m]);
}

std::vector<double> CutStore::learnt_shares(uint32_t cell) const {
  if (!active(cell) || !learnt(cell)) return {};
  const CutStoreEndView v = end_view();
  const size_t K = size(cell);
  std::vector<double> pri(K);
  std::vector<float> val(K);
  cut_cell_prior(v, cell, pri.data(), HostCutScratch(0));  // (active: no scratch)
  cut_values(v, cell, K, pri.data(), val.data());
  double sum = 0;
  for (float x : val) sum += x;
  std::vector<double> out(K);
  for (size_t k = 0; k < K; ++k) out[k] = val[k] / sum;
  return out;
}

void CutStore::clear(uint32_t cell) {
  cut_clear(end_view(), cell);
}

void CutStore::assign(uint32_t cell, const std::vector<uint32_t>& nodes,
                      const std::vector<float>& q) {
  const CutStoreEndView v = end_view();
  const size_t base = size_t(cell) * m_m;
  for (size_t k = 0; k < nodes.size(); ++k) {
    m_cuts.node[base + k] = nodes[k];
    m_q[base + k] = q[k];
    m_m2[base + k] = q[k] * q[k];  // known exactly: the mean is the target whatever rll.target says
    m_n[base + k] = 1.0f / m_s.alpha;
    m_weight[base + k] = cut_weight_of(v, cell, nodes[k]);
  }
  m_seen[cell] = 1e30f;  // only the configured defensive weight
  cut_bake(v, cell, uint32_t(nodes.size()), HostCutScratch(uint32_t(nodes.size())));
}

void CutStore::refresh(uint32_t cell) {
  cut_refresh(end_view(), cell, HostCutScratch(size(cell)));
}

CutStore::PassStats CutStore::end_pass(uint32_t cell) {
  const CutStoreEndView v = end_view();
  return cut_end_pass(v, cell, HostCutScratch(cut_scratch_room(v, cell)));
}

void CutStore::save_cell(uint32_t cell, BinaryWriter& w) const {
  const size_t base = size_t(cell) * m_m;
  const uint32_t K = size(cell);
  w.put(K);
  w.put_array(&m_cuts.node[base], K);
  w.put_array(&m_q[base], K);
  w.put_array(&m_m2[base], K);
  w.put_array(&m_n[base], K);
  w.put_array(&m_weight[base], K);
  w.put_array(&m_cuts.cdf[base], K);
  w.put(m_learnt[cell]);
  w.put(m_seen[cell]);
  w.put(m_eps[cell]);
  w.put(m_anchor[cell]);
  w.put(m_inv_unit[cell]);
  // rll.refine: the refined flag (a state is only read with the parameters it was saved with, so
  // one saved without refinement has the layout it always had).
  if (!m_refined.empty()) w.put(m_refined[cell]);
}

void CutStore::load_cell(uint32_t cell, BinaryReader& r) {
  auto damaged = [&](const char* what) {
    fail("cannot read '{}': the file is damaged (cell {}: {})", r.name(), cell, what);
  };
  const size_t base = size_t(cell) * m_m;
  const uint32_t K = r.get<uint32_t>();
  if (K > uint32_t(m_m)) damaged("a cut larger than rll.cut_size");
  clear(cell);
  r.get_array(&m_cuts.node[base], K);
  r.get_array(&m_q[base], K);
  r.get_array(&m_m2[base], K);
  r.get_array(&m_n[base], K);
  r.get_array(&m_weight[base], K);
  r.get_array(&m_cuts.cdf[base], K);
  m_learnt[cell] = r.get<uint8_t>();
  m_seen[cell] = r.get<float>();
  m_eps[cell] = r.get<float>();
  m_anchor[cell] = r.get<CellAnchor>();
  m_inv_unit[cell] = r.get<double>();
  if (!m_refined.empty()) {
    m_refined[cell] = r.get<uint8_t>();
    if (m_refined[cell] > 1) damaged("its refined flag is neither 0 nor 1");
  }
  if (K > 0) {
    const std::vector<uint32_t> nodes(m_cuts.node.begin() + long(base),
                                      m_cuts.node.begin() + long(base + K));
    if (!is_valid_cut(m_tree, nodes)) damaged("its cut is not a cut of this scene's light tree");
    float last = 0;
    for (size_t k = 0; k < K; ++k) {
      m_cuts.end[base + k] = m_tree.node(nodes[k]).end;
      const size_t i = base + k;
      // q < 0 marks a cluster never visited; every other value is finite and non-negative.
      if (!std::isfinite(m_q[i]) || !(m_m2[i] >= 0) || !std::isfinite(m_m2[i]) || !(m_n[i] >= 0) ||
          !std::isfinite(m_n[i]) || !(m_weight[i] >= 0) || !std::isfinite(m_weight[i]))
        damaged("a learnt value is negative or not finite");
      const float c = m_cuts.cdf[i];
      if (!(c >= last && c <= 1)) damaged("its CDF is not increasing in [0, 1]");
      last = c;
    }
    if (last != 1.0f) damaged("its CDF does not end at 1");
  }
  const CellAnchor& a = m_anchor[cell];
  if (!(m_eps[cell] >= 0 && m_eps[cell] <= 1) || !(m_seen[cell] >= 0) ||
      !std::isfinite(m_seen[cell]) || !(m_inv_unit[cell] > 0) || !std::isfinite(m_inv_unit[cell]) ||
      m_learnt[cell] > 1 || !std::isfinite(a.p.x + a.p.y + a.p.z + a.n.x + a.n.y + a.n.z))
    damaged("a cell value is out of range");
  m_cuts.size[cell] = K;
  if (K > 0) {  // the factors baked with the table, which the file does not hold
    const CutStoreEndView v = end_view();
    std::vector<double> pri(K);
    std::vector<float> val(K);
    HostCutScratch scratch(K);
    cut_cell_prior(v, cell, pri.data(), scratch);
    cut_values(v, cell, K, pri.data(), val.data());
    const double eps = m_learnt[cell] ? m_eps[cell] : 1.0;
    if (m_s.guided) cut_bake_guide(v, cell, K, pri.data(), val.data(), eps, scratch);
    cut_bake_target(v, cell, K, pri.data(), val.data(), eps, scratch);
  }
}

}  // namespace rll
