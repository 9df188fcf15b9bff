// The report's cell chart (eval/cell_chart.h) after a short rll render: every probe points at a
// cell of the sampler's table, the learnt bars are the sampler's own cluster probabilities, the
// tree's and the oracle's sum to 1 over the cut, and the probes' stride grows to keep the cells
// and probes bounded.
#include <gtest/gtest.h>

#include <set>

#include "rll/accel/accel.h"
#include "rll/core/params.h"
#include "rll/eval/cell_chart.h"
#include "rll/lights/light_dispatch.h"
#include "rll/lights/rll_sampler.h"
#include "rll/render/film.h"
#include "rll/render/render.h"
#include "support/test_support.h"

using namespace rll;

namespace {

struct Rendered {
  Scene scene;
  LightTree tree;
  Accel accel;
  IntegratorSettings settings;
  std::unique_ptr<LightSampler> rll, oracle;
  Rendered(Scene s, int spp)
      : scene(std::move(s)), tree(build_light_tree(scene)), accel(scene.mesh) {
    settings.type = IntegratorType::Direct;
    rll = make_light_sampler("rll", scene, tree, Params{}, &accel);
    Params fast = Params::parse({"oracle.points=2", "oracle.rays=1", "oracle.discovery_spp=2"});
    oracle = make_light_sampler("oracle", scene, tree, fast, &accel);
    Integrator integrator(scene, accel, *rll, settings);
    Film film(scene.width, scene.height);
    RenderSettings rs;
    rs.spp = spp;
    render(scene, integrator, *rll, film, rs);
  }
  const RllLightSampler& learnt() const { return dynamic_cast<const RllLightSampler&>(*rll); }
};

}  // namespace

TEST(CellChart, BarsAreTheSamplersClusterProbabilities) {
  const Rendered r(test::small_builtin_scene("cornell-boxes-room", 24, 18), 8);
  const CellChart c = cell_chart(r.scene, r.accel, r.settings, r.learnt(), "rll", r.oracle.get());
  EXPECT_EQ(c.sampler, "rll");
  EXPECT_EQ(c.stride, 1);
  ASSERT_EQ(c.probe_cell.size(), 24u * 18u);
  EXPECT_TRUE(c.has_oracle);
  std::set<uint32_t> ids;
  size_t probed = 0;
  for (int32_t p : c.probe_cell) {
    ASSERT_LT(p, int32_t(c.cells.size()));
    probed += p >= 0;
  }
  EXPECT_GT(probed, c.probe_cell.size() / 2);
  size_t with_cut = 0;
  for (const CellChartCell& cell : c.cells) {
    EXPECT_TRUE(ids.insert(cell.cell).second) << "cell " << cell.cell << " listed twice";
    ASSERT_EQ(cell.learnt.size(), cell.begin.size());
    ASSERT_EQ(cell.tree.size(), cell.begin.size());
    ASSERT_EQ(cell.oracle.size(), cell.begin.size());
    with_cut += cell.has_cut;
    // The learnt bar of a cluster is the sampler's probability of picking any of its lights in
    // that cell (the default defensive prior is folded into the cell's table, so the sum of pmf
    // over the cluster does not depend on the point).
    LightContext ctx;
    ctx.p = r.learnt().cuts().anchor(cell.cell).p;
    ctx.n = r.learnt().cuts().anchor(cell.cell).n;
    ctx.cell = cell.cell;
    double learnt = 0, tree = 0, oracle = 0;
    for (size_t k = 0; k < cell.begin.size(); ++k) {
      ASSERT_LT(cell.begin[k], cell.end[k]);
      if (k > 0) {
        EXPECT_EQ(cell.begin[k], cell.end[k - 1]);
      }
      double pmf = 0;
      for (uint32_t l = cell.begin[k]; l < cell.end[k]; ++l)
        pmf += light_pmf(r.rll->sampler_view(), ctx, l);
      // (Where the within-cluster descent finds no light facing the anchor, the sum is 0.)
      if (cell.has_cut && pmf > 0) {
        EXPECT_NEAR(cell.learnt[k], pmf, 1e-4) << "cell " << cell.cell << " cluster " << k;
      }
      learnt += cell.learnt[k];
      tree += cell.tree[k];
      oracle += cell.oracle[k];
    }
    EXPECT_EQ(cell.begin.front(), 0u);
    EXPECT_EQ(cell.end.back(), r.scene.lights.size());
    EXPECT_NEAR(learnt, 1, 1e-4);
    EXPECT_NEAR(oracle, 1, 1e-3);
    // A descent from the root reaches exactly one cluster of a cut, unless the point faces away
    // from every light (then none).
    if (tree != 0) {
      EXPECT_NEAR(tree, 1, 1e-4);
    }
  }
  EXPECT_GT(with_cut, c.cells.size() / 2);
}

TEST(CellChart, StrideGrowsToBoundProbesAndCells) {
  // 200 x 150 = 30000 pixels: over kCellChartMaxProbes, so one probe per 2 x 2 pixels at least.
  const Rendered r(test::small_builtin_scene("cornell-box", 200, 150), 1);
  const CellChart c = cell_chart(r.scene, r.accel, r.settings, r.learnt(), "rll", nullptr);
  EXPECT_GE(c.stride, 2);
  EXPECT_EQ(c.columns, (200 + c.stride - 1) / c.stride);
  EXPECT_EQ(c.rows, (150 + c.stride - 1) / c.stride);
  EXPECT_LE(c.probe_cell.size(), size_t(kCellChartMaxProbes));
  EXPECT_LE(c.cells.size(), size_t(kCellChartMaxCells));
  EXPECT_FALSE(c.has_oracle);
  for (const auto& cell : c.cells) EXPECT_TRUE(cell.oracle.empty());
}
