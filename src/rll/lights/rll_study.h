// The error budget's ideal light choice within a cluster (rll.ideal_light, docs/rll.md "The error
// budget"): rll (or the oracle) as it is, except that inside the cluster its table chose, a light
// is drawn in proportion to its contribution at the cell's anchor, visibility included, estimated
// with rll.ideal_light shadow rays per light and cached per cell and cluster (or, with
// rll.ideal_light_at=point, at each shading point, computed for each sample and pmf). A study, not
// a sampler: host-only (the host kind, which device renderers refuse), and costly.
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <memory>
#include <mutex>
#include <unordered_map>
#include <vector>

#include "rll/core/image.h"
#include "rll/lights/light_sampler.h"
#include "rll/scene/light.h"

namespace rll {

struct RllView;

// The i-th of n points of a Hammersley set in [0,1)^2, rotated by `shift` (Cranley-Patterson):
// each point is uniform (so an average over them is unbiased), and the set is stratified. The
// studies' many points on a light and many BSDF directions.
inline Vec2 rotated_hammersley(uint32_t i, uint32_t n, Vec2 shift) {
  uint32_t b = i;
  b = (b << 16) | (b >> 16);
  b = ((b & 0x00ff00ffu) << 8) | ((b & 0xff00ff00u) >> 8);
  b = ((b & 0x0f0f0f0fu) << 4) | ((b & 0xf0f0f0f0u) >> 4);
  b = ((b & 0x33333333u) << 2) | ((b & 0xccccccccu) >> 2);
  b = ((b & 0x55555555u) << 1) | ((b & 0xaaaaaaaau) >> 1);
  const float x = (float(i) + 0.5f) / float(n), y = float(b) * 0x1p-32f;
  auto wrap = [](float a) { return std::min(a - std::floor(a), 0x1.fffffep-1f); };
  return {wrap(x + shift.x), wrap(y + shift.y)};
}

class IdealLightSampler final : public LightSampler {
 public:
  // `inner`: rll or the oracle (a sampler whose view is rll's); `rays` per light of a cluster;
  // `at_point`: the distribution at each shading point itself, not at its cell's anchor.
  IdealLightSampler(std::unique_ptr<LightSampler> inner, const Scene& scene, const Accel& accel,
                    uint32_t rays, bool at_point = false);
  SamplerView sampler_view() const override;
  void end_pass() override;
  void lights_changed(const Scene& scene) override;
  void save_state(BinaryWriter& w) const override { m_inner->save_state(w); }
  void load_state(BinaryReader& r) override;
  nlohmann::json describe() const override;
  const LightSampler& inner() const { return *m_inner; }

  // The host kind's calls (LightSampler::set_host_calls).
  void prepare(LightContext& ctx, float u) const;
  SampledLight sample(const LightContext& ctx, double u) const;
  float pmf(const LightContext& ctx, uint32_t light) const;
  void record(const LightContext& ctx, const SampledLight& s, const NeeRecord& r);

  // The share of a cluster's probability left to rll's own within-cluster rule at the point, so
  // that a light the anchor does not see keeps a probability where the point does (unbiased).
  static constexpr float kDefensive = 0.1f;

 private:
  // A cluster's lights at a cell's anchor: the CDF of their estimated contributions (empty where
  // none was seen: rll's rule alone).
  struct Table {
    std::vector<float> cdf;
  };
  // The cached table of cluster `k` of the cell's cut, computed on first use; null where the
  // cache is full (rll's rule alone there).
  // At the shading point instead (rll.ideal_light_at=point): computed into `scratch` every time.
  const Table* table(const RllView& v, const LightContext& ctx, uint32_t k, Table& scratch) const;
  // The table of the lights [begin, end) at point p with normal `normal`, its rays seeded by
  // `seed`.
  Table compute(const Vec3& p, const Vec3& normal, uint32_t begin, uint32_t end,
                uint64_t seed) const;
  // The probability of light l (in cluster k of the cell's cut) within its cluster, `t` the
  // cluster's table (table()).
  float within_pmf(const RllView& v, const LightContext& ctx, uint32_t k, uint32_t l,
                   const Table* t) const;

  std::unique_ptr<LightSampler> m_inner;
  // What the estimates read of the scene, copied (the scene may move after construction, as a
  // test's fixture does; lights_changed copies them again): the lights in tree order, each one's
  // image where it has one (a view into the scene's texture, whose pixels a move keeps in place),
  // and the scene's bounds for shadow rays to directional lights.
  void copy_lights(const Scene& scene);
  std::vector<Light> m_lights;
  std::vector<TexelView> m_images;
  Vec3 m_center;
  float m_radius = 1;
  const Accel& m_accel;
  uint32_t m_rays;
  bool m_at_point;
  SamplerView m_inner_view;
  struct Key {
    uint64_t cell_key;
    uint32_t node;
    bool operator==(const Key&) const = default;
  };
  struct KeyHash {
    size_t operator()(const Key& k) const;
  };
  static constexpr int kShards = 64;
  struct Shard {
    std::mutex mutex;
    std::unordered_map<Key, std::unique_ptr<Table>, KeyHash> tables;
  };
  std::unique_ptr<Shard[]> m_shards;
  // Bytes the cached tables may take (a quarter of the memory budget), and what they take.
  double m_budget_bytes = 0;
  mutable std::atomic<uint64_t> m_bytes{0}, m_tables{0}, m_rays_traced{0}, m_full{0};
};

}  // namespace rll
