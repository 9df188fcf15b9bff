#include "rll/lights/ltc_sampler.h"

#include <algorithm>
#include <cmath>
#include <queue>
#include <thread>

#include "rll/core/error.h"
#include "rll/core/hash.h"
#include "rll/core/memory_budget.h"
#include "rll/core/parallel.h"
#include "rll/core/params.h"
#include "rll/core/rng.h"
#include "rll/core/sampling.h"
#include "rll/core/search.h"
#include "rll/learn/moments.h"
#include "rll/lights/cluster_draw.h"
#include "rll/lights/rll_view.h"
#include "rll/lighttree/light_tree.h"
#include "rll/scene/scene.h"

namespace rll {

const std::vector<ParamSpec<LtcSettings>>& ltc_params() {
  using S = LtcSettings;
  using R = ParamRange;
  static const std::vector<ParamSpec<S>> table = {
      int_param("clusters", R::closed(1, 1 << 20), field<S, &S::clusters>()),
      int_param("bins", R::closed(1, 32), field<S, &S::bins>()),
      int_param("capacity", R::closed(1, 1 << 24), field<S, &S::capacity>()),
      int_param("max_cut", R::closed(1, 1024), field<S, &S::max_cut>()),
      int_param("initial_cut", R::closed(1, 1024), field<S, &S::initial_cut>()),
      float_param("epsilon", R::open_closed(0, 1), field<S, &S::epsilon>(),
                  "it keeps every light that can contribute sampleable"),
      int_param("no_change", R::closed(1, 1 << 30), field<S, &S::no_change>()),
  };
  return table;
}

LtcSettings ltc_settings_from(const Params& p) {
  LtcSettings s;
  read_params(ltc_params(), p, "ltc", s);
  if (s.initial_cut > s.max_cut)
    fail("--set ltc.initial_cut: must be in [1, ltc.max_cut = {}] (got {})", s.max_cut,
         s.initial_cut);
  return s;
}

// --- Spatial clusters ---------------------------------------------------------------------------

SpatialClusters SpatialClusters::build(const Scene& scene, uint32_t count,
                                       uint32_t points_per_cluster) {
  const Mesh& mesh = scene.mesh;
  std::vector<uint32_t> tris;
  std::vector<double> prefix{0.0};
  for (uint32_t t = 0; t < mesh.triangle_count(); ++t) {
    if (scene.is_sky_triangle(t)) continue;
    double a = mesh.area(t);
    if (!(a > 0) || !std::isfinite(a)) continue;
    tris.push_back(t);
    prefix.push_back(prefix.back() + a);
  }
  std::vector<Vec3> points;
  if (!tris.empty()) {
    const size_t n = std::min<size_t>(size_t(count) * points_per_cluster, size_t(1) << 23);
    points.reserve(n);
    Pcg32 rng(0x17c1u, 0x2021u);
    const double total = prefix.back();
    for (size_t i = 0; i < n; ++i) {
      double target = (double(i) + rng.next_float()) / double(n) * total;  // stratified by area
      size_t k =
          size_t(std::upper_bound(prefix.begin() + 1, prefix.end(), target) - prefix.begin()) - 1;
      k = std::min(k, tris.size() - 1);
      Vec2 b = sample_uniform_triangle({rng.next_float(), rng.next_float()});
      const uint32_t t = tris[k];
      points.push_back(mesh.vertex(t, 0) * b.x + mesh.vertex(t, 1) * b.y +
                       mesh.vertex(t, 2) * (1 - b.x - b.y));
    }
  } else {
    points.push_back(scene.bounds.empty() ? Vec3(0) : scene.bounds.center());
  }
  return build(std::move(points), count);
}

SpatialClusters SpatialClusters::build(std::vector<Vec3> pts, uint32_t count) {
  SpatialClusters sc;
  if (pts.empty()) pts.push_back(Vec3(0));
  struct Range {
    uint32_t begin, end;
  };
  std::vector<Range> range{{0, uint32_t(pts.size())}};
  sc.m_node.push_back(Node{});
  struct Leaf {
    uint32_t node;
    float extent;
    int axis;
  };
  auto make_leaf = [&](uint32_t node) {
    Bounds3 b;
    for (uint32_t i = range[node].begin; i < range[node].end; ++i) b.expand(pts[i]);
    Vec3 d = b.diagonal();
    int axis = d.x >= d.y && d.x >= d.z ? 0 : (d.y >= d.z ? 1 : 2);
    return Leaf{node, d[axis], axis};
  };
  // The leaf with the largest box first; ties by node id, so the build is deterministic.
  auto cmp = [](const Leaf& a, const Leaf& b) {
    return a.extent != b.extent ? a.extent < b.extent : a.node > b.node;
  };
  std::priority_queue<Leaf, std::vector<Leaf>, decltype(cmp)> heap(cmp);
  heap.push(make_leaf(0));
  uint32_t leaves = 1;
  while (leaves < count && !heap.empty()) {
    Leaf l = heap.top();
    heap.pop();
    const Range r = range[l.node];
    if (r.end - r.begin < 2 || !(l.extent > 0)) continue;  // stays a leaf
    const int axis = l.axis;
    auto first = pts.begin() + r.begin, last = pts.begin() + r.end,
         mid = first + (r.end - r.begin) / 2;
    std::nth_element(first, mid, last,
                     [axis](const Vec3& a, const Vec3& b) { return a[axis] < b[axis]; });
    float m = (*mid)[axis], split = m;
    auto it = std::partition(first, last, [&](const Vec3& p) { return p[axis] < m; });
    if (it == first) {  // the median is the smallest value: put its ties on the left
      split = std::nextafter(m, kInf);
      it = std::partition(first, last, [&](const Vec3& p) { return p[axis] < split; });
    }
    if (it == first || it == last) continue;
    const uint32_t child = uint32_t(sc.m_node.size()), cut = uint32_t(it - pts.begin());
    sc.m_node[l.node] = Node{split, uint32_t(axis), child};
    sc.m_node.push_back(Node{});
    sc.m_node.push_back(Node{});
    range.push_back({r.begin, cut});
    range.push_back({cut, r.end});
    heap.push(make_leaf(child));
    heap.push(make_leaf(child + 1));
    ++leaves;
  }
  // Cluster ids in node order; the centre of each is the mean of its points.
  for (uint32_t i = 0; i < sc.m_node.size(); ++i) {
    if (sc.m_node[i].axis < 3) continue;
    double s[3] = {0, 0, 0};
    for (uint32_t j = range[i].begin; j < range[i].end; ++j)
      for (int a = 0; a < 3; ++a) s[a] += pts[j][a];
    const double n = std::max(1u, range[i].end - range[i].begin);
    sc.m_node[i].child = uint32_t(sc.m_centre.size());
    sc.m_centre.push_back(Vec3(float(s[0] / n), float(s[1] / n), float(s[2] / n)));
  }
  return sc;
}

// --- The initial cut ----------------------------------------------------------------------------

std::vector<uint32_t> power_cut(const LightTree& tree, int size) {
  return refine_cut(tree, size,
                    [](const LightTree& t, uint32_t n) { return double(t.node(n).bounds.power); });
}

// --- The sampler --------------------------------------------------------------------------------

namespace {
// The learning rate of the t-th visit of an entry (t >= 1).
inline double rate(double t) {
  return 1.0 / (4.0 * std::pow(std::max(t, 1.0), 0.857));
}

// sum_{t = T+1}^{T+N} log(1 - a_t): term by term for the first visits, where a_t is large, then
// by the midpoint integral of -a - a^2/2 (a < 2.2e-4 there; the error is far below float).
double log_keep(double T, double N) {
  double s = 0, t = T + 1;
  const double end = T + N;
  for (int i = 0; i < 4096 && t <= end; ++i, t += 1) s += std::log1p(-rate(t));
  if (t <= end) {
    const double a = t - 0.5, b = end + 0.5;
    s -= 0.25 / 0.143 * (std::pow(b, 0.143) - std::pow(a, 0.143));
    s -= (1.0 / 32) / -0.714 * (std::pow(b, -0.714) - std::pow(a, -0.714));
  }
  return s;
}

inline double unit_hash(uint64_t key, uint64_t node, uint64_t pass) {
  uint64_t h = mix64(key * 0x9e3779b97f4a7c15ull ^
                     mix64(node * 0xc2b2ae3d27d4eb4full + (pass << 40) + 0x2021));
  return double(h >> 11) * 0x1p-53;
}
}  // namespace

LtcLightSampler::LtcLightSampler(const Scene& scene, const LightTree& tree, const LtcSettings& s)
    : LightSampler("ltc"), m_tree(tree), m_s(s), m_m(s.max_cut) {
  set_host_calls(*this);
  if (m_tree.depth() >= kMaxTreeDepth)
    fail("{}: light tree too deep ({})", scene.source, m_tree.depth());
  m_clusters = SpatialClusters::build(scene, s.clusters);
  m_reward_scale = reward_scale(scene);
  m_keys = m_clusters.size() * s.bins * s.bins;
  check_memory(m_clusters, m_keys, s);
  // Allocated after the check, which counts them (kNodeBytes, kEntryBytes).
  m_cuts = CutArrays(m_tree, s.capacity, uint32_t(m_m), power_cut(m_tree, s.initial_cut));
  for (uint32_t n : m_cuts.initial)
    m_initial_mid.push_back(m_tree.node(n).is_leaf() ? 0 : m_tree.node(m_tree.node(n).child).end);
  m_slot = std::make_unique<std::atomic<uint32_t>[]>(m_keys);
  m_request = std::make_unique<std::atomic<uint32_t>[]>(m_keys);
  for (uint32_t k = 0; k < m_keys; ++k) {
    m_slot[k].store(0, std::memory_order_relaxed);
    m_request[k].store(0, std::memory_order_relaxed);
  }
  const uint32_t cap = s.capacity;
  m_key.assign(cap, kNoCell);
  m_born.assign(cap, 0);
  m_visits.assign(cap, 0.0);
  m_no_change.assign(cap, 0.0);
  m_prior_scale.assign(cap, 0.0f);
  m_prior_power.assign(cap, 0);
  m_inv_unit.assign(cap, 1 / m_reward_scale);
  const size_t n = size_t(cap) * m_m;
  m_w.assign(n, 0.0f);
  m_n.assign(n, 0.0f);
  m_mean.assign(n, 0.0f);
  m_sq.assign(n, 0.0f);
  m_sq0.assign(n, 0.0f);
  m_pi.assign(n, 1.0f);
  m_mid.assign(n, 0);
  m_sum = std::make_unique<ExactSum[]>(n);
  m_sum2 = std::make_unique<ExactSum[]>(n);
  m_sum2_0 = std::make_unique<ExactSum[]>(n);
  m_count = std::make_unique<std::atomic<uint32_t>[]>(n);
  for (size_t i = 0; i < n; ++i) m_count[i].store(0, std::memory_order_relaxed);
  m_free.resize(cap);
  for (uint32_t e = 0; e < cap; ++e) m_free[e] = e;
}

namespace {
// Bytes of the tables per node slot, per entry and per key (cluster x direction bin), as the
// constructor allocates them.
constexpr size_t kNodeBytes =
    3 * sizeof(uint32_t) + 7 * sizeof(float) + 3 * sizeof(ExactSum) + sizeof(uint32_t);
constexpr size_t kEntryBytes =
    2 * sizeof(uint32_t) + 4 * sizeof(double) + sizeof(float) + 1 + sizeof(uint32_t);
constexpr size_t kKeyBytes = 2 * sizeof(uint32_t);
}  // namespace

void LtcLightSampler::check_memory(const SpatialClusters& clusters, uint32_t keys,
                                   const LtcSettings& s) {
  // As rll's cell table: the tables are allocated up front, so a configuration the machine cannot
  // hold is refused before, not grown into the out-of-memory killer. A full table's end of pass
  // lists the keys that asked for an entry: (visits, key) per key at most.
  const double needed = double(clusters.bytes()) +
                        double(keys) * (kKeyBytes + 2 * sizeof(uint32_t)) +
                        double(s.capacity) * (kEntryBytes + double(s.max_cut) * kNodeBytes);
  if (needed > double(memory_budget_bytes()))
    fail(
        "ltc.capacity={} with ltc.max_cut={} ({} spatial clusters x ltc.bins={}^2 direction bins) "
        "needs {} for its entries, more than {}; lower ltc.capacity, ltc.max_cut, ltc.clusters or "
        "ltc.bins",
        s.capacity, s.max_cut, clusters.size(), s.bins, format_bytes(needed),
        memory_budget_phrase());
}

size_t LtcLightSampler::bytes() const {
  return m_clusters.bytes() + size_t(m_keys) * kKeyBytes +
         size_t(m_s.capacity) * (kEntryBytes + size_t(m_m) * kNodeBytes);
}

uint32_t LtcLightSampler::direction_bin(const Vec3& wo) const {
  const float len = length(wo);
  if (!(len > 0)) return 0;
  const int bins = int(m_s.bins);
  const float theta = std::acos(clamp(wo.z / len, -1.0f, 1.0f));
  float phi = std::atan2(wo.y, wo.x);
  if (phi < 0) phi += 2 * kPi;
  const int bt = std::min(bins - 1, int(theta * (float(bins) / kPi)));
  const int bp = std::min(bins - 1, int(phi * (float(bins) / (2 * kPi))));
  return uint32_t(bt * bins + bp);
}

uint32_t LtcLightSampler::entry_key(const LightContext& ctx) const {
  return m_clusters.find(ctx.p) * m_s.bins * m_s.bins + direction_bin(ctx.wo);
}

namespace {
constexpr uint32_t kClaimed = 0xffffffffu,
                   kFull = 0xfffffffeu;  // m_slot's states besides entry + 1
}  // namespace

void LtcLightSampler::prepare(LightContext& ctx, float u) {
  (void)u;
  ctx.cell = kNoCell;
  if (length_sq(ctx.n) == 0) return;
  const uint32_t key = entry_key(ctx);
  uint32_t v = m_slot[key].load(std::memory_order_acquire);
  if (v == 0) {
    // Create the entry: claim the key's slot, then take the next free entry, so that each new
    // key of a pass takes exactly one while they last. The accumulators every entry records
    // into are already there, so a new entry needs nothing else until end_pass.
    uint32_t expected = 0;
    if (m_slot[key].compare_exchange_strong(expected, kClaimed, std::memory_order_acq_rel,
                                            std::memory_order_acquire)) {
      const uint32_t i = m_next_free.load(std::memory_order_relaxed) < m_free.size()
                             ? m_next_free.fetch_add(1, std::memory_order_relaxed)
                             : uint32_t(m_free.size());
      if (i < m_free.size()) {
        const uint32_t e = m_free[i];
        m_key[e] = key;
        m_born[e] = m_pass;
        v = e + 1;
      } else {
        m_failed.fetch_add(1, std::memory_order_relaxed);
        v = kFull;
      }
      m_slot[key].store(v, std::memory_order_release);
    } else {
      v = expected;
    }
  }
  while (v == kClaimed) {  // another thread is between claiming the slot and filling it
    std::this_thread::yield();
    v = m_slot[key].load(std::memory_order_acquire);
  }
  // New keys count their visits: if they outnumber the free entries, the most visited get them.
  if (v == kFull) {
    m_request[key].fetch_add(1, std::memory_order_relaxed);
    return;  // table full: the plain tree for this point
  }
  if (m_born[v - 1] == m_pass) m_request[key].fetch_add(1, std::memory_order_relaxed);
  ctx.cell = v - 1;
}

detail::RllCut LtcLightSampler::cut(uint32_t entry) const {
  return detail::rll_cut(m_cuts.view(), entry);
}

float LtcLightSampler::node_probability(uint32_t entry, uint32_t k) const {
  return detail::rll_cdf_width(cut(entry), k);
}

SampledLight LtcLightSampler::sample(const LightContext& ctx, double u) const {
  const uint32_t e = ctx.cell;
  if (e == kNoCell) return sampled_light(tree_descend(m_tree, LightTree::kRoot, ctx.p, ctx.n, u));
  if (!has_cut(e)) {
    // The entry's first pass: sample like the tree; the reward goes to the node of the global
    // cut that holds the light, whose P(l | node) is the descent's product below that node.
    const detail::RllCut initial = cut(e);  // (no cut: the initial one)
    DescentSplit split;
    split.ends = initial.ends;
    split.nodes = initial.nodes;
    split.size = initial.size;
    SampledLight s = sampled_light(tree_descend(m_tree, LightTree::kRoot, ctx.p, ctx.n, u, &split));
    if (!(s.pmf > 0)) return {};
    ClusterDraw d;
    d.cluster = detail::rll_cluster_of(initial, s.light);
    const float within = split.cluster == d.cluster ? split.below : 0.0f;
    d.cluster_pmf = within > 0 ? s.pmf / within : 0.0f;
    set_cluster_draw(s, d);
    return s;
  }
  // A node from the entry's CDF as rll's table draws a cluster (rll_view.h): the interval of u
  // that selects node k is [cdf[k-1], cdf[k]) in double, its width what node_probability reports.
  const detail::RllCut c = cut(e);
  uint32_t k = 0;
  double uw = 0;
  if (!detail::rll_table_draw(c, u, &k, &uw)) return {};
  const TreeSample w = tree_descend(m_tree, c.nodes[k], ctx.p, ctx.n, uw);
  if (!(w.pmf > 0)) return {};
  SampledLight s;
  s.light = w.light;
  ClusterDraw d;
  d.cluster = k;
  d.cluster_pmf = detail::rll_cdf_width(c, k);
  s.pmf = d.cluster_pmf * w.pmf;
  set_cluster_draw(s, d);
  return s.pmf > 0 ? s : SampledLight{};
}

float LtcLightSampler::pmf(const LightContext& ctx, uint32_t light) const {
  const uint32_t e = ctx.cell;
  if (!has_cut(e)) return tree_descend_pmf(m_tree, LightTree::kRoot, light, ctx.p, ctx.n);
  const detail::RllCut c = cut(e);
  const uint32_t k = detail::rll_cluster_of(c, light);
  if (k >= c.size) return 0;
  const float within = tree_descend_pmf(m_tree, c.nodes[k], light, ctx.p, ctx.n);
  return detail::rll_cdf_width(c, k) * within;
}

void LtcLightSampler::record(const LightContext& ctx, const SampledLight& s, const NeeRecord& r) {
  const uint32_t e = ctx.cell;
  const ClusterDraw d = cluster_draw(s);
  if (e == kNoCell || !(s.pmf > 0) || !(d.cluster_pmf > 0)) return;
  const float F = r.estimate * r.mis_weight;
  if (!(F >= 0) || !std::isfinite(F)) return;
  // r = F / P(l | node): the node's own estimator, whose second moment the node learns.
  const double within = double(s.pmf) / double(d.cluster_pmf);
  const size_t i = size_t(e) * m_m + d.cluster;
  const double square = add_reward(m_sum[i], m_sum2[i], double(F) / within * m_inv_unit[e]);
  // The first pass records into the global cut, whose nodes' children are known from the tree.
  const uint32_t mid = has_cut(e) ? m_mid[i] : m_initial_mid[d.cluster];
  if (s.light < mid) m_sum2_0[i].add(square);
  m_count[i].fetch_add(1, std::memory_order_relaxed);
}

float LtcLightSampler::bound(uint32_t entry, uint32_t node) const {
  return m_tree.importance(node, m_clusters.centre(m_key[entry] / (m_s.bins * m_s.bins)), Vec3(0));
}

void LtcLightSampler::clear_pass(size_t slot) {
  m_sum[slot].reset();
  m_sum2[slot].reset();
  m_sum2_0[slot].reset();
  m_count[slot].store(0, std::memory_order_relaxed);
}

void LtcLightSampler::learn(uint32_t e, uint64_t pass, LearnScratch& scratch, uint32_t& splits) {
  const size_t base = size_t(e) * m_m;
  const bool fresh = m_cuts.size[e] == 0;
  const uint32_t K0 = fresh ? uint32_t(m_cuts.initial.size()) : m_cuts.size[e];
  double N = 0;
  for (uint32_t k = 0; k < K0; ++k) N += m_count[base + k].load(std::memory_order_relaxed);
  if (N == 0)
    return;  // nothing new: the cut and CDF stand (a new entry keeps sampling like the tree)

  // This pass's mean reward and mean squared reward per node, in scene units.
  std::vector<double>& mean_r = scratch.mean_r;
  std::vector<double>& mean_r2 = scratch.mean_r2;
  std::vector<double>& mean_r2_0 = scratch.mean_r2_0;
  std::vector<double>& cnt = scratch.count;
  mean_r.assign(K0, 0.0);
  mean_r2.assign(K0, 0.0);
  mean_r2_0.assign(K0, 0.0);
  cnt.assign(K0, 0.0);
  const double unit = 1 / m_inv_unit[e];
  for (uint32_t k = 0; k < K0; ++k) {
    const size_t i = base + k;
    cnt[k] = m_count[i].load(std::memory_order_relaxed);
    if (cnt[k] > 0) {
      const RewardMoments r(cnt[k], m_sum[i].value() * unit, m_sum2[i].value() * unit * unit);
      mean_r[k] = r.mean;
      mean_r2[k] = r.mean2;
      mean_r2_0[k] = std::min(m_sum2_0[i].value() * unit * unit / cnt[k], mean_r2[k]);
    }
    clear_pass(i);
  }

  if (fresh) {
    // The global cut, with the prior bound (importance at the cluster's centre, power where the
    // centre sees none) scaled to what this first pass saw. The bound estimates a node's
    // contribution, a first moment: its unit is the visited nodes' mean reward over their share
    // of the bound (a share under a quarter counts as a quarter, so that one bright, rarely drawn
    // node does not inflate all the others). Being a mean, it is at most sqrt(M2) and gives way to
    // the learnt second moments wherever rewards vary.
    const uint32_t K = K0;
    std::vector<double>& b = scratch.bound;
    b.assign(K, 0.0);
    double bsum = 0;
    for (uint32_t k = 0; k < K; ++k) bsum += b[k] = bound(e, m_cuts.initial[k]);
    m_prior_power[e] = !(bsum > 0);
    if (m_prior_power[e]) {
      bsum = 0;
      for (uint32_t k = 0; k < K; ++k) bsum += b[k] = m_tree.node(m_cuts.initial[k]).bounds.power;
    }
    VisitedTotal sums;
    for (uint32_t k = 0; k < K; ++k)
      if (cnt[k] > 0) sums.add(mean_r[k], bsum > 0 ? b[k] / bsum : 0.0);
    const double total = sums.total();
    m_prior_scale[e] = bsum > 0 ? float(total / bsum) : 0.0f;
    for (uint32_t k = 0; k < K; ++k) {
      const double prior = double(m_prior_scale[e]) * b[k];
      m_cuts.node[base + k] = m_cuts.initial[k];
      m_w[base + k] = float(prior * prior);
      m_n[base + k] = m_mean[base + k] = m_sq[base + k] = m_sq0[base + k] = 0;
      m_pi[base + k] = 1;
    }
    m_cuts.size[e] = K;
  }

  // The per-sample rule w := (1 - a) w + a r^2 over the pass's visits, aggregated (header).
  const double T = m_visits[e];
  const double L = log_keep(T, N);
  const uint32_t K = m_cuts.size[e];
  for (uint32_t k = 0; k < K; ++k) {
    if (cnt[k] == 0) continue;
    const size_t i = base + k;
    // In its first pass the entry sampled like the tree, not from its cut: each node's rewards
    // of that pass count as its opening visits (rates a_1 .. a_n), not as a share of the entry's.
    const double b = fresh ? std::exp(log_keep(0, cnt[k])) : std::exp(L * cnt[k] / N);
    m_w[i] = float(b * m_w[i] + (1 - b) * mean_r2[k]);
    m_pi[i] = float(b * m_pi[i]);
    const double n = double(m_n[i]) + cnt[k];
    m_mean[i] = float((double(m_n[i]) * m_mean[i] + cnt[k] * mean_r[k]) / n);
    m_sq[i] = float((double(m_n[i]) * m_sq[i] + cnt[k] * mean_r2[k]) / n);
    m_sq0[i] = float((double(m_n[i]) * m_sq0[i] + cnt[k] * mean_r2_0[k]) / n);
    m_n[i] = float(n);
  }
  m_visits[e] = T + N;

  // Refinement: the published per-sample split probability, over the node's visits of the pass.
  if (int(K) < m_m && m_no_change[e] < double(m_s.no_change)) {
    double var_sum = 0, mean_sum = 0;
    for (uint32_t k = 0; k < K; ++k) {
      const size_t i = base + k;
      var_sum += std::max(0.0, double(m_sq[i]) - double(m_mean[i]) * m_mean[i]);
      mean_sum += m_mean[i];
    }
    auto& chosen = scratch.chosen;  // (variance share, node index)
    chosen.clear();
    if (var_sum > 0 && mean_sum > 0) {
      const double v_rel = var_sum / (mean_sum * mean_sum);
      const double p_e = 1 / (1 + double(K) / m_s.initial_cut * std::exp(-v_rel));
      for (uint32_t k = 0; k < K; ++k) {
        const size_t i = base + k;
        if (cnt[k] == 0 || m_tree.node(m_cuts.node[i]).is_leaf()) continue;
        const double p_v = std::max(0.0, double(m_sq[i]) - double(m_mean[i]) * m_mean[i]) / var_sum;
        const double p_t = 1 - 1 / std::max(1.0, double(m_n[i]));
        const double p = std::clamp(p_t * p_v * p_e, 0.0, 1.0);
        const double p_pass = -std::expm1(cnt[k] * std::log1p(-std::min(p, 1 - 1e-16)));
        if (unit_hash(m_key[e], m_cuts.node[i], pass) < p_pass) chosen.push_back({p_v, k});
      }
    }
    // More candidates than room: the largest variance shares first (ties: lower index).
    const size_t room = size_t(m_m) - K;
    if (chosen.size() > room) {
      std::sort(chosen.begin(), chosen.end(), [](const auto& a, const auto& b) {
        return a.first != b.first ? a.first > b.first : a.second < b.second;
      });
      chosen.resize(room);
    }
    std::sort(chosen.begin(), chosen.end(),
              [](const auto& a, const auto& b) { return a.second > b.second; });
    for (const auto& [share, k] : chosen) {  // back to front: earlier indices stay valid
      (void)share;
      const size_t i = base + k;
      const LightTreeNode& nd = m_tree.node(m_cuts.node[i]);
      float b0, b1;
      if (m_prior_power[e]) {
        b0 = m_tree.node(nd.child).bounds.power;
        b1 = m_tree.node(nd.child + 1).bounds.power;
      } else {
        b0 = bound(e, nd.child);
        b1 = bound(e, nd.child + 1);
      }
      const float prior0 = m_prior_scale[e] * b0, prior1 = m_prior_scale[e] * b1;
      if (!(b0 + b1 > 0)) {
        b0 = float(m_tree.node(nd.child).light_count());
        b1 = float(m_tree.node(nd.child + 1).light_count());
      }
      const double f0 = double(b0) / (double(b0) + double(b1)), f1 = 1 - f0;
      // What the parent learnt, shared by where its second moment came from (header), blended
      // with the children's own prior bounds by the parent's remaining prior share.
      const double w = std::max(0.0f, m_w[i]), sq = m_sq[i];
      const double g0 = sq > 0 ? std::clamp(double(m_sq0[i]) / sq, 0.0, 1.0) : f0, g1 = 1 - g0;
      const double pi = std::clamp(double(m_pi[i]), 0.0, 1.0);
      const double s0 = (1 - pi) * std::sqrt(f0 * g0 * w) + pi * prior0;
      const double s1 = (1 - pi) * std::sqrt(f1 * g1 * w) + pi * prior1;
      // Shift the nodes after k by one.
      const uint32_t Kcur = m_cuts.size[e];
      for (size_t j = base + Kcur; j > i + 1; --j) {
        m_cuts.node[j] = m_cuts.node[j - 1];
        m_w[j] = m_w[j - 1];
        m_n[j] = m_n[j - 1];
        m_mean[j] = m_mean[j - 1];
        m_sq[j] = m_sq[j - 1];
        m_sq0[j] = m_sq0[j - 1];
        m_pi[j] = m_pi[j - 1];
      }
      m_cuts.node[i] = nd.child;
      m_cuts.node[i + 1] = nd.child + 1;
      m_w[i] = float(s0 * s0);
      m_w[i + 1] = float(s1 * s1);
      m_n[i] = m_n[i + 1] = m_mean[i] = m_mean[i + 1] = m_sq[i] = m_sq[i + 1] = m_sq0[i] =
          m_sq0[i + 1] = 0;
      m_pi[i + 1] = m_pi[i] = float(pi);
      m_cuts.size[e] = Kcur + 1;
      ++splits;
    }
    m_no_change[e] = chosen.empty() ? m_no_change[e] + N : 0.0;
  }

  // The next pass's unit: the entry's largest learnt sqrt(M2).
  double largest = 0;
  for (uint32_t k = 0; k < m_cuts.size[e]; ++k)
    largest = std::max(largest, std::sqrt(double(m_w[base + k])));
  next_unit(m_inv_unit[e], largest);
  bake(e, scratch);
}

void LtcLightSampler::bake(uint32_t e, LearnScratch& scratch) {
  const size_t base = size_t(e) * m_m;
  const uint32_t K = m_cuts.size[e];
  if (K == 0) return;
  // Defensive distribution: half the prior share (bound at the cluster's centre, or power),
  // half uniform over the nodes with power, so every node that can contribute keeps P > 0.
  std::vector<double>& d = scratch.defensive;
  std::vector<double>& v = scratch.value;
  d.assign(K, 0.0);
  v.assign(K, 0.0);
  double bsum = 0, vsum = 0;
  uint32_t powered = 0;
  for (uint32_t k = 0; k < K; ++k) {
    const uint32_t node = m_cuts.node[base + k];
    const float power = m_tree.node(node).bounds.power;
    d[k] = m_prior_power[e] ? power : bound(e, node);
    bsum += d[k];
    powered += power > 0;
    v[k] = std::sqrt(std::max(0.0, double(m_w[base + k])));
    if (!std::isfinite(v[k])) v[k] = 0;
    vsum += v[k];
  }
  for (uint32_t k = 0; k < K; ++k) {
    const bool has_power = m_tree.node(m_cuts.node[base + k]).bounds.power > 0;
    const double uniform = powered > 0 ? (has_power ? 1.0 / powered : 0.0) : 1.0 / K;
    d[k] = bsum > 0 ? 0.5 * d[k] / bsum + 0.5 * uniform : uniform;
  }
  const double eps = vsum > 0 ? double(m_s.epsilon) : 1.0;
  double acc = 0;
  for (uint32_t k = 0; k < K; ++k) {
    acc += (vsum > 0 ? (1 - eps) * v[k] / vsum : 0.0) + eps * d[k];
    m_cuts.cdf[base + k] = float(acc);
    const LightTreeNode& nd = m_tree.node(m_cuts.node[base + k]);
    m_cuts.end[base + k] = nd.end;
    m_mid[base + k] = nd.is_leaf() ? 0 : m_tree.node(nd.child).end;
  }
  for (uint32_t k = 0; k < K; ++k)
    m_cuts.cdf[base + k] = float(std::min(1.0, double(m_cuts.cdf[base + k]) / acc));
  m_cuts.cdf[base + K - 1] = 1.0f;
}

void LtcLightSampler::admit_by_visits() {
  // Drop the entries this pass created: which new keys got one depended on thread timing.
  const uint32_t K0 =
      uint32_t(m_cuts.initial.size());  // a new entry records into the global cut's nodes
  uint32_t used = 0;
  for (uint32_t e = 0; e < m_s.capacity; ++e) {
    if (m_key[e] == kNoCell) continue;
    if (m_born[e] != m_pass) {
      ++used;
      continue;
    }
    for (size_t i = size_t(e) * m_m, end = i + K0; i < end; ++i) clear_pass(i);
    m_slot[m_key[e]].store(0, std::memory_order_relaxed);
    m_key[e] = kNoCell;
  }
  // Every key this pass visited without an entry from an earlier pass, by visits (ties: a hash
  // of the key), gets a free entry while they last; its first pass with rewards is the next.
  std::vector<std::pair<uint32_t, uint32_t>> want;  // (visits, key)
  for (uint32_t k = 0; k < m_keys; ++k) {
    const uint32_t n = m_request[k].load(std::memory_order_relaxed);
    if (n == 0) continue;
    want.push_back({n, k});
    m_failed_total += n;  // these visits learnt nothing
    m_request[k].store(0, std::memory_order_relaxed);
    if (m_slot[k].load(std::memory_order_relaxed) == kFull)
      m_slot[k].store(0, std::memory_order_relaxed);
  }
  const size_t room = std::min<size_t>(m_s.capacity - used, want.size());
  const auto first = [](const std::pair<uint32_t, uint32_t>& a,
                        const std::pair<uint32_t, uint32_t>& b) {
    return a.first != b.first ? a.first > b.first : mix64(a.second) < mix64(b.second);
  };
  std::nth_element(want.begin(), want.begin() + room, want.end(), first);
  uint32_t e = 0;
  for (size_t j = 0; j < room; ++j) {
    while (m_key[e] != kNoCell) ++e;
    m_key[e] = want[j].second;
    m_born[e] = m_pass;  // an entry of earlier passes from the next pass on
    m_slot[want[j].second].store(e + 1, std::memory_order_relaxed);
  }
}

void LtcLightSampler::end_pass() {
  if (m_failed.load(std::memory_order_relaxed) > 0) {
    admit_by_visits();
  } else {
    for (uint32_t e = 0; e < m_s.capacity; ++e)
      if (m_key[e] != kNoCell && m_born[e] == m_pass)
        m_request[m_key[e]].store(0, std::memory_order_relaxed);
  }
  std::vector<uint32_t> entries;
  for (uint32_t e = 0; e < m_s.capacity; ++e)
    if (m_key[e] != kNoCell) entries.push_back(e);
  std::atomic<uint32_t> splits{0};
  const uint64_t pass = m_pass;
  parallel_for(entries.size(), 64, [&](size_t b, size_t end) {
    uint32_t sp = 0;
    LearnScratch scratch;
    for (size_t j = b; j < end; ++j) learn(entries[j], pass, scratch, sp);
    splits += sp;
  });
  m_splits_per_pass.push_back(splits.load());
  m_free.clear();
  for (uint32_t e = 0; e < m_s.capacity; ++e)
    if (m_key[e] == kNoCell) m_free.push_back(e);
  m_next_free.store(0, std::memory_order_relaxed);
  m_failed.store(0, std::memory_order_relaxed);
  ++m_pass;
}

void LtcLightSampler::lights_changed(const Scene& scene) {
  (void)scene;
  parallel_for(m_s.capacity, 256, [&](size_t b, size_t e) {
    LearnScratch scratch;
    for (size_t i = b; i < e; ++i)
      if (m_key[i] != kNoCell) bake(uint32_t(i), scratch);
  });
}

nlohmann::json LtcLightSampler::describe() const {
  uint64_t used = 0, with_cut = 0;
  double cut_sum = 0;
  uint64_t total_splits = 0;
  for (uint32_t e = 0; e < m_s.capacity; ++e) {
    if (m_key[e] == kNoCell) continue;
    ++used;
    if (m_cuts.size[e] > 0) {
      ++with_cut;
      cut_sum += m_cuts.size[e];
    }
  }
  for (uint32_t s : m_splits_per_pass) total_splits += s;
  nlohmann::json parameters = nlohmann::json::object();
  params_json(ltc_params(), m_s, parameters);
  return {{"name", name()},
          {"parameters", parameters},
          {"passes", m_pass},
          {"spatial_clusters", m_clusters.size()},
          {"entries_used", used},
          {"entries_with_cut", with_cut},
          {"failed_inserts", m_failed_total},
          {"mean_cut_size", with_cut ? cut_sum / double(with_cut) : 0.0},
          {"splits", total_splits},
          {"splits_per_pass", m_splits_per_pass},
          {"bytes", bytes()}};
}

}  // namespace rll
