// RLL's hot path as RLL_HD free functions over flat views (DESIGN 6): a point's cell (lookup,
// insert, last use, the first pass's anchor sums), a light from the cell's cut (its baked CDF, then
// a light inside the cluster), the pmf of any light, and a next-event sample's reward, summed
// exactly. RllLightSampler calls these on the CPU; a device renderer calls the same over device
// copies of the arrays. The end of pass stays on the host.
#pragma once

#include <bit>
#include <cmath>
#include <cstdint>

#include "rll/core/device.h"
#include "rll/core/hash.h"
#include "rll/core/sampling.h"
#include "rll/core/search.h"
#include "rll/learn/cell_grid.h"
#include "rll/learn/cut_store.h"
#include "rll/lights/cluster_draw.h"
#include "rll/lights/sampler_view.h"
#include "rll/lighttree/descent.h"

namespace rll {

// How a light is drawn inside a cluster: uniformly (the paper), by power (a static table), by a
// descent of the light tree below the cluster, or by power in small clusters and by descent in
// clusters of more than `descend_above` lights (Hybrid).
enum class WithinCluster { Uniform, Power, Tree, Hybrid };
// A cluster's reward per next-event sample: its estimate of the cluster's contribution
// (estimate / P(l | cluster), DESIGN 2), the estimate over the full pdf (the paper's fixed point,
// P ~ sqrt(I)), or Fermat's: the largest RGB channel of the full MIS-weighted contribution
// (path throughput included) over the full pdf, and no reward at all where the light could not
// contribute even unoccluded.
enum class RewardKind { Cluster, FullPdf, Fermat };
// The defensive term of the cluster distribution: a per-cell prior folded into the cell's baked
// table (constant cost), or the light tree's probability of the cluster at the shading point
// itself (a walk from the root per sample and per pmf).
enum class Defensive { Cell, Tree };

// Per cell, the first pass's point sums: position (units of 2^-24 of the scene diameter) and
// normal in fixed point, and a count, as two's complement words.
inline constexpr int kRllPointWords = 7;

struct RllView {
  LightTreeView tree;
  CellKeyer keyer;
  CellTableView table;
  CutStoreView cuts;
  View<uint32_t> last_used;         // per cell: the pass of its last lookup
  View<uint64_t> points;            // per cell, kRllPointWords
  View<const double> power_prefix;  // per light (tree order) and one more: prefix sums of power
  Vec3 origin;                      // of the point sums
  float extent = 1;                 // of the point sums: the scene's diameter
  uint32_t pass = 0;                // this pass, as last_used stamps it
  uint32_t descend_above = 16;      // Hybrid
  float sample_jitter = 0;          // RllSettings::sample_jitter
  WithinCluster within = WithinCluster::Tree;
  RewardKind reward = RewardKind::Cluster;
  Defensive defensive = Defensive::Cell;
  bool cold_uniform = false;
  bool guided = false;  // rll.sampling=guided
  int refine = 0;       // rll.refine: levels a point may go below its own into refined cells
};

namespace detail {

// The cut of a point's cell, or the shared initial cut (cdf null).
struct RllCut {
  uint32_t size;
  const uint32_t* ends;
  const uint32_t* nodes;
  const float* cdf;
};

RLL_HD inline bool rll_has_cut(const RllView& v, uint32_t cell) {
  return cell != kNoCell && v.cuts.active(cell);
}

// The cut of a cell of the shared cut arrays (rll's cells, ltc's entries), or the initial cut
// for a cell without one (kNoCell included).
RLL_HD inline RllCut rll_cut(const CutArraysView& c, uint32_t cell) {
  if (cell != kNoCell && c.active(cell)) {
    const size_t base = c.base(cell);
    return {c.size[cell], &c.end[base], &c.node[base], &c.cdf[base]};
  }
  return {uint32_t(c.initial.size), c.initial_ends.data, c.initial.data, nullptr};
}

RLL_HD inline RllCut rll_cut(const RllView& v, uint32_t cell) {
  return rll_cut(v.cuts, cell);
}

RLL_HD inline uint32_t rll_begin(const RllCut& c, uint32_t k) {
  return k > 0 ? c.ends[k - 1] : 0;
}

// The cluster holding `light`: the first whose end is above it.
RLL_HD inline uint32_t rll_cluster_of(const RllCut& c, uint32_t light) {
  return upper_bound_index(c.ends, 0u, c.size, light);
}

// Probability of cluster k in the cell's CDF: the exact width of its interval.
RLL_HD inline float rll_cdf_width(const RllCut& c, uint32_t k) {
  return float(double(c.cdf[k]) - (k > 0 ? double(c.cdf[k - 1]) : 0.0));
}

RLL_HD inline bool rll_descends(const RllView& v, uint32_t begin, uint32_t end) {
  return v.within == WithinCluster::Tree ||
         (v.within == WithinCluster::Hybrid && end - begin > v.descend_above);
}

// A cluster k of a cell's baked CDF for uc in [0, 1): the first entry above uc, each compared as
// a double, so that the interval of uc selecting k is exactly [cdf[k-1], cdf[k]), whose width
// rll_cdf_width reports (zero-width entries are never returned); `u_within` is uc rescaled inside
// that interval. False where k's width is zero.
RLL_HD inline bool rll_table_draw(const RllCut& c, double uc, uint32_t* k, double* u_within) {
  const uint32_t first = upper_bound_index(c.cdf, 0u, c.size, uc);
  uint32_t j = std::min(first, c.size - 1);
  while (j > 0 && c.cdf[j] == c.cdf[j - 1]) --j;
  const double lo = j > 0 ? double(c.cdf[j - 1]) : 0.0;
  const double q = double(c.cdf[j]) - lo;
  if (!(q > 0)) return false;
  *k = j;
  *u_within = clamp((uc - lo) / q, 0.0, kBelowOne);
  return true;
}

// Light inside cluster node `node` covering [begin, end), and its probability.
RLL_HD inline SampledLight rll_sample_within(const RllView& v, const LightContext& ctx,
                                             uint32_t node, uint32_t begin, uint32_t end,
                                             double u) {
  const uint32_t count = end - begin;
  SampledLight s;
  if (count == 1) {
    s.light = begin;
    s.pmf = 1.0f;
    return s;
  }
  if (rll_descends(v, begin, end))
    return sampled_light(tree_descend(v.tree, node, ctx.p, ctx.n, u));
  if (v.within != WithinCluster::Uniform) {
    // The static table: light powers in tree order as a prefix sum.
    const double* prefix = v.power_prefix.data;
    double lo = prefix[begin], total = prefix[end] - lo;
    if (total > 0) {
      double target = lo + u * total;
      // The first of prefix[begin + 1, end + 1) above target.
      const uint32_t first = upper_bound_index(prefix, begin + 1, end + 1, target);
      uint32_t l = std::min(first - 1, end - 1);
      while (l > begin && prefix[l + 1] == prefix[l]) --l;  // never a zero-power light
      s.light = l;
      s.pmf = float((prefix[l + 1] - prefix[l]) / total);
      return s;
    }
  }
  s.light = begin + std::min(count - 1, uint32_t(u * count));
  s.pmf = 1.0f / float(count);
  return s;
}

RLL_HD inline float rll_pmf_within(const RllView& v, const LightContext& ctx, uint32_t node,
                                   uint32_t begin, uint32_t end, uint32_t light) {
  const uint32_t count = end - begin;
  if (count == 1) return 1.0f;
  if (rll_descends(v, begin, end)) return tree_descend_pmf(v.tree, node, light, ctx.p, ctx.n);
  if (v.within != WithinCluster::Uniform) {
    double total = v.power_prefix[end] - v.power_prefix[begin];
    if (total > 0) return float((v.power_prefix[light + 1] - v.power_prefix[light]) / total);
  }
  return 1.0f / float(count);
}

// The full pmf of light l in cluster k (which contains it), and the cluster's probability.
// `within` is pmf_within(l), already known to the caller; `descent`: a descent from the root that
// reached l split at this cut, with `descent_pmf` its probability, if the caller has one (saves
// the reach).
RLL_HD inline float rll_mixture_pmf(const RllView& v, const LightContext& ctx, const RllCut& c,
                                    uint32_t k, uint32_t l, float within,
                                    const DescentSplit* descent, float descent_pmf,
                                    float* cluster_pmf) {
  const float q = rll_cdf_width(c, k);  // the cell's CDF: learnt, or with the prior
  if (v.defensive == Defensive::Cell) {
    *cluster_pmf = q;
    return q * within;
  }
  // P(l|x) = [(1 - eps) Q(s)/sum Q + eps reach(s|x)] P(l|s): the defensive prior of DESIGN 2 is
  // the tree's probability of the cluster at x. Before the cell has learnt anything, the tree
  // alone. A descent from the root that went through the cluster (`descent`) already holds reach.
  const float eps = v.cuts.eps[ctx.cell];
  const float reach = descent && descent->cluster == k
                          ? descent->reach
                          : tree_reach_pmf(v.tree, c.nodes[k], ctx.p, ctx.n);
  *cluster_pmf = (1 - eps) * q + eps * reach;
  if (rll_descends(v, rll_begin(c, k), c.ends[k])) return *cluster_pmf * within;
  // Another within-cluster rule: mix the two distributions over lights.
  const float tree =
      descent ? descent_pmf : tree_descend_pmf(v.tree, LightTree::kRoot, l, ctx.p, ctx.n);
  return (1 - eps) * q * within + eps * tree;
}

// The guided descent (rll.sampling=guided) of a cell with a cut: from the root, each step by the
// children's importance times the cell's factors, down to a cluster of the cut; then the light
// inside it as `within` says.
RLL_HD inline SampledLight rll_sample_guided(const RllView& v, const LightContext& ctx,
                                             const RllCut& c, double u) {
  const size_t base = size_t(ctx.cell) * v.cuts.m;
  const float *gl = &v.cuts.gl[base], *gr = &v.cuts.gr[base];
  uint32_t index = LightTree::kRoot, k0 = 0, k1 = c.size;
  float pmf = 1, importance = -1;
  while (k1 - k0 > 1) {
    // An inner node above the cut: its children meet at the boundary after cluster j.
    const LightTreeNode& node = v.tree.node(index);
    const uint32_t j = children_boundary(v.tree, node, c.ends, k0, k1);
    float i0 = -1, i1 = -1;
    const float p0 = first_child_probability(v.tree, node, ctx.p, ctx.n, gl[j], gr[j], &i0, &i1);
    if (u < p0) {
      u = std::min(u / p0, double(detail::kBelowOne));
      pmf *= p0;
      index = node.child;
      k1 = j + 1;
      importance = i0;
    } else {
      u = std::min((u - p0) / (1 - p0), double(detail::kBelowOne));
      pmf *= 1 - p0;
      index = node.child + 1;
      k0 = j + 1;
      importance = i1;
    }
  }
  if (!(pmf > 0)) return {};
  // The cluster is reached (index == nodes[k0]); its importance, where the last step did not
  // compute it (a group node, or a cut of one cluster).
  if (importance < 0) importance = tree_importance(v.tree, index, ctx.p, ctx.n);
  SampledLight w = rll_sample_within(v, ctx, index, rll_begin(c, k0), c.ends[k0], u);
  if (!(w.pmf > 0)) return {};
  ClusterDraw d;
  d.cluster = k0;
  d.cluster_pmf = pmf;
  d.importance = importance;
  d.target = v.cuts.vis[base + k0];
  set_cluster_draw(w, d);
  w.pmf = pmf * w.pmf;
  return w.pmf > 0 ? w : SampledLight{};
}

RLL_HD inline float rll_pmf_guided(const RllView& v, const LightContext& ctx, const RllCut& c,
                                   uint32_t light) {
  const size_t base = size_t(ctx.cell) * v.cuts.m;
  const float *gl = &v.cuts.gl[base], *gr = &v.cuts.gr[base];
  uint32_t index = LightTree::kRoot, k0 = 0, k1 = c.size;
  float pmf = 1;
  while (k1 - k0 > 1) {
    const LightTreeNode& node = v.tree.node(index);
    const uint32_t j = children_boundary(v.tree, node, c.ends, k0, k1);
    const float p0 =
        first_child_probability(v.tree, node, ctx.p, ctx.n, gl[j], gr[j], nullptr, nullptr);
    if (light < c.ends[j]) {
      pmf *= p0;
      index = node.child;
      k1 = j + 1;
    } else {
      pmf *= 1 - p0;
      index = node.child + 1;
      k0 = j + 1;
    }
    if (pmf == 0) return 0;
  }
  return pmf * rll_pmf_within(v, ctx, index, rll_begin(c, k0), c.ends[k0], light);
}

// llround on either device (CUDA's device code has llroundf).
RLL_HD inline int64_t round_to_int64(float x) {
#if RLL_DEVICE_CODE
  return int64_t(llroundf(x));
#else
  return int64_t(std::llround(x));
#endif
}

RLL_HD inline uint32_t float_bits(float x) {
#if RLL_DEVICE_CODE
  return __float_as_uint(x);
#else
  return std::bit_cast<uint32_t>(x);
#endif
}

// This sample's own jitter (rll.sample_jitter), from hashes of u (the level's rounding uses u
// itself): a disk of sample_jitter cell radii (half edges) and a quarter normal bin.
RLL_HD inline void rll_sample_jitter(const RllView& v, float u, Vec2* d, Vec2* nj) {
  const uint64_t h = mix64(uint64_t(float_bits(u)) ^ 0x6a09e667f3bcc909ull);
  auto unit = [&](int i) { return float((h >> (16 * i)) & 0xffff) * 0x1p-16f; };
  const Vec2 disk = sample_uniform_disk_concentric({unit(0), unit(1)});
  *d = {disk.x * 0.5f * v.sample_jitter, disk.y * 0.5f * v.sample_jitter};
  *nj = {(unit(2) - 0.5f) * 0.5f, (unit(3) - 0.5f) * 0.5f};
}

// The cell of a coordinate, made if it is new (with its anchor), its last use stamped; kNoCell
// where the table is full.
RLL_HD inline uint32_t rll_find_cell(const RllView& v, const CellCoord& coord) {
  bool created = false;
  const uint32_t cell = cell_find_or_insert(v.table, v.keyer.key(coord), &created);
  // Table full: no cell until eviction makes room.
  if (cell == CellTableView::kNone) return kNoCell;
  if (created) v.cuts.anchor[cell] = v.keyer.anchor(coord);
  // Stamp the pass of last use; a write only when it changes (no cache-line traffic per sample).
  if (atomic_load(&v.last_used[cell]) != v.pass) atomic_store(&v.last_used[cell], v.pass);
  return cell;
}

}  // namespace detail

// The cell coordinate of a shading point with a surface (ctx.n not zero): its position, normal
// and level of detail (u drives the level's rounding), with Fermat's per-sample jitter (from
// hashes of u) where `per_sample_jitter` and the view has one, and the direction bin of a glossy
// point. rll_prepare finds its cell by this key; the report's cell chart (eval/cell_chart.cpp)
// looks the same key up, so that both follow one rule.
// `finer`: levels below the point's own (a refined cell's child, rll.refine), with the same jitter.
RLL_HD inline CellCoord rll_cell_coord(const RllView& v, const LightContext& ctx, float u,
                                       bool per_sample_jitter = true, int finer = 0) {
  CellCoord coord;
  const int level = v.keyer.level(ctx.footprint, u) - finer;
  if (per_sample_jitter && v.sample_jitter > 0) {
    Vec2 d, nj;
    detail::rll_sample_jitter(v, u, &d, &nj);
    coord = v.keyer.locate_jittered_at_level(ctx.p, ctx.n, level, d, nj);
  } else {
    coord = v.keyer.locate_at_level(ctx.p, ctx.n, level);
  }
  if (v.keyer.settings().direction_bins > 0 && ctx.glossy && length_sq(ctx.wo) > 0)
    coord.dir = v.keyer.direction_bin(ctx.wo);
  return coord;
}

// Finds (or makes) the cell of the shading point: ctx.cell, kNoCell without a surface or where
// the table is full. u drives the level of detail's rounding (and Fermat's per-sample jitter).
// With rll.refine, a point whose cell is refined takes the cell one level finer (an ordinary cell
// of the grid, the one a point of a smaller footprint takes), down to rll.refine levels below its
// own; every cell on the way is stamped, so that a refined cell outlives its children.
RLL_HD inline void rll_prepare(const RllView& v, LightContext& ctx, float u) {
  ctx.cell = kNoCell;
  if (length_sq(ctx.n) == 0) return;
  CellCoord coord = rll_cell_coord(v, ctx, u);
  uint32_t cell = detail::rll_find_cell(v, coord);
  if (cell == kNoCell) return;
  uint32_t parent = kNoCell;
  uint8_t parent_half = 0;
  for (int finer = 1;
       finer <= v.refine && v.cuts.refined[cell] && coord.level > CellKeyer::kFinestLevel;
       ++finer) {
    const CellCoord child_coord = rll_cell_coord(v, ctx, u, true, finer);
    const uint32_t child = detail::rll_find_cell(v, child_coord);
    if (child == kNoCell) break;  // table full: the refined cell itself
    parent = cell;
    parent_half = coord.half;
    coord = child_coord;
    cell = child;
  }
  ctx.cell = cell;
  ctx.half = coord.half;
  if (!v.cuts.active(cell)) {  // the cell's first pass: its points make its anchor
    uint64_t* w = &v.points[size_t(cell) * kRllPointWords];
    const Vec3 q = (ctx.p - v.origin) * (0x1p24f / v.extent);
    const float f[6] = {q.x, q.y, q.z, ctx.n.x * 0x1p24f, ctx.n.y * 0x1p24f, ctx.n.z * 0x1p24f};
    for (int i = 0; i < 6; ++i) atomic_add(&w[i], uint64_t(detail::round_to_int64(f[i])));
    atomic_add(&w[6], uint64_t(1));
    // A refined cell's new child samples (and learns) with its parent's table through its first
    // pass, at whose end it starts from the parent's values (cut_seed_child): no cold pass.
    if (parent != kNoCell && v.cuts.active(parent)) {
      ctx.cell = parent;
      ctx.half = parent_half;
    }
  }
}

// A light for a prepared shading point (ctx.cell) and its probability, with the cluster it came
// from for rll_record and, in a cell with a cut, the cluster's target factor (1 without one).
RLL_HD inline SampledLight rll_sample(const RllView& v, const LightContext& ctx, double u) {
  using namespace detail;
  const RllCut c = rll_cut(v, ctx.cell);
  // A descent of the whole tree split at this cell's cut (the initial one before it has its own).
  DescentSplit split;
  split.ends = c.ends;
  split.nodes = c.nodes;
  split.size = c.size;
  const bool has_cut = rll_has_cut(v, ctx.cell);
  if (!has_cut && v.cold_uniform) {
    // Every cluster of the initial cut alike (Fermat: every Q starts equal).
    const uint32_t K = c.size;
    const uint32_t k = std::min(K - 1, uint32_t(u * K));
    const double u_within = clamp(u * K - k, 0.0, kBelowOne);
    SampledLight w = rll_sample_within(v, ctx, c.nodes[k], rll_begin(c, k), c.ends[k], u_within);
    if (!(w.pmf > 0)) return {};
    ClusterDraw d;
    d.cluster = k;
    d.cluster_pmf = 1.0f / float(K);
    set_cluster_draw(w, d);
    w.pmf = w.pmf / float(K);
    return w;
  }
  if (!has_cut) {
    // A point without a learnt cut (a cell new in this pass, or none: table full) samples
    // like the light tree. Its reward still goes to its cluster of the initial cut: given the
    // cluster, the tree chose the light with the probability of the path below the cluster.
    SampledLight s = sampled_light(tree_descend(v.tree, LightTree::kRoot, ctx.p, ctx.n, u, &split));
    if (!(s.pmf > 0)) return {};
    ClusterDraw d;
    d.cluster = rll_cluster_of(c, s.light);
    // (A cluster the path did not pass: the whole path's product, as the earlier record gave.)
    const float within = split.cluster == d.cluster ? split.below : s.pmf;
    d.cluster_pmf = within > 0 ? s.pmf / within : s.pmf;
    if (v.guided) d.importance = tree_importance(v.tree, c.nodes[d.cluster], ctx.p, ctx.n);
    set_cluster_draw(s, d);
    return s;
  }
  if (v.guided) return rll_sample_guided(v, ctx, c, u);
  const float eps = v.defensive == Defensive::Tree ? v.cuts.eps[ctx.cell] : 0.0f;
  uint32_t k, l;
  float within, descent_pmf = 0;
  const DescentSplit* descent = nullptr;
  if (u < eps) {
    // The defensive branch: a descent of the whole tree, then its cluster in this cut.
    const TreeSample t = tree_descend(v.tree, LightTree::kRoot, ctx.p, ctx.n, u / eps, &split);
    if (!(t.pmf > 0)) return {};
    l = t.light;
    k = rll_cluster_of(c, l);
    const uint32_t begin = rll_begin(c, k);
    if (rll_descends(v, begin, c.ends[k]))
      within = split.cluster == k ? split.below : t.pmf;
    else
      within = rll_pmf_within(v, ctx, c.nodes[k], begin, c.ends[k], l);
    descent = &split;
    descent_pmf = t.pmf;
  } else {
    // The learnt branch: a cluster from the cell's CDF, then a light inside it.
    double u_within = 0;
    if (!rll_table_draw(c, (u - eps) / (1 - eps), &k, &u_within)) return {};
    SampledLight w = rll_sample_within(v, ctx, c.nodes[k], rll_begin(c, k), c.ends[k], u_within);
    if (!(w.pmf > 0)) return {};
    l = w.light;
    within = w.pmf;  // the same top-down product as rll_pmf_within computes
  }
  SampledLight s;
  s.light = l;
  ClusterDraw d;
  d.cluster = k;
  s.pmf = rll_mixture_pmf(v, ctx, c, k, l, within, descent, descent_pmf, &d.cluster_pmf);
  d.target = v.cuts.vis[size_t(ctx.cell) * v.cuts.m + k];
  set_cluster_draw(s, d);
  return s.pmf > 0 ? s : SampledLight{};
}

// Another light from the cluster of `first` (a draw of rll_sample at the same point, pmf > 0),
// drawn from the same distribution over the cluster's lights that rll_sample draws from once
// that cluster is chosen: resampled NEE's candidates from one cluster (nee.draw=cluster,
// docs/nee.md), which pay the cell's table draw once. Its pmf is the full source pmf of the light,
// the cluster's probability (from first's record) times the within-cluster probability, as
// rll_sample forms it; the record is first's (the same cluster, probability and target). Exact
// where that within-cluster distribution does not depend on how the cluster was chosen: every
// setting but defensive=tree with a within rule other than the descent (rll_cluster_draws).
RLL_HD inline SampledLight rll_sample_in_cluster(const RllView& v, const LightContext& ctx,
                                                 const SampledLight& first, double u) {
  using namespace detail;
  const RllCut c = rll_cut(v, ctx.cell);
  const ClusterDraw d = cluster_draw(first);
  if (!(first.pmf > 0) || d.cluster >= c.size) return {};
  const uint32_t k = d.cluster;
  // A point without a cut and not cold-uniform draws like the tree: below the cluster's node, the
  // rest of the tree's descent (the node lies on every path to the cluster's lights).
  SampledLight w = !rll_has_cut(v, ctx.cell) && !v.cold_uniform
                       ? sampled_light(tree_descend(v.tree, c.nodes[k], ctx.p, ctx.n, u))
                       : rll_sample_within(v, ctx, c.nodes[k], rll_begin(c, k), c.ends[k], u);
  if (!(w.pmf > 0)) return {};
  w.pmf = d.cluster_pmf * w.pmf;
  w.record = first.record;
  return w.pmf > 0 ? w : SampledLight{};
}

// Whether rll_sample_in_cluster draws from the distribution rll_sample draws from given the
// cluster: not where the defensive term is the tree's own descent and the cluster's lights are
// drawn otherwise (a light of the cluster then comes from a mixture of two rules).
RLL_HD inline bool rll_cluster_draws(const RllView& v) {
  return !(v.defensive == Defensive::Tree && v.within != WithinCluster::Tree);
}

// The probability that rll_sample(v, ctx, .) returns `light`.
RLL_HD inline float rll_pmf(const RllView& v, const LightContext& ctx, uint32_t light) {
  using namespace detail;
  const RllCut c = rll_cut(v, ctx.cell);
  uint32_t k = rll_cluster_of(c, light);
  if (k >= c.size) return 0;
  if (!rll_has_cut(v, ctx.cell)) {
    if (!v.cold_uniform) return tree_descend_pmf(v.tree, LightTree::kRoot, light, ctx.p, ctx.n);
    return rll_pmf_within(v, ctx, c.nodes[k], rll_begin(c, k), c.ends[k], light) / float(c.size);
  }
  if (v.guided) return rll_pmf_guided(v, ctx, c, light);
  float within = rll_pmf_within(v, ctx, c.nodes[k], rll_begin(c, k), c.ends[k], light);
  float cluster_pmf;
  return rll_mixture_pmf(v, ctx, c, k, light, within, nullptr, 0.0f, &cluster_pmf);
}

// Rewards the cluster of a next-event sample (RewardKind); thread-safe, and exact whatever the
// order of the calls.
RLL_HD inline void rll_record(const RllView& v, const LightContext& ctx, const SampledLight& s,
                              const NeeRecord& r) {
  const float estimate = r.estimate;
  if (ctx.cell == kNoCell || !(s.pmf > 0) || !(estimate >= 0) || !std::isfinite(estimate)) return;
  const ClusterDraw d = cluster_draw(s);
  const float within = s.pmf / d.cluster_pmf;
  // DESIGN 2: the cluster reward estimates the cluster's total contribution I(s):
  // r = estimate / P(l|s). The original code divided by the full pdf (fixed point P ~ sqrt(I)).
  float reward = 0;
  switch (v.reward) {
    case RewardKind::Cluster:
      reward = estimate / within;
      if (v.guided) {
        // The ratio of the cluster's contribution to the tree's importance of it at the point.
        if (!(d.importance > 0)) return;
        reward /= d.importance;
      }
      break;
    case RewardKind::FullPdf:
      reward = estimate / s.pmf;
      break;
    case RewardKind::Fermat:
      if (!(r.unoccluded > 0)) return;  // the light cannot reach here at all: no reward
      reward = r.max_rgb / s.pmf;
      break;
  }
  if (!(reward >= 0) || !std::isfinite(reward)) return;
  // rll.refine: the half of the cell the point lies in along this pass's axis (x, y, z in turn).
  const bool upper = v.refine > 0 && ((ctx.half >> (v.pass % 3)) & 1);
  cut_record(v.cuts, ctx.cell, d.cluster, reward, upper);
}

}  // namespace rll
