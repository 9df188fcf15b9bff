// BSDFs evaluated in a local shading frame: Lambertian, rough GGX conductor, rough plastic, and the
// pbrt-v4 models: dielectric (smooth or rough glass), thin dielectric and the layered coated
// diffuse. Microfacet lobes are sampled from the distribution of visible normals (Heitz 2018).
// docs/materials.md describes the models, their references and where rll departs from them.
// Header only and RLL_HD: the CPU renderer and the GPU kernels run these same functions.
#pragma once

#include <bit>
#include <cmath>
#include <cstdint>

#include "rll/core/hash.h"
#include "rll/core/math.h"
#include "rll/core/rng.h"
#include "rll/core/sampling.h"
#include "rll/scene/material.h"

namespace rll {

struct BsdfSample {
  Rgb f;          // BSDF value (without the cosine)
  Vec3 wi;        // world space, unit
  float pdf = 0;  // solid angle
  // A Dirac lobe (smooth glass, a thin pane, a smooth coating's mirror reflection): f and pdf
  // share the same delta factor, only f / pdf means anything, and neither eval() nor pdf() sees
  // this direction. The integrator gives a light hit after such a bounce full weight (no MIS).
  bool delta = false;
};

// GGX microfacet distribution with isotropic roughness alpha.
struct Ggx {
  float alpha;
  RLL_HD float d(const Vec3& wm) const;      // normal distribution D(wm)
  RLL_HD float lambda(const Vec3& w) const;  // Smith Lambda
  RLL_HD float g1(const Vec3& w) const { return 1 / (1 + lambda(w)); }
  RLL_HD float g(const Vec3& wo, const Vec3& wi) const { return 1 / (1 + lambda(wo) + lambda(wi)); }
  // Density of visible normals seen from wo: D_wo(wm) = G1(wo) |wo.wm| D(wm) / |wo.z|.
  RLL_HD float visible_d(const Vec3& wo, const Vec3& wm) const;
  RLL_HD Vec3 sample_visible(const Vec3& wo, Vec2 u) const;  // wo.z > 0
};

RLL_HD inline float fresnel_dielectric(float cos_i, float eta);
RLL_HD inline Rgb fresnel_conductor(float cos_i, const Rgb& eta, const Rgb& k);

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
  RLL_HD float f(const Vec3& wo, const Vec3& wi, bool radiance) const;  // 0 for a smooth interface
  RLL_HD float pdf(const Vec3& wo, const Vec3& wi, Lobes lobes) const;  // 0 for a smooth interface
  RLL_HD bool sample(const Vec3& wo, float uc, Vec2 u, bool radiance, Lobes lobes,
                     InterfaceSample& out) const;
};

// Roughness (GGX alpha) below which Dielectric and CoatedDiffuse interfaces are perfectly smooth.
inline constexpr float kSmoothAlpha = 1e-3f;

// The MIS weight CoatedDiffuse's eval() gives the base sample joined to wi through a rough coat
// (`--set coated.weights`, docs/materials.md). Unbiased: against the density of the join it
// competes with, so the two weights sum to one and eval() estimates f without bias. Pbrt: the
// weight of pbrt-v4's LayeredBxDF::f() (the coat's pdf from inside towards wi), which makes f()
// too high wherever light reaches a rough coat by light sampling; only to match pbrt-v4's images.
enum class CoatedWeights : uint8_t { Unbiased, Pbrt };

class Bsdf {
 public:
  // `albedo` is the material's albedo times its texture at the hit, `roughness` the roughness
  // there (negative: the material's). `ns` is the shading normal, `ng` the geometric normal as
  // wound (its side is the outside of a Dielectric, so that `ior` is the inside's index over the
  // outside's); both are flipped to the side of wo, so surfaces are two-sided. `seed` feeds the
  // random walk of the stochastic CoatedDiffuse (see eval()), `weights` one of its MIS weights;
  // other materials ignore both.
  RLL_HD Bsdf(const MaterialData& material, const Rgb& albedo, const Vec3& ns, const Vec3& ng,
              const Vec3& wo, float roughness = -1, uint64_t seed = 0,
              CoatedWeights weights = CoatedWeights::Unbiased);

