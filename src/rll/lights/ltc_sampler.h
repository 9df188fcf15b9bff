// `ltc`: Wang et al. 2021, "Learning to cluster for rendering with many lights" (the CPU original,
// full-MIS variant), built from its description in shared/PEERS.md. Per entry (spatial cluster of
// shading points x bin of the outgoing direction) a cut of the light tree, started from a global
// cut of 8 nodes chosen by power and grown by variance-driven splits to at most 64 nodes; each
// node learns the second moment of its reward; NEE picks a node in proportion to sqrt(second
// moment) (with a small defensive mix), then a light below it by the light tree's descent.
//
// Why sqrt of the second moment, and the reward that learns it. A light l drawn from cut node s
// with P(s) P(l | s) gives the one-sample estimate F / (P(s) P(l | s)), F the light sample's
// MIS-weighted contribution f Le G V w_mis / pdf(y | l). Its second moment is
//   E[(F / (P(s) P(l|s)))^2] = sum_s M2(s) / P(s),   M2(s) = E_{l ~ P(.|s), y}[(F / P(l|s))^2],
// and minimising sum_s M2(s) / P(s) subject to sum_s P(s) = 1 (Lagrange) gives
// P(s) = sqrt(M2(s)) / sum_t sqrt(M2(t)). So the reward of a sample that chose s is
// r = F / P(l | s) (the node's own estimator, independent of P(s)); each node learns
// w(s) ~ E[r^2] = M2(s) by the exponential rule w := (1 - a) w + a r^2, a = 1 / (4 t^0.857), t the
// entry's visit count, and samples in proportion to sqrt(w). (The paper's reward
// sqrt(E[F^2] x lights / P(l|node)) is a per-sample square root whose average tends to E[|r|]-like
// values, not to sqrt(M2); averaging the square and taking the root afterwards hits the optimum.)
//
// Departures from the CPU original, each because rll's renders must be identical for any thread
// count (a sample's effect may not depend on which thread delivered it first):
// - record() only accumulates, exactly and order-independently (fixed-point ExactSum, counts);
//   end_pass() applies a pass's rewards. The per-sample rule over the pass's N visits of an entry,
//   n_s of them to node s, with the rewards replaced by their pass mean and node s's visits spread
//   evenly among the entry's, is w(s) := b w(s) + (1 - b) mean(r^2) with
//   b = exp((n_s / N) sum_{t=T+1..T+N} log(1 - a_t)); exact when the rewards of a pass are equal.
// - Splits are decided at end_pass with the published per-sample probability
//   p = (1 - 1/n) x var(s) / sum var x 1 / (1 + (K/8) exp(-V)), taken over the node's n_s visits of
//   the pass (split if u < 1 - (1 - p)^n_s, u a hash of (entry key, node, pass)): at most one split
//   per node and pass. V is the entry's total variance relative to the square of its total mean
//   reward (the original uses raw variance, which makes the rule depend on the scene's units).
//   An entry stops splitting once 128 visits pass without a split.
// - BSDF-sampled hits are not reported to samplers, so F is the light sample's MIS-weighted
//   contribution alone (estimate x mis_weight of NeeRecord), not the light and BSDF samples'.
// - A split shares the parent's learnt M2 between the children by what the parent saw: each node
//   also accumulates r^2 of the lights under its first child (g = that share of E[r^2]), and a
//   child c with bound share f gets sqrt(M2_c) = sqrt(f g_c M2_parent) (the exact second moment
//   if P(c | parent) were f at every point). It blends that with its own prior bound, the prior's
//   weight being the parent's remaining prior share prod (1 - a_t) over the visits since the prior
//   was set, the "(1 - a)^n" of the paper. (With the entry-level rate a node born late is
//   visited at a ~ 1e-4 and would otherwise keep its prior for the rest of the render.)
// - An entry samples like the light tree during the pass it was created in (its first rewards
//   go to the nodes of the global cut that hold the drawn lights); the cut's prior is then the
//   light tree's importance at the spatial cluster's centre, scaled to the first pass's mean
//   rewards (a bound of contribution is a first moment), and each node's first-pass rewards count
//   as its own opening visits: w = b prior^2 + (1 - b) mean(r^2), b = prod_{t<=n} (1 - a_t).
// - P(node) = (1 - eps) sqrt(w) / sum sqrt(w) + eps d(node), d half the prior share and half
//   uniform over nodes with power, so that every light that can contribute keeps pmf > 0.
// - A full entry table (ltc.capacity) sends new entries' points to the plain tree descent. Which
//   keys get the last free entries must not depend on thread timing, so a pass whose new keys
//   outnumber the free entries keeps none of the entries it created (nor their records): at its
//   end the free entries go to the new keys the pass visited most (ties: a hash of the key),
//   which start learning in the next pass. A key claims its slot before it takes a free entry,
//   so every new key of a pass gets one while they last (no entry is spent on a lost race), and
//   whether a pass overflowed depends only on how many new keys it visited.
// Direction bins: world-frame spherical coordinates of wo, theta = acos(wo.z) in 8 bins of pi/8
// and phi = atan2(wo.y, wo.x) in 8 bins of pi/4 (as the original, which bins pbrt's world wo).
#pragma once

