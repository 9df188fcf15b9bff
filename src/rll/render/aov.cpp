#include "rll/render/aov.h"

#include <cmath>
#include <limits>

#include "rll/core/error.h"
#include "rll/core/hash.h"
#include "rll/lights/oracle_sampler.h"
#include "rll/lights/rll_sampler.h"
#include "rll/lights/rll_view.h"

namespace rll {

const std::vector<AovInfo>& aov_list() {
  static const std::vector<AovInfo> list = {
      {Aov::Cell, "cell", "the sampler's cell id of the point (-1: none)"},
      {Aov::Probability, "probability", "the mean pmf of the light chosen"},
      {Aov::Entropy, "entropy", "entropy in bits of the cell's cluster distribution"},
      {Aov::Visible, "visible", "share of light samples whose shadow ray reached the light"},
      {Aov::Rewards, "rewards", "rewards the cell has received"},
  };
  return list;
}

const char* aov_name(Aov aov) {
  for (const auto& a : aov_list())
    if (a.kind == aov) return a.name;
  return "?";
}

std::vector<Aov> parse_aovs(const std::string& list, const char* flag) {
  std::string valid;
  for (const auto& a : aov_list()) valid += (valid.empty() ? "" : ", ") + std::string(a.name);
  std::vector<Aov> out;
  size_t begin = 0;
  for (;;) {
    const size_t end = list.find(',', begin);
    const std::string name = list.substr(begin, end == std::string::npos ? end : end - begin);
    const AovInfo* found = nullptr;
    for (const auto& a : aov_list())
      if (name == a.name) found = &a;
    if (!found) fail("{}: unknown diagnostic '{}' (valid: {})", flag, name, valid);
    for (Aov seen : out)
      if (seen == found->kind) fail("{}: '{}' is given twice", flag, name);
    out.push_back(found->kind);
    if (end == std::string::npos) break;
    begin = end + 1;
  }
  return out;
}

const RllLightSampler* sampler_cells(const LightSampler& sampler) {
  return sampler.learnt_cells().rll;
}

double cell_entropy(const CutStore& cuts, uint32_t cell) {
  if (!cuts.active(cell) || cuts.settings().guided) return std::numeric_limits<double>::quiet_NaN();
  const detail::RllCut cut{cuts.size(cell), cuts.ends(cell), cuts.nodes(cell), cuts.cdf(cell)};
  double h = 0;
  for (uint32_t k = 0; k < cut.size; ++k) {
    const double p = detail::rll_cdf_width(cut, k);
    if (p > 0) h -= p * std::log2(p);
  }
  return h;
}

std::vector<std::pair<std::string, std::vector<float>>> resolve_aovs(const Film& film,
                                                                     const LightSampler& sampler,
                                                                     const std::vector<Aov>& aovs) {
  const CameraVertexSums* v = film.camera_vertex();
  if (!v) fail("the film kept no camera vertices to make diagnostics of");
  const RllLightSampler* rll = sampler_cells(sampler);
  // The oracle's cuts come from shadow rays, not rewards (its own count is a stand-in of 1e30
  // that keeps the learnt share whole): its `rewards` are the shadow rays of the cell's estimates.
  const OracleLightSampler* oracle = sampler.learnt_cells().oracle;
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  const size_t n = v->cell.size();
  // A pixel's cell, if the sampler still has it.
  auto cell_of = [&](size_t i) {
    const uint32_t c = v->cell[i];
    return rll && c != CameraVertexSample::kNone && c < rll->table().capacity() &&
                   rll->table().in_use(c)
               ? c
               : CameraVertexSample::kNone;
  };
  std::vector<std::pair<std::string, std::vector<float>>> out;
  for (Aov aov : aovs) {
    std::vector<float> values(n, kNaN);
    for (size_t i = 0; i < n; ++i) {
      const uint32_t c = cell_of(i);
      switch (aov) {
        case Aov::Cell:
          values[i] = c == CameraVertexSample::kNone ? -1.0f : float(c);
          break;
        case Aov::Probability:
          if (v->sampled[i]) values[i] = float(v->light_pmf[i] / v->sampled[i]);
          break;
        case Aov::Entropy:
          if (c != CameraVertexSample::kNone) values[i] = float(cell_entropy(rll->cuts(), c));
          break;
        case Aov::Visible:
          if (v->shadow[i]) values[i] = float(double(v->visible[i]) / v->shadow[i]);
          break;
        case Aov::Rewards:
          if (c != CameraVertexSample::kNone)
            values[i] = oracle ? oracle->shadow_rays_of(c) : rll->cuts().rewards_seen(c);
          break;
      }
    }
    out.emplace_back(std::string("aov.") + aov_name(aov), std::move(values));
  }
  return out;
}

Rgb cell_colour(float id) {
  if (!(id >= 0)) return Rgb(0);
  const uint64_t h = mix64(uint64_t(id) + 0x9e3779b97f4a7c15ull);
  auto channel = [&](int i) { return 0.15f + 0.85f * float((h >> (16 * i)) & 0xffff) / 65535.0f; };
  return Rgb(channel(0), channel(1), channel(2));
}

}  // namespace rll
