// The settings of the learning samplers rll and fermat (RllSettings: the cut's, the cells' and
// the sampler's own), read from `--set rll.*` / `--set fermat.*` through one table per struct
// (core/param_table.h): each parameter's name and range are written once.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "rll/core/param_table.h"
#include "rll/learn/cell_grid.h"
#include "rll/learn/cut_params.h"
#include "rll/learn/cut_settings.h"
#include "rll/lights/rll_view.h"

namespace rll {

// rll's cut settings: CutSettings' own, with pooling one level up, in two tiers, by ratio to each
// cell's prior (docs/rll.md, "Pooling").
inline CutSettings rll_cut_defaults() {
  CutSettings c;
  c.pool_levels = 1;
  c.pool_up = 1;
  c.pool_ratio = true;
  return c;
}

struct RllSettings {
  std::string name = "rll";  // the sampler's name: rll, or fermat (the paper's settings)
  CutSettings cut = rll_cut_defaults();
  CellGridSettings grid;
  uint32_t capacity = 32768;  // cells
  WithinCluster within = WithinCluster::Tree;
  uint32_t descend_above = 16;  // Hybrid: clusters of more lights than this are descended
  RewardKind reward = RewardKind::Cluster;
  Defensive defensive = Defensive::Cell;
  // A cell without a cut yet (its first pass) samples the initial cut's clusters uniformly
  // (Fermat's cells start with every Q equal) instead of by the light tree.
  bool cold_uniform = false;
  // Per-sample jitter of the cell lookup (Fermat's, after Binder et al.): the point moves inside
  // a disk of this radius, in cell radii, in the tangent plane, and the normal by up to a
  // quarter bin. 0: off (rll.jitter is the per-pass jitter).
  float sample_jitter = 0;
  // Every this many passes, all cells are forgotten (Fermat resets its table every 32 frames);
  // 0: never.
  uint32_t reset_every = 0;
};

// The error budget's study settings (docs/rll.md, "The error budget"; issue 45): each swaps one
// component of rll's estimator for an ideal one, to measure how much of rll's error that component
// makes. Off by default, and then nothing changes: they are read apart from RllSettings (a state
// saved with or without them is the same state) and only for `rll` (and `oracle`, which samples
// with rll.*). Host-only (the megakernel on the CPU); every other renderer refuses them.
struct RllStudy {
  // The oracle's cluster table in place of the learnt one (the oracle sampler over rll's own cut:
  // oracle.refine defaults to 0 here, so that only the choice among the same clusters changes).
  bool cluster = false;
  // Shadow rays per light of the exact within-cluster distribution at the cell's anchor (each
  // light of the cluster in proportion to its contribution there, visibility included), cached
  // per cell and cluster; 0: rll's own within-cluster rule.
  uint32_t light = 0;
  // Where that distribution is taken: at the cell's anchor (false: what a per-cell table could
  // know at best) or at each shading point (true: the within-cluster choice's whole share,
  // computed for every sample and pmf; slow).
  bool light_at_point = false;
  // Points on the chosen light per next-event sample, each with its shadow ray, averaged: the
  // point's variance all but vanishes; 0: one point (rll's).
  uint32_t point = 0;
  // BSDF directions per vertex whose MIS-weighted emission replaces that of the path's own BSDF
  // ray (the BSDF side of MIS averaged over this many directions); 0: the path's one ray.
  uint32_t bsdf = 0;
};
const std::vector<ParamSpec<RllStudy>>& rll_study_params();
// rll.ideal_* from `params`, each checked against its range (errors name the key).
RllStudy rll_study_from(const Params& params);

// Reads <prefix>.* parameters over `base` (see docs/rll.md for each): rll.* over rll's
// defaults, fermat.* over fermat_settings(). Every key's range is checked as it is read, and the
// rules between keys after; an error names PREFIX.KEY.
RllSettings rll_settings_from(const Params& params, const std::string& prefix = "rll",
                              RllSettings base = {});
// RllSettings' own parameters (the cut's and the cells' are in learn/cut_params.h); every key of
// the three tables with its value in `s` and its range, one a line, as `rll samplers --params`
// lists them.
const std::vector<ParamSpec<RllSettings>>& rll_params();
// Calls f(table, part) for each of the three tables, with the part of `s` (the cut's, the
// cells', the whole) that it reads and sets: one list of rll's tables for reading, listing and
// describing them.
template <class Settings, class F>
void for_each_rll_table(Settings& s, F&& f) {
  f(cut_params(), s.cut);
  f(cell_grid_params(), s.grid);
  f(rll_params(), s);
}
std::vector<std::string> describe_rll_params(const RllSettings& s, const std::string& prefix);
// Every key of the three tables with its value in `s`, as one JSON object: the "parameters" of
// rll's and fermat's describe(), which a saved state is matched against.
nlohmann::json rll_parameters_json(const RllSettings& s);
// Fermat's RLL as published (PEERS.md): 256-cluster initial cut by light count, 75% uniform +
// 25% learnt clusters with every Q starting at 0.01, exponential learning at 0.05, the
// max-RGB full-pdf reward, one split-collapse per pass with T = 1 and Q split half and half,
// per-sample jitter and a table reset every 32 passes. One departure (docs/fermat.md): Fermat
// splits emitters into equal-energy virtual lights and picks uniformly among them inside a
// cluster; here the scene's own lights are picked by power inside a cluster, the distribution
// that uniform choice among equal-energy pieces approximates.
RllSettings fermat_settings();

}  // namespace rll
