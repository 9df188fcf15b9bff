// BSDFs evaluated in a local shading frame: Lambertian, rough GGX conductor, rough plastic.
// Microfacet lobes are sampled from the distribution of visible normals (Heitz 2018).
#pragma once

#include "rll/core/math.h"
#include "rll/scene/material.h"

namespace rll {

struct BsdfSample {
  Rgb f;       // BSDF value (without the cosine)
  Vec3 wi;     // world space, unit
  float pdf = 0;  // solid angle
};

// GGX microfacet distribution with isotropic roughness alpha.
struct Ggx {
  float alpha;
  float d(const Vec3& wm) const;               // normal distribution D(wm)
  float lambda(const Vec3& w) const;           // Smith Lambda
  float g1(const Vec3& w) const { return 1 / (1 + lambda(w)); }
  float g(const Vec3& wo, const Vec3& wi) const { return 1 / (1 + lambda(wo) + lambda(wi)); }
  // Density of visible normals seen from wo: D_wo(wm) = G1(wo) |wo.wm| D(wm) / |wo.z|.
  float visible_d(const Vec3& wo, const Vec3& wm) const;
  Vec3 sample_visible(const Vec3& wo, Vec2 u) const;  // wo.z > 0
};

float fresnel_dielectric(float cos_i, float eta);
Rgb fresnel_conductor(float cos_i, const Rgb& eta, const Rgb& k);

class Bsdf {
 public:
  // `albedo` is the material's albedo times its texture at the hit. `ns` is the shading normal,
  // `ng` the geometric normal; both are flipped to the side of wo, so surfaces are two-sided.
  Bsdf(const Material& material, const Rgb& albedo, const Vec3& ns, const Vec3& ng, const Vec3& wo);

  Rgb eval(const Vec3& wo, const Vec3& wi) const;
  float pdf(const Vec3& wo, const Vec3& wi) const;
  // u_lobe chooses a lobe, u the direction; false if no direction could be sampled.
  bool sample(const Vec3& wo, float u_lobe, Vec2 u, BsdfSample& out) const;
  const Vec3& shading_normal() const { return m_frame.n; }
  const Vec3& geometric_normal() const { return m_ng; }
  // True if the BSDF reflects nothing (the path can stop).
  bool is_black() const { return m_black; }

 private:
  // Probability of sampling the specular lobe of a plastic, given wo (local).
  float specular_probability(const Vec3& wo_local) const;
  bool same_side(const Vec3& wo, const Vec3& wi) const;

  MaterialType m_type;
  Frame m_frame;
  Vec3 m_ng;
  Rgb m_albedo, m_specular, m_eta, m_k;
  float m_ior;
  Ggx m_ggx;
  bool m_black;
};

}  // namespace rll
