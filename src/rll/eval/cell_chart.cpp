#include "rll/eval/cell_chart.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "rll/accel/accel.h"
#include "rll/core/parallel.h"
#include "rll/lights/light_dispatch.h"
#include "rll/lights/rll_sampler.h"
#include "rll/lights/rll_view.h"
#include "rll/render/path_vertex.h"
#include "rll/scene/interaction.h"
#include "rll/scene/scene.h"
#include "rll/scene/scene_view.h"

namespace rll {

namespace {

// The shading context of a pixel centre's first hit, as the path's first vertex makes it; false
// where the ray leaves the scene or the surface takes no light sample.
bool first_vertex(const PathConstants& c, const Scene& scene, const Accel& accel, int x, int y,
                  LightContext& ctx) {
  const Ray ray = scene.camera.generate_ray(float(x) + 0.5f, float(y) + 0.5f);
  Hit hit;
  if (!accel.intersect(ray, hit)) return false;
  const SurfaceHit sh = make_surface_hit(c.scene.mesh, hit);
  const Vec3 wo = -ray.d;
  const Bsdf bsdf = make_vertex_bsdf(c, sh, wo, BsdfNumbers{}, 0);
  if (bsdf.is_black() || !samples_light(c, bsdf)) return false;
  PathState s = start_path(c);
  ctx = make_vertex_context(c, s, sh, hit, wo, bsdf);
  return length_sq(ctx.n) > 0;
}

// The cell rll_prepare would find for ctx, looked up without inserting one: the level of detail
// rounded to the nearest (u = 0.5 with stochastic rounding picks the nearer level), the pass's
// jitter as the last pass left it, no per-sample jitter.
uint32_t find_cell(const RllView& v, const LightContext& ctx) {
  const uint32_t cell = cell_find(v.table, v.keyer.key(rll_cell_coord(v, ctx, 0.5f, false)));
  return cell == CellTableView::kNone ? kNoCell : cell;
}

}  // namespace

CellChart cell_chart(const Scene& scene, const Accel& accel, const IntegratorSettings& settings,
                     const RllLightSampler& learnt, const std::string& name,
                     const LightSampler* oracle) {
  CellChart chart;
  chart.sampler = name;
  const SamplerView sv = learnt.sampler_view();
  const RllView& v = *sv.rll;
  const SceneData data(scene);
  const PathConstants c = make_path_constants(scene, data.view(), settings);
  const int w = scene.width, h = scene.height;

  // Probe; widen the stride while there are too many probes or cells (each try stops at the
  // first cell over the cap, so a try costs at most kCellChartMaxProbes rays).
  int stride = std::max(1, int(std::ceil(std::sqrt(double(w) * h / kCellChartMaxProbes))));
  std::vector<LightContext> first_point;  // per chart cell: its first probe's context
  std::unordered_map<uint32_t, int32_t> index;
  for (;; ++stride) {
    chart.stride = stride;
    chart.columns = (w + stride - 1) / stride;
    chart.rows = (h + stride - 1) / stride;
    if (size_t(chart.columns) * chart.rows > size_t(kCellChartMaxProbes)) continue;
    chart.probe_cell.assign(size_t(chart.columns) * chart.rows, -1);
    index.clear();
    first_point.clear();
    bool too_many = false;
    for (int j = 0; j < chart.rows && !too_many; ++j)
      for (int i = 0; i < chart.columns; ++i) {
        const int x = std::min(w - 1, i * stride + stride / 2);
        const int y = std::min(h - 1, j * stride + stride / 2);
        LightContext ctx;
        if (!first_vertex(c, scene, accel, x, y, ctx)) continue;
        const uint32_t cell = find_cell(v, ctx);
        if (cell == kNoCell) continue;
        auto [it, added] = index.emplace(cell, int32_t(first_point.size()));
        if (added) {
          ctx.cell = cell;
          first_point.push_back(ctx);
          if (first_point.size() > size_t(kCellChartMaxCells)) {
            too_many = true;
            break;
          }
        }
        chart.probe_cell[size_t(j) * chart.columns + i] = it->second;
      }
    if (!too_many) break;
  }

  const size_t lights = scene.lights.size();
  chart.has_oracle = oracle != nullptr;
  if (oracle && double(lights) * double(first_point.size()) > kCellChartMaxOracleWork) {
    chart.has_oracle = false;
    chart.note = fmt::format(
        "the oracle's bars are left out: {} lights x {} cells is over {:g} pmf evaluations", lights,
        first_point.size(), kCellChartMaxOracleWork);
  }
  std::vector<uint32_t> cell_ids(first_point.size());
  for (const auto& [cell, i] : index) cell_ids[size_t(i)] = cell;
  const SamplerView ov = chart.has_oracle ? oracle->sampler_view() : SamplerView{};
  chart.cells.resize(first_point.size());
  parallel_for_each(first_point.size(), [&](size_t i) {
    CellChartCell& out = chart.cells[i];
    const uint32_t cell = cell_ids[i];
    const LightContext& ctx = first_point[i];
    out.cell = cell;
    out.level = learnt.cuts().anchor(cell).level;
    out.has_cut = detail::rll_has_cut(v, cell);
    const detail::RllCut cut = detail::rll_cut(v, cell);
    LightContext oracle_ctx = ctx;
    if (chart.has_oracle) prepare_point(ov, oracle_ctx, 0.5f);
    for (uint32_t k = 0; k < cut.size; ++k) {
      const uint32_t begin = detail::rll_begin(cut, k), end = cut.ends[k];
      out.begin.push_back(begin);
      out.end.push_back(end);
      const float tree = tree_reach_pmf(v.tree, cut.nodes[k], ctx.p, ctx.n);
      out.tree.push_back(tree);
      if (out.has_cut)
        out.learnt.push_back(detail::rll_cdf_width(cut, k));
      else
        out.learnt.push_back(v.cold_uniform ? 1.0f / float(cut.size) : tree);
      if (chart.has_oracle) {
        double sum = 0;
        for (uint32_t l = begin; l < end; ++l) sum += light_pmf(ov, oracle_ctx, l);
        out.oracle.push_back(float(sum));
      }
    }
  });
  return chart;
}

}  // namespace rll
