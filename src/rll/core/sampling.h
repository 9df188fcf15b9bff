// Sampling warps from the unit square (RLL_HD: kernels call them) and small discrete
// distributions (host only).
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
  size_t sample(double u, double* u_remapped = nullptr) const;

 private:
  std::vector<float> m_pmf;
  std::vector<double> m_cdf;      // m_cdf[i] = sum of pmf[0..i], last == 1
  std::vector<uint32_t> m_guide;  // size()+1 cutpoints: first index whose cdf exceeds k/size()
  double m_total = 0;
};

}  // namespace rll