  // CoatedDiffuse evaluates by a random walk between its interfaces (as pbrt-v4's LayeredBxDF):
  // eval() is then an unbiased estimate of f, seeded by (seed, wo, wi); pdf() an approximation
  // seeded by (wo, wi) only, so that it is a fixed function of the directions and MIS weights
  // built from it still sum to one; sample() returns f / pdf = the walk's weight (an unbiased
  // estimate of f cos / density) with pdf = pdf(wo, wi), seeded by (seed, u_lobe, u).
  RLL_HD Rgb eval(const Vec3& wo, const Vec3& wi) const;
  RLL_HD float pdf(const Vec3& wo, const Vec3& wi) const;
  // u_lobe chooses a lobe, u the direction; false if no direction could be sampled.
  RLL_HD bool sample(const Vec3& wo, float u_lobe, Vec2 u, BsdfSample& out) const;
  RLL_HD const Vec3& shading_normal() const { return m_frame.n; }
  RLL_HD const Vec3& geometric_normal() const { return m_ng; }
  // True if the BSDF reflects nothing (the path can stop).
  RLL_HD bool is_black() const { return m_black; }
  // Every lobe is a Dirac delta (smooth glass, thin pane): eval() and pdf() are zero everywhere,
  // so light sampling at this vertex is useless.
  RLL_HD bool is_delta() const { return m_delta_only; }
  // sample() may return a delta sample.
  RLL_HD bool has_delta() const { return m_has_delta; }
  // Light may pass to the other side of the geometric surface.
  RLL_HD bool has_transmission() const {
    return m_type == MaterialType::Dielectric || m_type == MaterialType::ThinDielectric;
  }
  // The BSDF's diffuse part, which path-space filtering's demodulation (render/psf.h) divides by
  // its albedo: Separable where a Lambertian lobe is summed apart from the glossy one (Diffuse,
  // Plastic: f = f_diffuse + f_glossy), Layered where the Lambertian base is reached through a
  // coat by a random walk that mixes the lobes (CoatedDiffuse), None where there is no diffuse
  // lobe (conductors, glass) or its albedo is black.
  enum class DiffusePart : uint8_t { None, Separable, Layered };
  RLL_HD DiffusePart diffuse_part() const;
  // The Lambertian lobe's albedo (texture included): Separable BSDFs'.
  RLL_HD const Rgb& diffuse_albedo() const { return m_albedo; }
  // The Lambertian lobe's share of f(wo, wi) per channel, in [0, 1] (0 where f is 0): 1 for
  // Diffuse, f_diffuse / f for Plastic. A Separable BSDF's only; multiplying an estimate of
  // f(wo, wi) (an NEE sample's, or a bounce's f / pdf) by it estimates the diffuse lobe's.
  RLL_HD Rgb diffuse_share(const Vec3& wo, const Vec3& wi) const;

 private:
  // Probability of sampling the specular lobe of a plastic, given wo (local).
  RLL_HD float specular_probability(const Vec3& wo_local) const;
  // A plastic's base seen through its coating twice, at local wo, wi (both above): its f's
  // diffuse term (eval), which diffuse_share takes the share of.
  RLL_HD Rgb plastic_base(const Vec3& wo_local, const Vec3& wi_local) const;
  RLL_HD bool same_side(const Vec3& wo, const Vec3& wi) const;
  // wi lies on the geometric side a sample of local side `local_above` must have.
  RLL_HD bool geometric_side_ok(const Vec3& wi_world, bool local_above) const;
  // CoatedDiffuse, local frame, wo.z > 0 and wi.z > 0.
  RLL_HD Rgb layered_eval(const Vec3& wo, const Vec3& wi, Pcg32& rng) const;
  RLL_HD float layered_pdf(const Vec3& wo, const Vec3& wi, Pcg32& rng) const;
  // The walk's sample: direction, the product of f and cosines, the product of pdfs.
  RLL_HD bool layered_sample(const Vec3& wo, float uc, Vec2 u, Pcg32& rng, Vec3& wi, Rgb& f,
                             float& pdf, bool& delta) const;
  RLL_HD float layer_transmittance(const Vec3& w) const;

  MaterialType m_type;
  Frame m_frame;
  Vec3 m_ng;
  Rgb m_albedo, m_specular, m_eta, m_k;
  float m_ior;
  Ggx m_ggx;
  DielectricInterface m_interface;  // Dielectric (eta relative to wo's side), CoatedDiffuse's coat
  float m_thickness = 0;
  uint64_t m_seed = 0;
  CoatedWeights m_weights = CoatedWeights::Unbiased;
  bool m_black;
  bool m_delta_only = false, m_has_delta = false;
};

// The definitions, inline so that nvcc compiles them into every kernel that calls them.

// --- GGX ----------------------------------------------------------------------------------------

RLL_HD inline float Ggx::d(const Vec3& wm) const {
  // Microfacets face outwards: a normal below the surface has zero density.
  if (wm.z <= 0) return 0;
  float cos2 = wm.z * wm.z;
  float tan2 = (1 - cos2) / cos2;
  float a2 = alpha * alpha;
  float e = 1 + tan2 / a2;
  return 1 / (kPi * a2 * cos2 * cos2 * e * e);
}

