// Sampling warps from the unit square and discrete distributions (built on the host, sampled by
// RLL_HD functions over their flat view, which kernels call).
#pragma once

#include <span>
#include <vector>

#include "rll/core/math.h"

namespace rll {

RLL_HD inline Vec2 sample_uniform_disk_concentric(Vec2 u) {
  float ox = 2 * u.x - 1, oy = 2 * u.y - 1;
  if (ox == 0 && oy == 0) return {0, 0};
  float r, theta;
  if (std::abs(ox) > std::abs(oy)) {
    r = ox;
    theta = (kPi / 4) * (oy / ox);
  } else {
    r = oy;
    theta = kPi / 2 - (kPi / 4) * (ox / oy);
  }
  return {r * std::cos(theta), r * std::sin(theta)};
}

RLL_HD inline Vec3 sample_cosine_hemisphere(Vec2 u) {
  Vec2 d = sample_uniform_disk_concentric(u);
  float z = safe_sqrt(1 - d.x * d.x - d.y * d.y);
  return {d.x, d.y, z};
}
RLL_HD inline float cosine_hemisphere_pdf(float cos_theta) {
  return cos_theta > 0 ? cos_theta * kInvPi : 0;
}

RLL_HD inline Vec3 sample_uniform_sphere(Vec2 u) {
  float z = 1 - 2 * u.x;
  float r = safe_sqrt(1 - z * z);
  float phi = 2 * kPi * u.y;
  return {r * std::cos(phi), r * std::sin(phi), z};
}

// Uniform point on a triangle as barycentrics (b0, b1); b2 = 1 - b0 - b1.
// Heitz 2019's low-distortion square-to-triangle map.
RLL_HD inline Vec2 sample_uniform_triangle(Vec2 u) {
  float b0, b1;
  if (u.x < u.y) {
    b0 = u.x / 2;
    b1 = u.y - b0;
  } else {
    b1 = u.y / 2;
    b0 = u.x - b1;
  }
  return {b0, b1};
}

RLL_HD inline float power_heuristic(float f_pdf, float g_pdf) {
  float f = f_pdf * f_pdf, g = g_pdf * g_pdf;
  if (std::isinf(f)) return 1;
  return f + g > 0 ? f / (f + g) : 0;
}

// What sampling a DiscreteDistribution reads: its tables, owning nothing (DESIGN 6).
struct DistributionView {
  View<const float> pmf;
  View<const double> cdf;      // cdf[i] = sum of pmf[0..i], last == 1
  View<const uint32_t> guide;  // size()+1 cutpoints: first index whose cdf exceeds k/size()
  double total = 0;
  RLL_HD bool empty() const { return total <= 0; }
};

// The index whose CDF interval holds u (first entry whose cdf exceeds u; entries with zero pmf are
// never returned because their cdf equals their predecessor's), and u rescaled to a fresh uniform
// value in [0,1) for reuse. d must not be empty.
// The guide table narrows the search to the entries between two cutpoints, usually one or two;
// then a branchless upper bound over them (its halving steps compile to conditional moves, which
// the branch predictor cannot miss). The result is the plain inverse-CDF index.
RLL_HD inline size_t sample_discrete(const DistributionView& d, double u,
                                     double* u_remapped = nullptr) {
  const double* base = d.cdf.data;
  size_t n = d.cdf.size;
  if (!d.guide.empty()) {
    const size_t g = d.guide.size - 1;
    const size_t k = std::min(size_t(u * double(g)), g - 1);
    base += d.guide[k];
    n = size_t(d.guide[k + 1] - d.guide[k]) + 1;
  }
  for (; n > 1;) {
    const size_t half = n / 2;
    base = base[half] <= u ? base + half : base;
    n -= half;
  }
  size_t i = std::min<size_t>(size_t(base - d.cdf.data) + (*base <= u), d.cdf.size - 1);
  while (d.pmf[i] == 0 && i > 0) --i;  // guard against u rounding onto a zero-width tail
  if (u_remapped) {
    double lo = i == 0 ? 0.0 : d.cdf[i - 1];
    double width = d.cdf[i] - lo;
    *u_remapped = width > 0 ? clamp((u - lo) / width, 0.0, 0x1.fffffffffffffp-1) : 0.0;
  }
  return i;
}

// A piecewise-constant discrete distribution sampled by CDF inversion (binary search).
class DiscreteDistribution {
 public:
  DiscreteDistribution() = default;
  explicit DiscreteDistribution(std::span<const float> weights);
  size_t size() const { return m_pmf.size(); }
  bool empty() const { return m_total <= 0; }
  double total() const { return m_total; }
  float pmf(size_t i) const { return m_pmf[i]; }
  // Returns the index and rescales u to a fresh uniform value in [0,1) for reuse.
  size_t sample(double u, double* u_remapped = nullptr) const {
    return sample_discrete(view(), u, u_remapped);
  }
  // Valid while the distribution lives and is not reassigned.
  DistributionView view() const {
    return {view_of(m_pmf), view_of(m_cdf), view_of(m_guide), m_total};
  }

 private:
  std::vector<float> m_pmf;
  std::vector<double> m_cdf;      // m_cdf[i] = sum of pmf[0..i], last == 1
  std::vector<uint32_t> m_guide;  // size()+1 cutpoints: first index whose cdf exceeds k/size()
  double m_total = 0;
};

}  // namespace rll
