// BSDFs evaluated in a local shading frame: Lambertian, rough GGX conductor, rough plastic, and the
// pbrt-v4 models: dielectric (smooth or rough glass), thin dielectric and the layered coated
// diffuse. Microfacet lobes are sampled from the distribution of visible normals (Heitz 2018).
// docs/materials.md describes the models, their references and where rll departs from them.
#pragma once

#include <cstdint>

#include "rll/core/math.h"
#include "rll/scene/material.h"

namespace rll {

class Pcg32;

struct BsdfSample {
  Rgb f;       // BSDF value (without the cosine)
  Vec3 wi;     // world space, unit
  float pdf = 0;  // solid angle
  // A Dirac lobe (smooth glass, a thin pane, a smooth coating's mirror reflection): f and pdf
  // share the same delta factor, only f / pdf means anything, and neither eval() nor pdf() sees
  // this direction. The integrator gives a light hit after such a bounce full weight (no MIS).
  bool delta = false;
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

// Which lobes of a dielectric interface a sample or pdf is restricted to.
enum class Lobes : uint8_t { All, Reflection, Transmission };

struct InterfaceSample {
  float f = 0;  // BSDF value (the interface is colourless)
  Vec3 wi;
  float pdf = 0;
  bool delta = false, transmission = false;
};

// A dielectric interface in its local frame (normal +z), smooth or GGX-rough. `eta` is the index
// below the surface (z < 0) over the index above; wo and wi may lie on either side. `radiance`
// selects radiance transport, where refraction scales by 1 / eta'^2 (eta' the relative index
// seen from wo); importance transport (the adjoint, used by the layered model's walk) does not.
struct DielectricInterface {
  float eta = 1.5f;
  Ggx ggx{0.1f};
  bool smooth = true;
  float f(const Vec3& wo, const Vec3& wi, bool radiance) const;  // 0 for a smooth interface
  float pdf(const Vec3& wo, const Vec3& wi, Lobes lobes) const;  // 0 for a smooth interface
  bool sample(const Vec3& wo, float uc, Vec2 u, bool radiance, Lobes lobes, InterfaceSample& out) const;
};

// Roughness (GGX alpha) below which Dielectric and CoatedDiffuse interfaces are perfectly smooth.
inline constexpr float kSmoothAlpha = 1e-3f;

class Bsdf {
 public:
  // `albedo` is the material's albedo times its texture at the hit, `roughness` the roughness
  // there (negative: the material's). `ns` is the shading normal, `ng` the geometric normal as
  // wound (its side is the outside of a Dielectric, so that `ior` is the inside's index over the
  // outside's); both are flipped to the side of wo, so surfaces are two-sided. `seed` feeds the
  // random walk of the stochastic CoatedDiffuse (see eval()); other materials ignore it.
  Bsdf(const Material& material, const Rgb& albedo, const Vec3& ns, const Vec3& ng, const Vec3& wo,
       float roughness = -1, uint64_t seed = 0);

  // CoatedDiffuse evaluates by a random walk between its interfaces (as pbrt-v4's LayeredBxDF):
  // eval() is then an unbiased estimate of f, seeded by (seed, wo, wi); pdf() an approximation
  // seeded by (wo, wi) only, so that it is a fixed function of the directions and MIS weights
  // built from it still sum to one; sample() returns f / pdf = the walk's weight (an unbiased
  // estimate of f cos / density) with pdf = pdf(wo, wi), seeded by (seed, u_lobe, u).
  Rgb eval(const Vec3& wo, const Vec3& wi) const;
  float pdf(const Vec3& wo, const Vec3& wi) const;
  // u_lobe chooses a lobe, u the direction; false if no direction could be sampled.
  bool sample(const Vec3& wo, float u_lobe, Vec2 u, BsdfSample& out) const;
  const Vec3& shading_normal() const { return m_frame.n; }
  const Vec3& geometric_normal() const { return m_ng; }
  // True if the BSDF reflects nothing (the path can stop).
  bool is_black() const { return m_black; }
  // Every lobe is a Dirac delta (smooth glass, thin pane): eval() and pdf() are zero everywhere,
  // so light sampling at this vertex is useless.
  bool is_delta() const { return m_delta_only; }
  // sample() may return a delta sample.
  bool has_delta() const { return m_has_delta; }
  // Light may pass to the other side of the geometric surface.
  bool has_transmission() const {
    return m_type == MaterialType::Dielectric || m_type == MaterialType::ThinDielectric;
  }

 private:
  // Probability of sampling the specular lobe of a plastic, given wo (local).
  float specular_probability(const Vec3& wo_local) const;
  bool same_side(const Vec3& wo, const Vec3& wi) const;
  // wi lies on the geometric side a sample of local side `local_above` must have.
  bool geometric_side_ok(const Vec3& wi_world, bool local_above) const;
  // CoatedDiffuse, local frame, wo.z > 0 and wi.z > 0.
  Rgb layered_eval(const Vec3& wo, const Vec3& wi, Pcg32& rng) const;
  float layered_pdf(const Vec3& wo, const Vec3& wi, Pcg32& rng) const;
  // The walk's sample: direction, the product of f and cosines, the product of pdfs.
  bool layered_sample(const Vec3& wo, float uc, Vec2 u, Pcg32& rng, Vec3& wi, Rgb& f, float& pdf,
                      bool& delta) const;
  float layer_transmittance(const Vec3& w) const;

  MaterialType m_type;
  Frame m_frame;
  Vec3 m_ng;
  Rgb m_albedo, m_specular, m_eta, m_k;
  float m_ior;
  Ggx m_ggx;
  DielectricInterface m_interface;  // Dielectric (eta relative to wo's side), CoatedDiffuse's coat
  float m_thickness = 0;
  uint64_t m_seed = 0;
  bool m_black;
  bool m_delta_only = false, m_has_delta = false;
};

}  // namespace rll