RLL_HD inline float Ggx::lambda(const Vec3& w) const {
  float cos2 = w.z * w.z;
  if (cos2 <= 0) return kInf;
  float tan2 = std::max(0.0f, 1 - cos2) / cos2;
  return (std::sqrt(1 + alpha * alpha * tan2) - 1) * 0.5f;
}

RLL_HD inline float Ggx::visible_d(const Vec3& wo, const Vec3& wm) const {
  if (wo.z <= 0) return 0;
  return g1(wo) / wo.z * d(wm) * std::max(0.0f, dot(wo, wm));
}

RLL_HD inline Vec3 Ggx::sample_visible(const Vec3& wo, Vec2 u) const {
  Vec3 vh = normalize(Vec3(alpha * wo.x, alpha * wo.y, wo.z));
  float lensq = vh.x * vh.x + vh.y * vh.y;
  Vec3 t1 = lensq > 1e-12f ? Vec3(-vh.y, vh.x, 0) / std::sqrt(lensq) : Vec3(1, 0, 0);
  Vec3 t2 = cross(vh, t1);
  float r = std::sqrt(u.x), phi = 2 * kPi * u.y;
  float p1 = r * std::cos(phi), p2 = r * std::sin(phi);
  float s = 0.5f * (1 + vh.z);
  p2 = (1 - s) * safe_sqrt(1 - p1 * p1) + s * p2;
  Vec3 nh = t1 * p1 + t2 * p2 + vh * safe_sqrt(1 - p1 * p1 - p2 * p2);
  return normalize(Vec3(alpha * nh.x, alpha * nh.y, std::max(1e-6f, nh.z)));
}

// --- Fresnel ------------------------------------------------------------------------------------

RLL_HD inline float fresnel_dielectric(float cos_i, float eta) {
  cos_i = clamp(cos_i, -1.0f, 1.0f);
  if (cos_i < 0) {
    eta = 1 / eta;
    cos_i = -cos_i;
  }
  float sin2_t = (1 - cos_i * cos_i) / (eta * eta);
  if (sin2_t >= 1) return 1;
  float cos_t = safe_sqrt(1 - sin2_t);
  float r_par = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
  float r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
  return 0.5f * (r_par * r_par + r_perp * r_perp);
}

namespace bsdf_detail {
// Fresnel reflectance of a conductor for one channel (complex index eta + i k).
RLL_HD inline float fresnel_complex(float cos_i, float eta, float k) {
  cos_i = clamp(cos_i, 0.0f, 1.0f);
  float c2 = cos_i * cos_i, s2 = 1 - c2;
  float e2 = eta * eta, k2 = k * k;
  float t0 = e2 - k2 - s2;
  float a2b2 = std::sqrt(std::max(0.0f, t0 * t0 + 4 * e2 * k2));
  float a = safe_sqrt(0.5f * (a2b2 + t0));
  float t1 = a2b2 + c2, t2 = 2 * cos_i * a;
  float rs = (t1 - t2) / (t1 + t2);
  float t3 = c2 * a2b2 + s2 * s2, t4 = t2 * s2;
  float rp = rs * (t3 - t4) / (t3 + t4);
  return clamp(0.5f * (rp + rs), 0.0f, 1.0f);
}
}  // namespace bsdf_detail

RLL_HD inline Rgb fresnel_conductor(float cos_i, const Rgb& eta, const Rgb& k) {
  return {bsdf_detail::fresnel_complex(cos_i, eta.x, k.x),
          bsdf_detail::fresnel_complex(cos_i, eta.y, k.y),
          bsdf_detail::fresnel_complex(cos_i, eta.z, k.z)};
}

// --- Dielectric interface ------------------------------------------------------------------------

namespace bsdf_detail {
// Refraction of w (pointing away from the surface) through the interface of normal +z, `eta` the
// index below over the index above. etap: the relative index seen from w's side.
RLL_HD inline bool refract_dir(const Vec3& w, Vec3 n, float eta, float& etap, Vec3& wt) {
  float cos_i = dot(n, w);
  if (cos_i < 0) {
    eta = 1 / eta;
    cos_i = -cos_i;
    n = -n;
  }
  float sin2_t = std::max(0.0f, 1 - cos_i * cos_i) / (eta * eta);
  if (sin2_t >= 1) return false;
  float cos_t = safe_sqrt(1 - sin2_t);
  wt = -w / eta + n * (cos_i / eta - cos_t);
  etap = eta;
  return true;
}

// Visible-normal density from either side: G1(w) |w.wm| D(wm) / |w.z|.
RLL_HD inline float visible_density(const Ggx& ggx, const Vec3& w, const Vec3& wm) {
  return ggx.g1(w) / std::abs(w.z) * ggx.d(wm) * std::abs(dot(w, wm));
}

// The microfacet normal of a pair (up-facing), its relative index and whether the pair reflects;
// false where no microfacet joins them or one faces away from it.
struct HalfVector {
  Vec3 wm;
  float etap;
  bool reflect;
};
RLL_HD inline bool half_vector(const Vec3& wo, const Vec3& wi, float eta, HalfVector& h) {
  if (wo.z == 0 || wi.z == 0) return false;
  h.reflect = wo.z * wi.z > 0;
  h.etap = h.reflect ? 1 : (wo.z > 0 ? eta : 1 / eta);
  Vec3 wm = wi * h.etap + wo;
  float len2 = length_sq(wm);
  if (!(len2 > 0)) return false;
  wm = wm / std::sqrt(len2);
  if (wm.z < 0) wm = -wm;
  if (dot(wm, wi) * wi.z < 0 || dot(wm, wo) * wo.z < 0) return false;
  h.wm = wm;
  return true;
}
}  // namespace bsdf_detail

