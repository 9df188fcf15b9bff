#include "rll/lights/rll_study.h"

#include <algorithm>
#include <bit>
#include <cmath>

#include "rll/accel/accel.h"
#include "rll/core/hash.h"
#include "rll/core/memory_budget.h"
#include "rll/core/rng.h"
#include "rll/core/search.h"
#include "rll/lights/light_dispatch.h"
#include "rll/scene/interaction.h"
#include "rll/scene/scene.h"

namespace rll {

namespace {

// Where sampling departs from rll's: a cell with its own cut, sampled by its baked table.
bool applies(const RllView& v, const LightContext& ctx) {
  return detail::rll_has_cut(v, ctx.cell) && !v.guided && v.defensive == Defensive::Cell;
}

// The index in [0, size) whose CDF interval holds x (zero-width entries never returned).
uint32_t cdf_index(const std::vector<float>& cdf, float x) {
  uint32_t i = upper_bound_index(cdf.data(), 0u, uint32_t(cdf.size()), x);
  i = std::min(i, uint32_t(cdf.size()) - 1);
  while (i > 0 && cdf[i] == cdf[i - 1]) --i;
  return i;
}

float cdf_width(const std::vector<float>& cdf, uint32_t i) {
  return i > 0 ? cdf[i] - cdf[i - 1] : cdf[0];
}

}  // namespace

size_t IdealLightSampler::KeyHash::operator()(const Key& k) const {
  return size_t(mix64(k.cell_key ^ (uint64_t(k.node) * 0x9e3779b97f4a7c15ull)));
}

IdealLightSampler::IdealLightSampler(std::unique_ptr<LightSampler> inner, const Scene& scene,
                                     const Accel& accel, uint32_t rays, bool at_point)
    : LightSampler(inner->name(), inner->has_state()),
      m_inner(std::move(inner)),
      m_accel(accel),
      m_rays(rays),
      m_at_point(at_point),
      m_shards(new Shard[kShards]) {
  m_budget_bytes = double(memory_budget_bytes()) / 4;
  copy_lights(scene);
  m_inner_view = m_inner->sampler_view();
  set_host_calls(*this);
}

SamplerView IdealLightSampler::sampler_view() const {
  return host_view(m_inner_view.prepares, m_inner_view.learns);
}

void IdealLightSampler::end_pass() {
  m_inner->end_pass();
  m_inner_view = m_inner->sampler_view();
}

void IdealLightSampler::copy_lights(const Scene& scene) {
  m_lights = scene.lights;
  m_images.assign(m_lights.size(), TexelView{});
  for (size_t l = 0; l < m_lights.size(); ++l)
    if (m_lights[l].has_image()) m_images[l] = scene.textures[m_lights[l].triangle].texel_view();
  m_center = scene.bounds.center();
  m_radius = scene.radius;
}

void IdealLightSampler::lights_changed(const Scene& scene) {
  m_inner->lights_changed(scene);
  copy_lights(scene);
  m_inner_view = m_inner->sampler_view();
  for (int i = 0; i < kShards; ++i) m_shards[i].tables.clear();
  m_bytes = 0;
}

void IdealLightSampler::load_state(BinaryReader& r) {
  m_inner->load_state(r);
  m_inner_view = m_inner->sampler_view();
}

nlohmann::json IdealLightSampler::describe() const {
  nlohmann::json j = m_inner->describe();
  j["study"] = {{"ideal_light", m_rays},
                {"ideal_light_at", m_at_point ? "point" : "anchor"},
                {"tables", m_tables.load()},
                {"table_bytes", m_bytes.load()},
                {"shadow_rays", m_rays_traced.load()},
                {"lookups_over_budget", m_full.load()}};
  return j;
}

IdealLightSampler::Table IdealLightSampler::compute(const Vec3& p, const Vec3& normal,
                                                    uint32_t begin, uint32_t end,
                                                    uint64_t seed) const {
  const float len = length(normal);
  Table t;
  if (!(len > 0)) return t;
  const Vec3 n = normal / len;
  Pcg32 rng(0x1dea1u, seed);
  std::vector<double> e(end - begin, 0.0);
  uint64_t traced = 0;
  for (uint32_t l = begin; l < end; ++l) {
    const Light& light = m_lights[l];
    const TexelView& image = m_images[l];
    const uint32_t rays = light.is_delta() ? 1 : m_rays;  // a delta light has one point
    const Vec2 shift{rng.next_float(), rng.next_float()};
    double sum = 0;
    for (uint32_t r = 0; r < rays; ++r) {
      const LightLiSample ls = sample_li(light, p, rotated_hammersley(r, rays, shift), &image);
      if (!(ls.pdf > 0)) continue;
      const float cos = dot(ls.wi, n);
      if (!(cos > 0)) continue;
      const float value = luminance(ls.L) * cos / ls.pdf;
      if (!(value > 0) || !std::isfinite(value)) continue;
      ++traced;
      if (m_accel.occluded(shadow_ray_to_light(p, n, light, ls, m_center, m_radius))) continue;
      sum += double(value);
    }
    e[l - begin] = sum / double(rays);
  }
  m_rays_traced += traced;
  double total = 0;
  for (double x : e) total += x;
  if (!(total > 0) || !std::isfinite(total)) return t;
  t.cdf.resize(e.size());
  double run = 0;
  for (size_t i = 0; i < e.size(); ++i) {
    run += e[i];
    t.cdf[i] = float(run / total);
  }
  t.cdf.back() = 1.0f;
  return t;
}

const IdealLightSampler::Table* IdealLightSampler::table(const RllView& v, const LightContext& ctx,
                                                         uint32_t k, Table& scratch) const {
  const detail::RllCut c = detail::rll_cut(v, ctx.cell);
  const uint32_t begin = detail::rll_begin(c, k), end = c.ends[k];
  if (m_at_point) {
    // At the shading point itself: computed for every sample and pmf, seeded by the point.
    uint64_t h = c.nodes[k];
    for (float x : {ctx.p.x, ctx.p.y, ctx.p.z, ctx.n.x, ctx.n.y, ctx.n.z})
      h = mix64(h ^ std::bit_cast<uint32_t>(x));
    scratch = compute(ctx.p, ctx.n, begin, end, h);
    return &scratch;
  }
  const Key key{v.table.key_of[ctx.cell], c.nodes[k]};
  Shard& shard = m_shards[KeyHash{}(key) % kShards];
  {
    std::lock_guard lock(shard.mutex);
    if (auto it = shard.tables.find(key); it != shard.tables.end()) return it->second.get();
  }
  if (double(m_bytes.load()) >= m_budget_bytes) {
    ++m_full;
    return nullptr;
  }
  // Computed outside the lock; a function of the key alone, so a table two threads compute at
  // once is the same table (renders stay the same for any thread count).
  const CellAnchor& a = v.cuts.anchor[ctx.cell];
  auto made =
      std::make_unique<Table>(compute(a.p, a.n, begin, end, mix64(key.cell_key ^ key.node)));
  std::lock_guard lock(shard.mutex);
  auto [it, inserted] = shard.tables.try_emplace(key, std::move(made));
  if (inserted) {
    m_bytes += it->second->cdf.size() * sizeof(float) + sizeof(Table) + sizeof(Key);
    ++m_tables;
  }
  return it->second.get();
}

float IdealLightSampler::within_pmf(const RllView& v, const LightContext& ctx, uint32_t k,
                                    uint32_t l, const Table* t) const {
  const detail::RllCut c = detail::rll_cut(v, ctx.cell);
  const uint32_t begin = detail::rll_begin(c, k);
  const float rule = detail::rll_pmf_within(v, ctx, c.nodes[k], begin, c.ends[k], l);
  if (!t || t->cdf.empty()) return rule;
  return kDefensive * rule + (1 - kDefensive) * cdf_width(t->cdf, l - begin);
}

void IdealLightSampler::prepare(LightContext& ctx, float u) const {
  prepare_point(m_inner_view, ctx, u);
}

SampledLight IdealLightSampler::sample(const LightContext& ctx, double u) const {
  const RllView& v = *m_inner_view.rll;
  if (!applies(v, ctx)) return rll_sample(v, ctx, u);
  const detail::RllCut c = detail::rll_cut(v, ctx.cell);
  uint32_t k = 0;
  double uw = 0;
  if (!detail::rll_table_draw(c, u, &k, &uw)) return {};
  const uint32_t begin = detail::rll_begin(c, k), end = c.ends[k];
  Table scratch;
  const Table* t = table(v, ctx, k, scratch);
  uint32_t l;
  if (!t || t->cdf.empty()) {
    l = detail::rll_sample_within(v, ctx, c.nodes[k], begin, end, uw).light;
  } else if (uw < kDefensive) {
    l = detail::rll_sample_within(v, ctx, c.nodes[k], begin, end, uw / kDefensive).light;
  } else {
    l = begin + cdf_index(t->cdf, float((uw - kDefensive) / (1 - kDefensive)));
  }
  ClusterDraw d;
  d.cluster = k;
  d.cluster_pmf = detail::rll_cdf_width(c, k);
  d.target = v.cuts.vis[size_t(ctx.cell) * v.cuts.m + k];
  SampledLight s;
  s.light = l;
  s.pmf = d.cluster_pmf * within_pmf(v, ctx, k, l, t);
  set_cluster_draw(s, d);
  return s.pmf > 0 ? s : SampledLight{};
}

float IdealLightSampler::pmf(const LightContext& ctx, uint32_t light) const {
  const RllView& v = *m_inner_view.rll;
  if (!applies(v, ctx)) return rll_pmf(v, ctx, light);
  const detail::RllCut c = detail::rll_cut(v, ctx.cell);
  const uint32_t k = detail::rll_cluster_of(c, light);
  if (k >= c.size) return 0;
  Table scratch;
  return detail::rll_cdf_width(c, k) * within_pmf(v, ctx, k, light, table(v, ctx, k, scratch));
}

void IdealLightSampler::record(const LightContext& ctx, const SampledLight& s, const NeeRecord& r) {
  record_nee(m_inner_view, ctx, s, r);
}

}  // namespace rll
