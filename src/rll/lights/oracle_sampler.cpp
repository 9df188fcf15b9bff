#include "rll/lights/oracle_sampler.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>

#include "rll/accel/accel.h"
#include "rll/core/error.h"
#include "rll/core/long_work.h"
#include "rll/core/memory_budget.h"
#include "rll/core/parallel.h"
#include "rll/core/params.h"
#include "rll/core/rng.h"
#include "rll/core/sampling.h"
#include "rll/learn/cut_store.h"
#include "rll/learn/split_collapse.h"
#include "rll/lights/light_dispatch.h"
#include "rll/lights/tree_sampler.h"
#include "rll/lighttree/light_tree.h"
#include "rll/scene/interaction.h"

namespace rll {

const std::vector<ParamSpec<OracleSettings>>& oracle_params() {
  using S = OracleSettings;
  using R = ParamRange;
  static const std::vector<ParamSpec<S>> table = {
      int_param("discovery_spp", R::closed(1, 1024), field<S, &S::discovery_spp>()),
      int_param("bounces", R::closed(0, 16), field<S, &S::bounces>()),
      int_param("points", R::closed(1, 4096), field<S, &S::points_per_cell>()),
      int_param("rays", R::closed(1, 4096), field<S, &S::rays>()),
      int_param("refine", R::closed(0, 4096), field<S, &S::refine>()),
  };
  return table;
}

OracleSettings oracle_settings_from(const Params& p) {
  OracleSettings s;
  read_params(oracle_params(), p, "oracle", s);
  return s;
}

namespace {

struct CellPoint {
  uint32_t cell;
  uint64_t order;  // random key: the kept points of a cell are those with the smallest keys
  LightContext ctx;
};

// Occluded contribution of the lights under `node` at the points, irradiance-like (cosine
// at the point, no BSDF): mean of f/p over points x rays, the light chosen by the tree's
// descent inside the node.
double estimate(const Scene& scene, const LightTree& tree, const Accel& accel, uint32_t node,
                const std::vector<LightContext>& pts, int rays, Pcg32& rng, uint64_t& traced) {
  double sum = 0;
  for (const LightContext& x : pts) {
    if (cancel_requested()) break;  // the render that follows stops too
    for (int r = 0; r < rays; ++r) {
      const TreeSample t = tree_descend(tree, node, x.p, x.n, rng.next_double());
      Vec2 u{rng.next_float(), rng.next_float()};
      if (!(t.pmf > 0)) continue;
      const Light& light = scene.lights[t.light];
      const TexelView image =
          light.has_image() ? scene.textures[light.triangle].texel_view() : TexelView{};
      LightLiSample ls = sample_li(light, x.p, u, &image);
      if (!(ls.pdf > 0)) continue;
      float cos = dot(ls.wi, x.ns);
      if (cos <= 0 || dot(ls.wi, x.n) <= 0) continue;
      ++traced;
      if (accel.occluded(
              shadow_ray_to_light(x.p, x.n, light, ls, scene.bounds.center(), scene.radius)))
        continue;
      sum += double(luminance(ls.L)) * cos / ls.pdf / t.pmf;
    }
  }
  return sum / double(pts.size() * size_t(rays));
}

// An estimate as the cuts keep it: a float, and finite where a light's radiance is near a
// float's largest (the cuts' sums would turn to inf and their probabilities to NaN).
float finite_estimate(double e) {
  constexpr float kMax = std::numeric_limits<float>::max();
  return e > double(kMax) ? kMax : float(e);
}

}  // namespace

OracleLightSampler::OracleLightSampler(const Scene& scene, const LightTree& tree,
                                       const Accel& accel, const RllSettings& rll,
                                       const OracleSettings& s)
    : LightSampler("oracle"), m_s(s), m_tree(tree), m_accel(accel), m_rll_settings(rll) {
  precompute(scene);
}

void OracleLightSampler::lights_changed(const Scene& scene) {
  precompute(scene);
}

void OracleLightSampler::precompute(const Scene& scene) {
  const OracleSettings& s = m_s;
  const Accel& accel = m_accel;
  const RllSettings& rll = m_rll_settings;
  auto t0 = std::chrono::steady_clock::now();
  RllSettings fixed = rll;
  fixed.grid.jitter = 0;          // one fixed grid: the oracle's cells never move
  fixed.cut.guided = false;       // the oracle knows each cluster's contribution: a table per cell
  fixed.grid.direction_bins = 0;  // its discovery paths find cells by position and normal only
  fixed.cut.pool_levels = 0;      // it knows each cell's clusters: nothing to pool
  fixed.cut.pool_up = 0;
  m_rll = std::make_unique<RllLightSampler>(scene, m_tree, fixed);
  set_learnt_cells({m_rll.get(), this});
  const SamplerView view = m_rll->sampler_view();  // its cells found as a render finds them
  const LightTree& tree = m_tree;

  // 1. Discovery: camera paths (diffuse bounces) find the cells and points where NEE happens.
  const int w = scene.width, h = scene.height;
  // Every vertex of every discovery path may keep a point (closed rooms come near that).
  check_memory_budget(double(w) * h * s.discovery_spp * (s.bounces + 1) * sizeof(CellPoint),
                      fmt::format("the oracle's discovery ({}x{} pixels x oracle.discovery_spp={} "
                                  "x (oracle.bounces={} + 1) points)",
                                  w, h, s.discovery_spp, s.bounces));
  std::mutex merge;
  std::vector<CellPoint> found;
  m_interrupted = false;
  LongWork discovery("the oracle's discovery", uint64_t(h), "rows of pixels");
  parallel_for(size_t(h), 1, [&](size_t y0, size_t y1) {
    std::vector<CellPoint> local;
    for (size_t y = y0; y < y1; ++y) {
      if (cancel_requested()) break;
      for (int x = 0; x < w; ++x)
        for (int k = 0; k < s.discovery_spp; ++k) {
          SampleStream st(s.seed, y * w + x, uint64_t(k));
          Vec2 j = st.next2();
          Ray ray = scene.camera.generate_ray(x + j.x, float(y) + j.y);
          float footprint = 0, prev_pdf = 1 / sqr(scene.camera.pixel_angle());
          for (int depth = 0; depth <= s.bounces; ++depth) {
            Hit hit;
            if (!accel.intersect(ray, hit)) break;
            SurfaceHit sh = make_surface_hit(scene, hit);
            if (scene.is_sky_triangle(sh.tri)) break;
            LightContext c;
            c.n = face_forward(sh.ng, -ray.d);
            c.ns = dot(sh.ns, c.n) < 0 ? -sh.ns : sh.ns;
            c.p = sh.p;
            footprint = widen_footprint(footprint, hit.t, prev_pdf, ray.d, sh.ng);
            c.footprint = footprint;
            prepare_point(view, c, st.next());
            if (c.cell != kNoCell) local.push_back({c.cell, mix64(st.next_double() * 0x1p53), c});
            Vec3 d = Frame(c.ns).to_world(sample_cosine_hemisphere(st.next2()));
            if (dot(d, c.n) <= 0) break;
            prev_pdf = std::max(1e-3f, dot(d, c.ns) * kInvPi);
            ray = spawn_ray(c.p, c.n, d);
          }
        }
      discovery.add(1);
    }
    std::lock_guard lock(merge);
    found.insert(found.end(), local.begin(), local.end());
  });
  // Deterministic whatever the thread count: order by (cell key, random key).
  const CellTable& table = m_rll->table();
  std::sort(found.begin(), found.end(), [&](const CellPoint& a, const CellPoint& b) {
    uint64_t ka = table.key_of(a.cell), kb = table.key_of(b.cell);
    return ka != kb ? ka < kb : a.order < b.order;
  });
  std::vector<std::pair<size_t, size_t>> ranges;  // per cell: [begin, end) in found
  for (size_t i = 0; i < found.size();) {
    size_t j = i;
    while (j < found.size() && found[j].cell == found[i].cell) ++j;
    ranges.push_back({i, std::min(j, i + size_t(s.points_per_cell))});
    i = j;
  }
  m_cells = uint32_t(ranges.size());

  // 2. Per cell: every cluster of the initial cut estimated with shadow rays, then greedy
  // split-collapse on the estimates (split the largest, collapse the smallest twin pair).
  CutStore& cuts = m_rll->cuts();
  const int M = rll.cut.cut_size;
  const std::vector<uint32_t> initial = initial_cut(tree, M);
  // Its cost, known now and checked before a ray is traced: the settings' ranges allow plans of
  // hours (oracle.points=4096:rays=4096). Each refinement step estimates two children; a cut
  // that can hold every light stops splitting once it has.
  const size_t steps =
      tree.light_count() > size_t(M)
          ? size_t(s.refine)
          : std::min(size_t(s.refine),
                     tree.light_count() - std::min(tree.light_count(), initial.size()));
  double planned = 0;
  for (const auto& [begin, end] : ranges) planned += double(end - begin);
  planned *= double(s.rays) * double(initial.size() + 2 * steps);
  if (planned > kMaxOracleShadowRays)
    fail(
        "the oracle would trace about {:.3g} shadow rays before rendering ({} cells x up to "
        "oracle.points={} points x oracle.rays={} rays x ({} clusters + 2 x {} of oracle.refine={} "
        "steps)), more than {:.3g}; lower oracle.points, oracle.rays or oracle.refine",
        planned, ranges.size(), s.points_per_cell, s.rays, initial.size(), steps, s.refine,
        kMaxOracleShadowRays);
  m_cell_rays.assign(ranges.size(), {kNoCell, 0.0f});
  LongWork progress(fmt::format("the oracle's estimates (about {:.3g} shadow rays)", planned),
                    ranges.size(), "cells");
  std::atomic<uint64_t> rays{0};
  const SplitCollapse split_collapse(tree, M, 1.0f);
  parallel_for(ranges.size(), 1, [&](size_t b, size_t e) {
    uint64_t traced = 0;
    for (size_t r = b; r < e; ++r) {
      if (cancel_requested()) break;  // cells not reached sample like the light tree
      const uint64_t traced_before = traced;
      std::vector<LightContext> pts;
      for (size_t i = ranges[r].first; i < ranges[r].second; ++i) pts.push_back(found[i].ctx);
      const uint32_t cell = found[ranges[r].first].cell;
      Pcg32 rng(s.seed, table.key_of(cell));
      // The learnt cuts' step (split_collapse.h) with q = value = score = the estimate and
      // T = 1: split the largest, collapse the smallest sibling pair (their estimates add); the
      // children of a split are then estimated, not shared. The estimates are never negative, so
      // the step's refusal to split a cluster of value 0 is the collapse test's.
      Cut cut;
      cut.nodes = initial;
      cut.q.resize(initial.size());
      for (size_t k = 0; k < initial.size(); ++k)
        cut.q[k] =
            finite_estimate(estimate(scene, tree, accel, initial[k], pts, s.rays, rng, traced));
      cut.m2.assign(initial.size(), 0.0f);  // unused: the oracle keeps no second moment
      cut.n.assign(initial.size(), 0.0f);
      cut.weight.assign(initial.size(), 0.0f);
      std::vector<float> value = cut.q, score = cut.q;
      auto no_weight = [](uint32_t) { return 0.0f; };
      auto halves = [](uint32_t) { return 1.0f; };  // overwritten by the children's estimates
      for (int step = 0; step < s.refine; ++step) {
        long at = -1;
        if (!split_collapse.step(cut, value, score, no_weight, halves, &at)) break;
        for (const long i : {at, at + 1})
          cut.q[i] = value[i] = score[i] =
              finite_estimate(estimate(scene, tree, accel, cut.nodes[i], pts, s.rays, rng, traced));
      }
      if (cancel_requested()) break;  // its estimates were cut short: it keeps no cut
      cuts.assign(cell, cut.nodes, value);
      m_cell_rays[r] = {cell, float(traced - traced_before)};
      progress.add(1);
    }
    rays += traced;
  });
  m_rays = rays.load();
  m_interrupted = cancel_requested();
  std::sort(m_cell_rays.begin(), m_cell_rays.end());
  m_rll->freeze();
  m_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

nlohmann::json OracleLightSampler::describe() const {
  nlohmann::json j = m_rll->describe();
  j["name"] = name();
  nlohmann::json& oracle = j["oracle"] = nlohmann::json::object();
  params_json(oracle_params(), m_s, oracle);
  oracle["cells"] = m_cells;
  oracle["shadow_rays"] = m_rays;
  oracle["precompute_seconds"] = m_seconds;
  if (m_interrupted) oracle["interrupted"] = true;
  return j;
}

float OracleLightSampler::shadow_rays_of(uint32_t cell) const {
  const auto it = std::lower_bound(m_cell_rays.begin(), m_cell_rays.end(),
                                   std::pair<uint32_t, float>{cell, 0.0f});
  return it != m_cell_rays.end() && it->first == cell ? it->second
                                                      : std::numeric_limits<float>::quiet_NaN();
}

}  // namespace rll