#include <atomic>
#include <memory>
#include <vector>

#include "rll/core/param_table.h"
#include "rll/learn/cut.h"
#include "rll/learn/cut_arrays.h"
#include "rll/learn/moments.h"
#include "rll/lights/light_sampler.h"
#include "rll/lights/rll_view.h"
#include "rll/lights/tree_sampler.h"

namespace rll {

struct LtcSettings {
  uint32_t clusters = 32768;  // spatial clusters (fewer when the scene's surfaces are small)
  uint32_t bins = 8;          // direction bins per spherical coordinate (bins x bins per cluster)
  uint32_t capacity = 65536;  // entries (cluster, bin) with a cut, allocated up front
  int initial_cut = 8;
  int max_cut = 64;
  float epsilon = 0.1f;      // weight of the defensive distribution
  uint32_t no_change = 128;  // visits without a split after which an entry stops splitting
};

// Reads ltc.* parameters (see docs/ltc.md), each checked against its range (errors name the key),
// by the table of ltc's parameters (core/param_table.h).
LtcSettings ltc_settings_from(const Params& params);
const std::vector<ParamSpec<LtcSettings>>& ltc_params();

// The spatial clusters: a kd-tree over points sampled by area on the scene's surfaces (sky
// excluded), built by splitting the leaf with the largest box at the median of its points along
// its longest axis until `count` leaves (or no leaf holds two distinct points). Every point of
// space falls in exactly one leaf.
class SpatialClusters {
 public:
  SpatialClusters() = default;
  static SpatialClusters build(const Scene& scene, uint32_t count, uint32_t points_per_cluster = 4);
  // Builds over given points (tests).
  static SpatialClusters build(std::vector<Vec3> points, uint32_t count);
  uint32_t size() const { return uint32_t(m_centre.size()); }
  uint32_t find(const Vec3& p) const {
    uint32_t i = 0;
    while (m_node[i].axis < 3)
      i = m_node[i].child + (p[m_node[i].axis] >= m_node[i].split ? 1u : 0u);
    return m_node[i].child;
  }
  // Mean of the build points in a cluster.
  const Vec3& centre(uint32_t cluster) const { return m_centre[cluster]; }
  size_t bytes() const { return m_node.size() * sizeof(Node) + m_centre.size() * sizeof(Vec3); }

 private:
  struct Node {
    float split = 0;
    uint32_t axis = 3;   // 3: leaf, `child` is then the cluster id
    uint32_t child = 0;  // inner: first of two adjacent children
  };
  std::vector<Node> m_node;
  std::vector<Vec3> m_centre;
};

// The global initial cut: refine from the root, always splitting the node with the most power
// (ties: the lower node id), until `size` nodes or only leaves; sorted by light range.
std::vector<uint32_t> power_cut(const LightTree& tree, int size);

class LtcLightSampler final : public LightSampler {
 public:
  LtcLightSampler(const Scene& scene, const LightTree& tree, const LtcSettings& settings);
  // The host kind over its prepare, sample, pmf and record below (it has no device version).
  SamplerView sampler_view() const override { return host_view(true, true); }
  void end_pass() override;
  void lights_changed(const Scene& scene) override;
  nlohmann::json describe() const override;

  // For tests and tools.
  const SpatialClusters& clusters() const { return m_clusters; }
  uint32_t direction_bin(const Vec3& wo) const;
  uint32_t entry_key(const LightContext& ctx) const;  // cluster * bins^2 + bin
  bool has_cut(uint32_t entry) const { return entry != kNoCell && m_cuts.active(entry); }
  uint32_t cut_size(uint32_t entry) const { return m_cuts.size[entry]; }
  const uint32_t* cut_nodes(uint32_t entry) const { return m_cuts.nodes(entry); }
  // Probability of node k of an entry's cut (the width of its CDF interval).
  float node_probability(uint32_t entry, uint32_t k) const;
  // An entry's cut (the global one while it has none) as rll's table draw and lookups read one
  // (rll_view.h).
  detail::RllCut cut(uint32_t entry) const;
  const std::vector<uint32_t>& initial_cut() const { return m_cuts.initial; }
  size_t bytes() const;