RLL_HD inline float DielectricInterface::f(const Vec3& wo, const Vec3& wi, bool radiance) const {
  bsdf_detail::HalfVector h;
  if (smooth || !bsdf_detail::half_vector(wo, wi, eta, h)) return 0;
  const Vec3& wm = h.wm;
  float fr = fresnel_dielectric(dot(wo, wm), eta);
  if (h.reflect) return ggx.d(wm) * ggx.g(wo, wi) * fr / std::abs(4 * wi.z * wo.z);
  float denom = sqr(dot(wi, wm) + dot(wo, wm) / h.etap) * wi.z * wo.z;
  float ft = ggx.d(wm) * (1 - fr) * ggx.g(wo, wi) * std::abs(dot(wi, wm) * dot(wo, wm) / denom);
  if (radiance) ft /= sqr(h.etap);
  return ft;
}

RLL_HD inline float DielectricInterface::pdf(const Vec3& wo, const Vec3& wi, Lobes lobes) const {
  bsdf_detail::HalfVector h;
  if (smooth || !bsdf_detail::half_vector(wo, wi, eta, h)) return 0;
  const Vec3& wm = h.wm;
  float r = fresnel_dielectric(dot(wo, wm), eta), t = 1 - r;
  if (lobes == Lobes::Reflection) t = 0;
  if (lobes == Lobes::Transmission) r = 0;
  if (!(r + t > 0)) return 0;
  float vd = bsdf_detail::visible_density(ggx, wo, wm);
  if (h.reflect) return vd / (4 * std::abs(dot(wo, wm))) * r / (r + t);
  float denom = sqr(dot(wi, wm) + dot(wo, wm) / h.etap);
  return vd * std::abs(dot(wi, wm)) / denom * t / (r + t);
}

RLL_HD inline bool DielectricInterface::sample(const Vec3& wo, float uc, Vec2 u, bool radiance,
                                               Lobes lobes, InterfaceSample& out) const {
  if (wo.z == 0) return false;
  if (smooth) {
    float r = fresnel_dielectric(wo.z, eta), t = 1 - r;
    if (lobes == Lobes::Reflection) t = 0;
    if (lobes == Lobes::Transmission) r = 0;
    if (!(r + t > 0)) return false;
    out.delta = true;
    if (uc < r / (r + t)) {
      out.wi = Vec3(-wo.x, -wo.y, wo.z);
      out.f = r / std::abs(wo.z);
      out.pdf = r / (r + t);
      out.transmission = false;
      return true;
    }
    float etap;
    Vec3 wi;
    if (!bsdf_detail::refract_dir(wo, Vec3(0, 0, 1), eta, etap, wi) || wi.z == 0) return false;
    out.wi = wi;
    out.f = t / std::abs(wi.z);
    if (radiance) out.f /= sqr(etap);
    out.pdf = t / (r + t);
    out.transmission = true;
    return true;
  }
  Vec3 wm = ggx.sample_visible(wo.z > 0 ? wo : -wo, u);
  float r = fresnel_dielectric(dot(wo, wm), eta), t = 1 - r;
  if (lobes == Lobes::Reflection) t = 0;
  if (lobes == Lobes::Transmission) r = 0;
  if (!(r + t > 0)) return false;
  Vec3 wi;
  if (uc < r / (r + t)) {
    wi = reflect(wo, wm);
    if (!(wi.z * wo.z > 0)) return false;
    out.transmission = false;
  } else {
    float etap;
    if (!bsdf_detail::refract_dir(wo, wm, eta, etap, wi) || !(wi.z * wo.z < 0)) return false;
    out.transmission = true;
  }
  out.wi = wi;
  out.delta = false;
  out.f = f(wo, wi, radiance);
  out.pdf = pdf(wo, wi, lobes);
  return out.pdf > 0 && out.f > 0;
}

// --- Bsdf ---------------------------------------------------------------------------------------

