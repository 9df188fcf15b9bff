#include "rll/scene/bsdf.h"

#include "rll/core/sampling.h"

namespace rll {

// --- GGX ----------------------------------------------------------------------------------------

float Ggx::d(const Vec3& wm) const {
  // Microfacets face outwards: a normal below the surface has zero density.
  if (wm.z <= 0) return 0;
  float cos2 = wm.z * wm.z;
  float tan2 = (1 - cos2) / cos2;
  float a2 = alpha * alpha;
  float e = 1 + tan2 / a2;
  return 1 / (kPi * a2 * cos2 * cos2 * e * e);
}

float Ggx::lambda(const Vec3& w) const {
  float cos2 = w.z * w.z;
  if (cos2 <= 0) return kInf;
  float tan2 = std::max(0.0f, 1 - cos2) / cos2;
  return (std::sqrt(1 + alpha * alpha * tan2) - 1) * 0.5f;
}

float Ggx::visible_d(const Vec3& wo, const Vec3& wm) const {
  if (wo.z <= 0) return 0;
  return g1(wo) / wo.z * d(wm) * std::max(0.0f, dot(wo, wm));
}

Vec3 Ggx::sample_visible(const Vec3& wo, Vec2 u) const {
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

float fresnel_dielectric(float cos_i, float eta) {
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

namespace {
// Fresnel reflectance of a conductor for one channel (complex index eta + i k).
float fresnel_complex(float cos_i, float eta, float k) {
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
}  // namespace

Rgb fresnel_conductor(float cos_i, const Rgb& eta, const Rgb& k) {
  return {fresnel_complex(cos_i, eta.x, k.x), fresnel_complex(cos_i, eta.y, k.y),
          fresnel_complex(cos_i, eta.z, k.z)};
}

// --- Bsdf ---------------------------------------------------------------------------------------

Bsdf::Bsdf(const Material& m, const Rgb& albedo, const Vec3& ns, const Vec3& ng, const Vec3& wo)
    : m_type(m.type),
      m_albedo(albedo),
      m_specular(m.specular),
      m_eta(m.eta),
      m_k(m.k),
      m_ior(m.ior),
      m_ggx{std::max(1e-3f, m.roughness)} {
  m_ng = face_forward(ng, wo);
  Vec3 n = dot(ns, m_ng) < 0 ? -ns : ns;
  m_frame = Frame(n);
  m_black = m.type == MaterialType::Diffuse ? rll::is_black(albedo)
            : m.type == MaterialType::Conductor ? rll::is_black(m.specular)
                                                : rll::is_black(albedo) && rll::is_black(m.specular);
}

bool Bsdf::same_side(const Vec3& wo, const Vec3& wi) const {
  // Reflection only: both directions must lie above the geometric surface (no light leaks
  // through shading normals).
  return dot(wi, m_ng) > 0 && dot(wo, m_ng) > 0;
}

float Bsdf::specular_probability(const Vec3& wo) const {
  float f = fresnel_dielectric(wo.z, m_ior);
  float s = f * luminance(m_specular);
  float d = (1 - f) * luminance(m_albedo);
  if (s + d <= 0) return 0.5f;
  return clamp(s / (s + d), 0.1f, 0.9f);
}

Rgb Bsdf::eval(const Vec3& wo_w, const Vec3& wi_w) const {
  if (!same_side(wo_w, wi_w)) return Rgb(0);
  Vec3 wo = m_frame.to_local(wo_w), wi = m_frame.to_local(wi_w);
  if (wo.z <= 0 || wi.z <= 0) return Rgb(0);
  if (m_type == MaterialType::Diffuse) return m_albedo * kInvPi;
  Vec3 wm = normalize(wo + wi);
  float spec = m_ggx.d(wm) * m_ggx.g(wo, wi) / (4 * wo.z * wi.z);
  if (m_type == MaterialType::Conductor)
    return m_specular * fresnel_conductor(dot(wo, wm), m_eta, m_k) * spec;
  // Plastic: coating reflection plus the base seen through the coating twice.
  float fr = fresnel_dielectric(dot(wo, wm), m_ior);
  float t = (1 - fresnel_dielectric(wi.z, m_ior)) * (1 - fresnel_dielectric(wo.z, m_ior));
  return m_specular * (fr * spec) + m_albedo * (t * kInvPi);
}

float Bsdf::pdf(const Vec3& wo_w, const Vec3& wi_w) const {
  if (!same_side(wo_w, wi_w)) return 0;
  Vec3 wo = m_frame.to_local(wo_w), wi = m_frame.to_local(wi_w);
  if (wo.z <= 0 || wi.z <= 0) return 0;
  if (m_type == MaterialType::Diffuse) return cosine_hemisphere_pdf(wi.z);
  Vec3 wm = normalize(wo + wi);
  float spec_pdf = m_ggx.visible_d(wo, wm) / (4 * dot(wo, wm));
  if (m_type == MaterialType::Conductor) return spec_pdf;
  float ps = specular_probability(wo);
  return ps * spec_pdf + (1 - ps) * cosine_hemisphere_pdf(wi.z);
}

bool Bsdf::sample(const Vec3& wo_w, float u_lobe, Vec2 u, BsdfSample& out) const {
  Vec3 wo = m_frame.to_local(wo_w);
  if (wo.z <= 0 || dot(wo_w, m_ng) <= 0) return false;
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