 private:
  friend class LightSampler;  // its host kind's calls (set_host_calls)
  // The host kind's calls: find the point's entry (ctx.cell; made there for a new key,
  // thread-safely), draw a light, its probability, accumulate a sample's reward (thread-safe;
  // applied at end_pass).
  void prepare(LightContext& ctx, float u);
  SampledLight sample(const LightContext& ctx, double u) const;
  float pmf(const LightContext& ctx, uint32_t light) const;
  void record(const LightContext& ctx, const SampledLight& s, const NeeRecord& r);

  // Refuses (rll::Error naming the keys) tables beyond the memory budget, before they exist.
  static void check_memory(const SpatialClusters& clusters, uint32_t keys, const LtcSettings& s);
  // Importance of a node at an entry's cluster centre (no receiver normal): the prior bound.
  float bound(uint32_t entry, uint32_t node) const;
  // The end of pass's per-entry lists, one set per worker (reused from entry to entry).
  struct LearnScratch {
    std::vector<double> mean_r, mean_r2, mean_r2_0, count;  // per node: this pass's moments
    std::vector<double> bound, defensive, value;
    std::vector<std::pair<double, uint32_t>> chosen;  // nodes to split
  };
  void learn(uint32_t entry, uint64_t pass, LearnScratch& scratch, uint32_t& splits);
  void bake(uint32_t entry, LearnScratch& scratch);
  // Empties a node slot's accumulators of the pass.
  void clear_pass(size_t slot);

  const LightTree& m_tree;  // the render session's (it outlives its samplers)
  LtcSettings m_s;
  int m_m;  // node slots per entry (max_cut)
  SpatialClusters m_clusters;
  std::vector<uint32_t> m_initial_mid;  // per node of the global cut: its first child's end
  double m_reward_scale = 1;

  // key -> entry + 1 (0: none; kClaimed: being created; kFull: no free entry this pass), keys =
  // cluster * bins^2 + bin.
  std::unique_ptr<std::atomic<uint32_t>[]> m_slot;
  // key -> prepares this pass while the key had no entry from an earlier pass (the priority of
  // new keys when the table overflows; modulo 2^32, which is still the same for any thread count).
  std::unique_ptr<std::atomic<uint32_t>[]> m_request;
  uint32_t m_keys = 0;
  // Entry allocation: free entries handed out from m_next_free up; rebuilt at end_pass.
  std::vector<uint32_t> m_free;
  std::atomic<uint32_t> m_next_free{0};
  std::atomic<uint64_t> m_failed{0};  // keys of this pass that found no free entry
  // Drops the entries created in this pass and gives the free entries to the new keys visited
  // most (end_pass of a pass whose new keys outnumbered the free entries).
  void admit_by_visits();

  // Per entry.
  std::vector<uint32_t> m_key;       // kNoCell: free
  std::vector<uint64_t> m_born;      // the pass it was created in
  std::vector<double> m_visits;      // t: NEE samples the entry learnt from
  std::vector<double> m_no_change;   // visits since the last split
  std::vector<float> m_prior_scale;  // prior(node) = scale x bound(node) (power where no bound)
  std::vector<uint8_t> m_prior_power;
  std::vector<double> m_inv_unit;  // 1 / unit of the entry's accumulators during the pass
  // Per entry, its cut and sampling CDF (size 0 until the end of its first pass with rewards),
  // and the global cut (initial): the cut arrays rll's CutStore keeps its cells' cuts in.
  CutArrays m_cuts;
  // Per node slot (entry * max_cut + k).
  std::vector<float> m_w;  // learnt second moment w ~ M2
  // Node statistics since it entered the cut: count, E[r], E[r^2].
  std::vector<float> m_n, m_mean, m_sq;
  std::vector<float> m_sq0;  // ... and E[r^2 1{light under the first child}]: how a split shares M2
  std::vector<float> m_pi;   // the share of w still made of the prior: prod (1 - a) over its visits
  std::vector<uint32_t> m_mid;  // end of the node's first child's range (0 for a leaf)
  // This pass: sums of r, r^2, r^2 under child 0.
  std::unique_ptr<ExactSum[]> m_sum, m_sum2, m_sum2_0;
  std::unique_ptr<std::atomic<uint32_t>[]> m_count;

  uint64_t m_pass = 0;
  uint64_t m_failed_total = 0;
  std::vector<uint32_t> m_splits_per_pass;
};

}  // namespace rll