namespace bsdf_detail {
inline constexpr int kLayerMaxDepth =
    10;  // pbrt-v4's coateddiffuse defaults: maxdepth 10, nsamples 1

RLL_HD inline uint64_t bits_of(const Vec3& v) {
  return mix64(std::bit_cast<uint32_t>(v.x) | uint64_t(std::bit_cast<uint32_t>(v.y)) << 32) ^
         mix64(std::bit_cast<uint32_t>(v.z) + 0x9e3779b97f4a7c15ull);
}
}  // namespace bsdf_detail

RLL_HD inline Bsdf::Bsdf(const MaterialData& m, const Rgb& albedo, const Vec3& ns, const Vec3& ng,
                         const Vec3& wo, float roughness, uint64_t seed, CoatedWeights weights)
    : m_type(m.type),
      m_albedo(albedo),
      m_specular(m.specular),
      m_eta(m.eta),
      m_k(m.k),
      m_ior(m.ior),
      m_ggx{std::max(1e-3f, roughness >= 0 ? roughness : m.roughness)},
      m_seed(seed),
      m_weights(weights) {
  m_ng = face_forward(ng, wo);
  Vec3 n = dot(ns, m_ng) < 0 ? -ns : ns;
  m_frame = Frame(n);
  const float alpha = roughness >= 0 ? roughness : m.roughness;
  // A copy: device code cannot bind std::max's reference to a host constant.
  const float smooth_alpha = kSmoothAlpha;
  switch (m.type) {
    case MaterialType::Dielectric:
      // The geometric normal as wound points outside: from there, ior is inside over outside.
      m_interface.eta = dot(wo, ng) >= 0 ? m.ior : 1 / m.ior;
      m_interface.smooth = !(alpha >= smooth_alpha);
      m_interface.ggx = Ggx{std::max(smooth_alpha, alpha)};
      m_delta_only = m_has_delta = m_interface.smooth;
      break;
    case MaterialType::ThinDielectric:
      m_delta_only = m_has_delta = true;
      break;
    case MaterialType::CoatedDiffuse:
      // Two-sided like pbrt-v4's: the coating faces wo whatever the winding.
      m_interface.eta = m.ior;
      m_interface.smooth = !(alpha >= smooth_alpha);
      m_interface.ggx = Ggx{std::max(smooth_alpha, alpha)};
      m_has_delta = m_interface.smooth;
      m_thickness = std::max(0.0f, m.thickness);
      break;
    default:
      break;
  }
  m_black = m.type == MaterialType::Diffuse     ? rll::is_black(albedo)
            : m.type == MaterialType::Conductor ? rll::is_black(m.specular)
            : m.type == MaterialType::Plastic   ? rll::is_black(albedo) && rll::is_black(m.specular)
                                                : false;
}

RLL_HD inline bool Bsdf::same_side(const Vec3& wo, const Vec3& wi) const {
  // Reflection only: both directions must lie above the geometric surface (no light leaks
  // through shading normals).
  return dot(wi, m_ng) > 0 && dot(wo, m_ng) > 0;
}

RLL_HD inline bool Bsdf::geometric_side_ok(const Vec3& wi, bool local_above) const {
  float c = dot(wi, m_ng);
  return local_above ? c > 0 : c < 0;
}

RLL_HD inline float Bsdf::specular_probability(const Vec3& wo) const {
  float f = fresnel_dielectric(wo.z, m_ior);
  float s = f * luminance(m_specular);
  float d = (1 - f) * luminance(m_albedo);
  if (s + d <= 0) return 0.5f;
  return clamp(s / (s + d), 0.1f, 0.9f);
}

// --- CoatedDiffuse: the layered random walk ------------------------------------------------------

RLL_HD inline float Bsdf::layer_transmittance(const Vec3& w) const {
  // The medium between the layers absorbs with unit density (albedo 0) over `thickness`.
  if (m_thickness <= 0) return 1;
  return std::exp(-m_thickness / std::abs(w.z));
}

