// The data of the report's cell chart: which cell of a learning sampler (rll, fermat) the camera
// ray of each probed pixel first hits, and per such cell the probability of each cluster of its
// cut as the sampler's baked table holds it, as the light tree gives it and as the oracle gives
// it, so that a reader can click a pixel and see what the cell learnt against its prior.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "rll/render/integrator.h"

namespace rll {

class Accel;
class LightSampler;
class RllLightSampler;
struct Scene;

// At most this many probes and distinct cells per chart: the report embeds at most 24 clusters
// and one sum a cell (about 0.75 kB), so the chart's data stay under about 1.5 MB.
inline constexpr int kCellChartMaxProbes = 16384;
inline constexpr int kCellChartMaxCells = 2048;
// The oracle's bars cost one pmf per light and cell; above this product they are left out.
inline constexpr double kCellChartMaxOracleWork = 2e8;

struct CellChartCell {
  uint32_t cell = 0;     // its id in the sampler's table
  int level = 0;         // level of detail: the cell's edge is 2^level x the scene's diameter
  bool has_cut = false;  // false: not learnt yet; it samples the initial cut by the light tree
  // Per cluster of its cut: the lights [begin, end) (light tree order, the scene's light index).
  std::vector<uint32_t> begin, end;
  // Per cluster: the learnt probability (the width of the cluster's interval in the cell's baked
  // CDF, the defensive prior folded in, as sampling uses it; the tree's where there is no cut),
  // the light tree's (the probability that a descent from the root reaches the cluster's node:
  // the sum of the tree sampler's pmf over its lights) and the oracle's (the sum of its pmf over
  // the cluster's lights; empty without an oracle). Tree and oracle are taken at the cell's first
  // probe point.
  std::vector<float> learnt, tree, oracle;
};

struct CellChart {
  std::string sampler;  // the sampler whose image the chart belongs to
  // Probes: one per block of stride x stride pixels, at the centre of the block's middle pixel
  // (clamped to the image), columns x rows of them, row by row.
  int stride = 1, columns = 0, rows = 0;
  std::vector<int32_t> probe_cell;  // per probe: an index into `cells`, or -1 (no cell there)
  std::vector<CellChartCell> cells;
  bool has_oracle = false;
  std::string note;  // why the oracle's bars are missing, when an oracle was given
};

// Probes the image of `learnt` (after its render: its cells and baked tables as they ended) at
// the smallest stride whose probes are at most kCellChartMaxProbes and meet at most
// kCellChartMaxCells distinct cells. A pixel has no cell where the camera ray leaves the scene,
// or hits a surface that takes no light sample (Dirac BSDF), or where the sampler's table holds
// no cell for the point (it is looked up, never inserted). `oracle` may be null.
CellChart cell_chart(const Scene& scene, const Accel& accel, const IntegratorSettings& settings,
                     const RllLightSampler& learnt, const std::string& name,
                     const LightSampler* oracle);

}  // namespace rll
