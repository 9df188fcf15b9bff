#include "rll/lights/rll_sampler.h"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <utility>

#include "rll/core/binary_io.h"
#include "rll/core/device.h"
#include "rll/core/error.h"
#include "rll/core/hash.h"
#include "rll/core/memory_budget.h"
#include "rll/core/parallel.h"
#include "rll/core/params.h"
#include "rll/core/sampling.h"
#include "rll/lights/tree_sampler.h"
#include "rll/lighttree/light_tree.h"
#include "rll/scene/scene.h"

namespace rll {

namespace {
void check_memory(const RllSettings& s) {
  // The cell table, the cuts and the point sums, allocated up front, and the end of pass's
  // scratch at its largest (every cell's cut full; pooling's coarse cells, one per cell and tier):
  // refuse a configuration the machine cannot hold rather than grow towards the out-of-memory
  // killer.
  const double scratch_per_cluster =
      CutScratchArena::kDoubles * sizeof(double) + CutScratchArena::kFloats * sizeof(float);
  const double needed =
      double(CutStore::bytes_for(s.capacity, s.cut.cut_size, s.cut.guided, s.cut.pool_tiers(),
                                 s.cut.refine > 0)) +
      double(s.capacity) * (2 * 2 * sizeof(uint64_t) + sizeof(uint32_t) + 7 * sizeof(int64_t)) +
      double(s.capacity) * s.cut.cut_size * scratch_per_cluster * std::max(1, s.cut.pool_tiers());
  if (needed > double(memory_budget_bytes()))
    fail(
        "{0}.capacity={1} with {0}.cut_size={2} needs {3} for its cells, more than {4}; lower "
        "{0}.capacity or {0}.cut_size",
        s.name, s.capacity, s.cut.cut_size, format_bytes(needed), memory_budget_phrase());
}
}  // namespace

RllLightSampler::RllLightSampler(const Scene& scene, const LightTree& tree, const RllSettings& s)
    : LightSampler(s.name, true), m_tree(tree), m_s(s), m_keyer(s.grid, scene.bounds) {
  set_resident_learner(this);
  set_learnt_cells({this, nullptr});
  check_memory(s);
  m_table = std::make_unique<CellTable>(s.capacity);
  // Guided: the rewards are ratios to the tree's importance, of the order of a reflectance.
  m_cuts = std::make_unique<CutStore>(m_tree, s.capacity, s.cut,
                                      s.cut.guided ? 1.0 : reward_scale(scene), s.name);
  m_last_used.assign(s.capacity, 0);
  m_points.assign(size_t(s.capacity) * kPointWords, 0);
  m_origin = scene.bounds.lo;
  m_extent = std::max(1e-20f, length(scene.bounds.hi - scene.bounds.lo));
  refresh_light_powers(scene);
  m_keyer.set_pass(0, 0);
  refresh_view();
}

RllLightSampler::~RllLightSampler() {
  if (m_remote) m_remote->forget();
}

void RllLightSampler::refresh_light_powers(const Scene& scene) {
  m_power_prefix.assign(scene.lights.size() + 1, 0.0);
  for (size_t i = 0; i < scene.lights.size(); ++i)
    m_power_prefix[i + 1] = m_power_prefix[i] + double(light_bounds(scene.lights[i]).power);
}

void RllLightSampler::refresh_view() {
  RllView& v = m_view;
  v.tree = m_tree.view();
  v.keyer = m_keyer;
  v.table = m_table->view();
  v.cuts = m_cuts->view();
  v.last_used = view_of(m_last_used);
  v.points = view_of(m_points);
  v.power_prefix = view_of(m_power_prefix);
  v.origin = m_origin;
  v.extent = m_extent;
  v.pass = uint32_t(m_pass);
  v.descend_above = m_s.descend_above;
  v.sample_jitter = m_s.sample_jitter;
  v.within = m_s.within;
  v.reward = m_s.reward;
  v.defensive = m_s.defensive;
  v.cold_uniform = m_s.cold_uniform;
  v.guided = m_s.cut.guided;
  v.refine = m_s.cut.refine;
  if (m_remote) m_remote->view_changed(v);
}

SamplerView RllLightSampler::sampler_view() const {
  sync();
  SamplerView v;
  v.kind = SamplerKind::Rll;
  v.tree = m_view.tree;
  v.rll = &m_view;
  v.prepares = true;
  v.learns = !m_frozen;
  return v;
}

size_t RllLightSampler::bytes() const {
  return m_table->bytes() + m_cuts->bytes() +
         m_s.capacity * (sizeof(uint32_t) + kPointWords * sizeof(int64_t)) +
         m_power_prefix.size() * sizeof(double) + m_scratch.bytes();
}

RllLearnView RllLightSampler::learn_view() {
  RllLearnView v;
  v.cuts = m_cuts->end_view();
  v.table = m_table->view();
  v.free_room = m_table->free_room();
  v.last_used = view_of(m_last_used);
  v.points = view_of(m_points);
  v.keyer = m_keyer;
  v.origin = m_origin;
  v.extent = m_extent;
  v.capacity = m_s.capacity;
  return v;
}

ResidentState RllLightSampler::resident_state() {
  sync();
  return {learn_view(), &m_view, &m_pool};
}

void RllLightSampler::lend_to(DeviceCopy& copy) {
  if (m_remote != &copy) sync();
  m_remote = &copy;
}

void RllLightSampler::sync() const {
  if (!m_remote) return;
  DeviceCopy* const remote = m_remote;
  m_remote = nullptr;
  remote->pull(m_pool);
}

void RllLightSampler::end_pass() {
  if (!m_remote) return end_pass_with({});
  end_pass_with([&](const RllLearnView& v, RllPoolState<HostBackend>&, uint32_t used_before,
                    bool reset) { return m_remote->end_pass(v, used_before, reset); });
}

void RllLightSampler::end_pass_with(const EndPassRun& run) {
  if (m_frozen) return;
  const bool reset = m_s.reset_every > 0 && (m_pass + 1) % m_s.reset_every == 0;
  const RllPassCounts c =
      run ? run(learn_view(), m_pool, m_table->used(), reset)
          : rll_end_pass(HostBackend{}, learn_view(), m_pool, m_scratch, m_table->used(), reset);
  m_table->rebuilt(c.used);
  if (m_s.cut.pool_levels > 0) m_pool_changes_per_pass.push_back(c.pool_changes);
  m_changes_per_pass.push_back(c.changes);
  m_splits_per_pass.push_back(c.splits);
  m_collapses_per_pass.push_back(c.collapses);
  m_touched_per_pass.push_back(c.touched);
  if (m_s.cut.refine > 0) m_refined_per_pass.push_back(c.refined);
  m_failed_inserts += c.failed;
  m_evictions += c.evicted;
  if (c.failed > 0 && !m_warned_full) {
    // Said once: points without a cell sample like the tree and teach nothing.
    fmt::print(stderr,
               "rll: warning: {0}'s cell table is full ({0}.capacity={1}): {2} points this pass "
               "found no cell and sampled without learning; raise {0}.capacity\n",
               m_s.name, m_s.capacity, c.failed);
    m_warned_full = true;
  }
  ++m_pass;
  m_keyer.set_pass(m_pass, 0);
  m_resets += reset;
  refresh_view();
}

void RllLightSampler::lights_changed(const Scene& scene) {
  refresh_light_powers(scene);
  if (m_remote)
    m_remote->lights_changed(m_tree.view(), view_of(std::as_const(m_power_prefix)));
  else
    rll_lights_changed(HostBackend{}, learn_view(), m_pool, m_scratch);
  refresh_view();
}

void RllLightSampler::save_state(BinaryWriter& w) const {
  sync();
  w.put(m_s.capacity);
  w.put(m_pass);
  w.put(m_resets);
  w.put(m_table->used());
  for (uint32_t c = 0; c < m_s.capacity; ++c) {
    if (!m_table->in_use(c)) continue;
    w.put(c);
    w.put(m_table->key_of(c));
    w.put(m_last_used[c]);
    m_cuts->save_cell(c, w);
  }
  if (m_s.cut.pool_levels > 0) {  // the coarse cells, in key order
    const size_t K = m_cuts->initial_size();
    w.put(uint32_t(m_pool.keys.size()));
    for (size_t i = 0; i < m_pool.keys.size(); ++i) {
      w.put(m_pool.keys[i]);
      w.put_array(&m_pool.q[i * K], K);
      w.put_array(&m_pool.m2[i * K], K);
      w.put_array(&m_pool.n[i * K], K);
    }
  }
}

void RllLightSampler::load_state(BinaryReader& r) {
  sync();
  auto damaged = [&](const std::string& what) {
    fail("cannot read '{}': the file is damaged ({})", r.name(), what);
  };
  if (r.get<uint32_t>() != m_s.capacity) damaged("its cell table has another capacity");
  const uint64_t pass = r.get<uint64_t>(), resets = r.get<uint64_t>();
  const uint32_t used = r.get<uint32_t>();
  if (used > m_s.capacity) damaged("more cells than the table holds");
  for (uint32_t c = 0; c < m_s.capacity; ++c) {
    m_cuts->clear(c);
    m_last_used[c] = 0;
  }
  std::vector<uint64_t> key_of(m_s.capacity, 0);
  long previous = -1;
  for (uint32_t i = 0; i < used; ++i) {
    const uint32_t c = r.get<uint32_t>();
    if (c >= m_s.capacity || long(c) <= previous) damaged("a cell id out of order");
    previous = long(c);
    key_of[c] = r.get<uint64_t>();
    if (key_of[c] == 0) damaged("a cell without a key");
    const uint32_t last = r.get<uint32_t>();
    if (last > pass) damaged("a cell used after the last pass");
    m_last_used[c] = last;
    m_cuts->load_cell(c, r);
  }
  m_pool.clear(HostBackend{});
  if (m_s.cut.pool_levels > 0) {
    const size_t K = m_cuts->initial_size();
    const uint32_t count = r.get<uint32_t>();
    if (count > uint64_t(used) * uint64_t(m_s.cut.pool_tiers()))
      damaged("more coarse cells than cells");
    uint64_t last = 0;
    for (uint32_t i = 0; i < count; ++i) {
      const uint64_t key = r.get<uint64_t>();
      if (i > 0 && key <= last) damaged("coarse cells out of order");
      last = key;
      m_pool.keys.push_back(key);
      for (auto* a : {&m_pool.q, &m_pool.m2, &m_pool.n}) a->resize(m_pool.keys.size() * K);
      const size_t at = (m_pool.keys.size() - 1) * K;
      r.get_array(&m_pool.q[at], K);
      r.get_array(&m_pool.m2[at], K);
      r.get_array(&m_pool.n[at], K);
      const auto& q = m_pool.q;
      const auto& m2 = m_pool.m2;
      const auto& n = m_pool.n;
      for (size_t k = at; k < at + K; ++k)
        if (!((q[k] >= 0 || q[k] == -1) && std::isfinite(q[k]) && m2[k] >= 0 &&
              std::isfinite(m2[k]) && n[k] >= 0 && std::isfinite(n[k])))
          damaged("a coarse cell's value is negative or not finite");
    }
  }
  if (r.remaining() != 0) damaged("bytes after the last cell");
  if (!m_table->restore(key_of)) damaged("a cell key twice");
  std::fill(m_points.begin(), m_points.end(), 0);
  m_pass = pass;
  m_resets = resets;
  m_keyer.set_pass(m_pass, 0);
  if (m_s.cut.pool_levels > 0) rll_give_pool_shares(HostBackend{}, learn_view(), m_pool, m_scratch);
  refresh_view();
}

nlohmann::json RllLightSampler::describe() const {
  sync();
  double mean_cut = 0;
  uint32_t active = 0, refined = 0;
  for (uint32_t c = 0; c < m_s.capacity; ++c) {
    if (m_cuts->active(c)) {
      mean_cut += m_cuts->size(c);
      ++active;
    }
    refined += m_table->in_use(c) && m_cuts->refined(c);
  }
  nlohmann::json j = {
      {"name", name()},
      {"parameters", rll_parameters_json(m_s)},
      {"resets", m_resets},
      {"passes", m_pass},
      {"cells_used", m_table->used()},
      {"cells_capacity", m_s.capacity},
      {"cells_with_cut", active},
      {"evictions", m_evictions},
      {"failed_inserts", m_failed_inserts},
      {"mean_cut_size", active ? mean_cut / active : 0.0},
      {"pool_cells", m_pool.keys.size()},
      {"splits_per_pass", m_splits_per_pass},
      {"collapses_per_pass", m_collapses_per_pass},
      {"cells_touched_per_pass", m_touched_per_pass},
      {"changes_per_pass", m_changes_per_pass},
      {"pool_changes_per_pass", m_pool_changes_per_pass},
      {"bytes", bytes()},
  };
  if (m_s.cut.refine > 0) {
    j["cells_refined"] = refined;
    j["refined_per_pass"] = m_refined_per_pass;
  }
  return j;
}

}  // namespace rll