RLL_HD inline Rgb Bsdf::layered_eval(const Vec3& wo, const Vec3& wi, Pcg32& rng) const {
  const DielectricInterface& top = m_interface;
  Rgb f(top.f(wo, wi, true));  // reflection off the coating
  InterfaceSample wos, wis;
  // Into the layer from wo, and (adjoint) from wi: the latter is the exit every base vertex is
  // joined to.
  if (!top.sample(wo, rng.next_float(), {rng.next_float(), rng.next_float()}, true,
                  Lobes::Transmission, wos) ||
      !(wos.f > 0) || !(wos.pdf > 0) || wos.wi.z == 0)
    return f;
  if (!top.sample(wi, rng.next_float(), {rng.next_float(), rng.next_float()}, false,
                  Lobes::Transmission, wis) ||
      !(wis.f > 0) || !(wis.pdf > 0) || wis.wi.z == 0)
    return f;
  Rgb beta(wos.f * std::abs(wos.wi.z) / wos.pdf);
  Vec3 w = wos.wi;  // travelling down
  bool at_top = true;
  for (int depth = 0; depth < bsdf_detail::kLayerMaxDepth; ++depth) {
    if (depth > 3 && max_component(beta) < 0.25f) {
      float q = std::max(0.0f, 1 - max_component(beta));
      if (rng.next_float() < q) break;
      beta /= 1 - q;
    }
    at_top = !at_top;
    beta *= layer_transmittance(w);
    if (at_top) {  // reflect off the coating's underside, back down
      InterfaceSample bs;
      if (!top.sample(-w, rng.next_float(), {rng.next_float(), rng.next_float()}, true,
                      Lobes::Reflection, bs) ||
          !(bs.f > 0) || !(bs.pdf > 0) || bs.wi.z == 0)
        break;
      beta *= bs.f * std::abs(bs.wi.z) / bs.pdf;
      w = bs.wi;
    } else {  // the Lambertian base
      // Next-event: join to the presampled exit direction.
      const float base_pdf = std::abs(wis.wi.z) * kInvPi;
      float wt = top.smooth ? 1 : power_heuristic(wis.pdf, base_pdf);
      f += beta * m_albedo *
           (kInvPi * std::abs(wis.wi.z) * wt * layer_transmittance(wis.wi) * wis.f / wis.pdf);
      Vec3 d = sample_cosine_hemisphere({rng.next_float(), rng.next_float()});
      if (!(d.z > 0)) break;
      beta *= m_albedo;  // (albedo / pi) cos / (cos / pi)
      w = d;
      if (!top.smooth) {  // the base sample leaving through the coating towards wi
        float f_exit = top.f(-w, wi, true);
        if (f_exit > 0) {
          // Unbiased: against the density of the joining strategy (wis drawn from wi, here -w).
          // Pbrt: pbrt-v4's exitInterface.PDF(-w, wi), the density of another strategy.
          const float other = m_weights == CoatedWeights::Pbrt
                                  ? top.pdf(-w, wi, Lobes::Transmission)
                                  : top.pdf(wi, -w, Lobes::Transmission);
          float wt2 = power_heuristic(d.z * kInvPi, other);
          f += beta * (layer_transmittance(d) * f_exit * wt2);
        }
      }
    }
    if (rll::is_black(beta)) break;
  }
  return f;
}

RLL_HD inline float Bsdf::layered_pdf(const Vec3& wo, const Vec3& wi, Pcg32& rng) const {
  const DielectricInterface& top = m_interface;
  float sum = top.pdf(wo, wi, Lobes::Reflection);
  InterfaceSample wos, wis;
  if (top.sample(wo, rng.next_float(), {rng.next_float(), rng.next_float()}, true,
                 Lobes::Transmission, wos) &&
      wos.f > 0 && wos.pdf > 0 &&
      top.sample(wi, rng.next_float(), {rng.next_float(), rng.next_float()}, false,
                 Lobes::Transmission, wis) &&
      wis.f > 0 && wis.pdf > 0) {
    const float r_pdf = std::abs(wis.wi.z) * kInvPi;  // base: -wos.wi to -wis.wi
    if (top.smooth) {
      sum += r_pdf;
    } else {
      Vec3 d = sample_cosine_hemisphere({rng.next_float(), rng.next_float()});
      if (d.z > 0) {
        sum += power_heuristic(wis.pdf, r_pdf) * r_pdf;
        float t_pdf = top.pdf(-d, wi, Lobes::All);
        sum += power_heuristic(d.z * kInvPi, t_pdf) * t_pdf;
      }
    }
  }
  // Mixed with the uniform density, as pbrt-v4 does, so that it is never zero.
  return 0.1f / (4 * kPi) + 0.9f * sum;
}

RLL_HD inline bool Bsdf::layered_sample(const Vec3& wo, float uc, Vec2 u, Pcg32& rng, Vec3& wi,
                                        Rgb& f, float& pdf, bool& delta) const {
  const DielectricInterface& top = m_interface;
  InterfaceSample bs;
  if (!top.sample(wo, uc, u, true, Lobes::All, bs) || !(bs.f > 0) || !(bs.pdf > 0) || bs.wi.z == 0)
    return false;
  if (!bs.transmission) {
    wi = bs.wi;
    f = Rgb(bs.f);
    pdf = bs.pdf;
    delta = bs.delta;
    return true;
  }
  Vec3 w = bs.wi;
  bool specular = bs.delta;
  f = Rgb(bs.f * std::abs(bs.wi.z));
  pdf = bs.pdf;
  bool at_top = true;
  for (int depth = 0; depth < bsdf_detail::kLayerMaxDepth; ++depth) {
    float rr = max_component(f) / pdf;
    if (depth > 3 && rr < 0.25f) {
      float q = std::max(0.0f, 1 - rr);
      if (rng.next_float() < q) return false;
      pdf *= 1 - q;
    }
    if (w.z == 0) return false;
    at_top = !at_top;
    f *= layer_transmittance(w);
    if (!at_top) {  // the Lambertian base
      Vec3 d = sample_cosine_hemisphere({rng.next_float(), rng.next_float()});
      if (!(d.z > 0)) return false;
      f *= m_albedo * (kInvPi * d.z);
      pdf *= d.z * kInvPi;
      specular = false;
      w = d;
    } else {
      InterfaceSample s;
      if (!top.sample(-w, rng.next_float(), {rng.next_float(), rng.next_float()}, true, Lobes::All,
                      s) ||
          !(s.f > 0) || !(s.pdf > 0) || s.wi.z == 0)
        return false;
      f *= Rgb(s.f);
      pdf *= s.pdf;
      specular = specular && s.delta;
      w = s.wi;
      if (s.transmission) {  // out through the coating: w points up
        wi = w;
        delta = specular;
        return true;
      }
      f *= Rgb(std::abs(s.wi.z));
    }
  }
  return false;
}

// --- Bsdf: eval, pdf, sample -------------------------------------------------------------------

RLL_HD inline Bsdf::DiffusePart Bsdf::diffuse_part() const {
  if (m_type == MaterialType::CoatedDiffuse) return DiffusePart::Layered;
  if ((m_type == MaterialType::Diffuse || m_type == MaterialType::Plastic) &&
      !rll::is_black(m_albedo))
    return DiffusePart::Separable;
  return DiffusePart::None;
}

RLL_HD inline Rgb Bsdf::diffuse_share(const Vec3& wo_w, const Vec3& wi_w) const {
  if (m_type == MaterialType::Diffuse) return Rgb(1);
  const Rgb f = eval(wo_w, wi_w);
  if (rll::is_black(f)) return Rgb(0);
  // eval()'s Plastic base term, under the same conditions (f is 0 where they fail).
  const Rgb d = plastic_base(m_frame.to_local(wo_w), m_frame.to_local(wi_w));
  Rgb share(0);
  for (int c = 0; c < 3; ++c)
    if (f[c] > 0) share[c] = std::min(1.0f, d[c] / f[c]);
  return share;
}

RLL_HD inline Rgb Bsdf::eval(const Vec3& wo_w, const Vec3& wi_w) const {
  if (m_type == MaterialType::Dielectric) {
    Vec3 wo = m_frame.to_local(wo_w), wi = m_frame.to_local(wi_w);
    if (wo.z <= 0 || dot(wo_w, m_ng) <= 0 || !geometric_side_ok(wi_w, wi.z > 0)) return Rgb(0);
    return Rgb(m_interface.f(wo, wi, true));
  }
  if (m_type == MaterialType::ThinDielectric) return Rgb(0);
  if (!same_side(wo_w, wi_w)) return Rgb(0);
  Vec3 wo = m_frame.to_local(wo_w), wi = m_frame.to_local(wi_w);
  if (wo.z <= 0 || wi.z <= 0) return Rgb(0);
  if (m_type == MaterialType::Diffuse) return m_albedo * kInvPi;
  if (m_type == MaterialType::CoatedDiffuse) {
    Pcg32 rng(mix64(m_seed ^ bsdf_detail::bits_of(wo)) ^ bsdf_detail::bits_of(wi),
              0x3c6ef372fe94f82bull);
    return layered_eval(wo, wi, rng);
  }
  Vec3 wm = normalize(wo + wi);
  float spec = m_ggx.d(wm) * m_ggx.g(wo, wi) / (4 * wo.z * wi.z);
  if (m_type == MaterialType::Conductor)
    return m_specular * fresnel_conductor(dot(wo, wm), m_eta, m_k) * spec;
  // Plastic: coating reflection plus the base seen through the coating twice.
  float fr = fresnel_dielectric(dot(wo, wm), m_ior);
  return m_specular * (fr * spec) + plastic_base(wo, wi);
}

RLL_HD inline Rgb Bsdf::plastic_base(const Vec3& wo, const Vec3& wi) const {
  const float t = (1 - fresnel_dielectric(wi.z, m_ior)) * (1 - fresnel_dielectric(wo.z, m_ior));
  return m_albedo * (t * kInvPi);
}

RLL_HD inline float Bsdf::pdf(const Vec3& wo_w, const Vec3& wi_w) const {
  if (m_type == MaterialType::Dielectric) {
    Vec3 wo = m_frame.to_local(wo_w), wi = m_frame.to_local(wi_w);
    if (wo.z <= 0 || dot(wo_w, m_ng) <= 0 || !geometric_side_ok(wi_w, wi.z > 0)) return 0;
    return m_interface.pdf(wo, wi, Lobes::All);
  }
  if (m_type == MaterialType::ThinDielectric) return 0;
  if (!same_side(wo_w, wi_w)) return 0;
  Vec3 wo = m_frame.to_local(wo_w), wi = m_frame.to_local(wi_w);
  if (wo.z <= 0 || wi.z <= 0) return 0;
  if (m_type == MaterialType::Diffuse) return cosine_hemisphere_pdf(wi.z);
  if (m_type == MaterialType::CoatedDiffuse) {
    // Seeded by the directions alone: a fixed function, so MIS weights from it sum to one.
    Pcg32 rng(bsdf_detail::bits_of(wo) ^ mix64(bsdf_detail::bits_of(wi)), 0x5851f42d4c957f2dull);
    return layered_pdf(wo, wi, rng);
  }
  Vec3 wm = normalize(wo + wi);
  float spec_pdf = m_ggx.visible_d(wo, wm) / (4 * dot(wo, wm));
  if (m_type == MaterialType::Conductor) return spec_pdf;
  float ps = specular_probability(wo);
  return ps * spec_pdf + (1 - ps) * cosine_hemisphere_pdf(wi.z);
}

RLL_HD inline bool Bsdf::sample(const Vec3& wo_w, float u_lobe, Vec2 u, BsdfSample& out) const {
  Vec3 wo = m_frame.to_local(wo_w);
  if (wo.z <= 0 || dot(wo_w, m_ng) <= 0) return false;
  out.delta = false;
  if (m_type == MaterialType::Dielectric) {
    InterfaceSample s;
    if (!m_interface.sample(wo, u_lobe, u, true, Lobes::All, s)) return false;
    out.wi = m_frame.to_world(s.wi);
    if (!geometric_side_ok(out.wi, s.wi.z > 0)) return false;
    out.f = Rgb(s.f);
    out.pdf = s.pdf;
    out.delta = s.delta;
    return out.pdf > 0;
  }
  if (m_type == MaterialType::ThinDielectric) {
    // Light bouncing inside the pane: R' = R + T^2 R / (1 - R^2), T' = 1 - R'.
    float r = fresnel_dielectric(wo.z, m_ior), t = 1 - r;
    if (r < 1) r += t * t * r / (1 - r * r);
    t = 1 - r;
    out.delta = true;
    if (u_lobe < r) {
      out.wi = m_frame.to_world(Vec3(-wo.x, -wo.y, wo.z));
      if (!geometric_side_ok(out.wi, true)) return false;
      out.f = Rgb(r / wo.z);
      out.pdf = r;
    } else {
      out.wi = -wo_w;
      out.f = Rgb(t / wo.z);
      out.pdf = t;
    }
    return out.pdf > 0;
  }
  if (m_type == MaterialType::CoatedDiffuse) {
    Pcg32 rng(
        mix64(m_seed ^ std::bit_cast<uint32_t>(u_lobe)) ^
            mix64(std::bit_cast<uint32_t>(u.x) | uint64_t(std::bit_cast<uint32_t>(u.y)) << 32),
        0x9b05688c2b3e6c1full);
    Vec3 wi;
    Rgb f;
    float walk_pdf;
    bool delta = false;
    if (!layered_sample(wo, u_lobe, u, rng, wi, f, walk_pdf, delta) || !(walk_pdf > 0))
      return false;
    if (!(wi.z > 0)) return false;
    out.wi = m_frame.to_world(wi);
    if (!geometric_side_ok(out.wi, true)) return false;
    out.delta = delta;
    if (delta) {
      out.f = f;
      out.pdf = walk_pdf;
      return true;
    }
    // The walk's weight f / walk_pdf, carried with pdf(): the pdf MIS weighs by.
    out.pdf = pdf(wo_w, out.wi);
    if (!(out.pdf > 0)) return false;
    out.f = f * (out.pdf / walk_pdf);
    return is_finite(out.f);
  }
  Vec3 wi;
  bool specular = m_type == MaterialType::Conductor ||
                  (m_type == MaterialType::Plastic && u_lobe < specular_probability(wo));
  if (specular) {
    Vec3 wm = m_ggx.sample_visible(wo, u);
    wi = reflect(wo, wm);
  } else {
    wi = sample_cosine_hemisphere(u);
  }
  if (wi.z <= 0) return false;
  out.wi = m_frame.to_world(wi);
  out.pdf = pdf(wo_w, out.wi);
  out.f = eval(wo_w, out.wi);
  return out.pdf > 0;
}

}  // namespace rll
