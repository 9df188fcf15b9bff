#include "rll/scene/light.h"

#include "rll/core/sampling.h"

namespace rll {

void refresh_triangle_light(Light& l) {
  Vec3 c = cross(l.p1 - l.p0, l.p2 - l.p0);
  float len = length(c);
  l.area = 0.5f * len;
  l.n = len > 0 ? c / len : Vec3(0, 0, 1);
}

Light make_triangle_light(const Vec3& a, const Vec3& b, const Vec3& c, const Rgb& radiance,
                          bool two_sided, uint32_t triangle) {
  Light l;
  l.type = LightType::Triangle;
  l.p0 = a;
  l.p1 = b;
  l.p2 = c;
  l.radiance = radiance;
  l.two_sided = two_sided;
  l.triangle = triangle;
  refresh_triangle_light(l);
  return l;
}

Light make_point_light(const Vec3& position, const Rgb& intensity) {
  Light l;
  l.type = LightType::Point;
  l.p0 = position;
  l.radiance = intensity;
  return l;
}

Light make_directional_light(const Vec3& direction_to_light, const Rgb& irradiance) {
  Light l;
  l.type = LightType::Directional;
  l.p0 = normalize(direction_to_light);
  l.radiance = irradiance;
  return l;
}

Rgb emitted_radiance(const Light& l, const Vec3& w) {
  if (l.type != LightType::Triangle) return Rgb(0);
  float c = dot(l.n, w);
  return (c > 0 || (l.two_sided && c < 0)) ? l.radiance : Rgb(0);
}

float triangle_solid_angle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  Vec3 A = a - p, B = b - p, C = c - p;
  float la = length(A), lb = length(B), lc = length(C);
  if (!(la > 0 && lb > 0 && lc > 0)) return 0;
  A /= la;
  B /= lb;
  C /= lc;
  float num = std::abs(dot(A, cross(B, C)));
  float den = 1 + dot(A, B) + dot(B, C) + dot(C, A);
  return std::abs(2 * std::atan2(num, den));
}

namespace {

// Uniform direction in the spherical triangle (A, B, C) (unit vectors) of area `omega`
// (Arvo 1995): choose the sub-triangle area u0*omega, which fixes a point C' on arc AC, then a
// point on arc BC' with the right density.
Vec3 sample_spherical_triangle(const Vec3& A, const Vec3& B, const Vec3& C, float omega, Vec2 u) {
  // Angle at A between arcs AB and AC, from the normals of the planes OAB and OAC.
  Vec3 n_ab = cross(A, B), n_ac = cross(A, C);
  float l_ab = length(n_ab), l_ac = length(n_ac);
  if (!(l_ab > 0 && l_ac > 0)) return A;
  float cos_alpha = clamp(dot(n_ab, n_ac) / (l_ab * l_ac), -1.0f, 1.0f);
  float alpha = std::acos(cos_alpha), sin_alpha = std::sin(alpha);
  float cos_c = dot(A, B);
  float area = u.x * omega;
  float s = std::sin(area - alpha), t = std::cos(area - alpha);
  float uu = t - cos_alpha, vv = s + sin_alpha * cos_c;
  float q = ((vv * t - uu * s) * cos_alpha - vv) / ((vv * s + uu * t) * sin_alpha);
  q = clamp(q, -1.0f, 1.0f);
  Vec3 c_perp = C - A * dot(C, A);
  float lp = length(c_perp);
  if (!(lp > 0)) return A;
  Vec3 C2 = A * q + c_perp * (safe_sqrt(1 - q * q) / lp);
  float z = 1 - u.y * (1 - dot(C2, B));
  Vec3 b_perp = C2 - B * dot(C2, B);
  float lb = length(b_perp);
  if (!(lb > 0)) return B;
  return normalize(B * z + b_perp * (safe_sqrt(1 - z * z) / lb));
}

bool use_spherical(float omega) { return omega > kMinSphericalSolidAngle && omega < kMaxSphericalSolidAngle; }

}  // namespace

LightLiSample sample_li(const Light& l, const Vec3& p, Vec2 u) {
  LightLiSample s;
  switch (l.type) {
    case LightType::Triangle: {
      if (l.area <= 0) return s;
      float omega = triangle_solid_angle(p, l.p0, l.p1, l.p2);
      Vec3 y;
      if (use_spherical(omega)) {
        Vec3 w = sample_spherical_triangle(normalize(l.p0 - p), normalize(l.p1 - p), normalize(l.p2 - p), omega, u);
        // The point on the triangle's plane along w.
        float denom = dot(l.n, w);
        if (denom == 0) return s;
        float t = dot(l.n, l.p0 - p) / denom;
        if (!(t > 0)) return s;
        y = p + w * t;
      } else {
        Vec2 b = sample_uniform_triangle(u);
        y = l.p0 * b.x + l.p1 * b.y + l.p2 * (1 - b.x - b.y);
      }
      Vec3 d = y - p;
      float d2 = length_sq(d);
      if (!(d2 > 0)) return s;
      float dist = std::sqrt(d2);
      Vec3 wi = d / dist;
      float cos_l = std::abs(dot(l.n, wi));
      Rgb L = emitted_radiance(l, -wi);
      if (cos_l <= 0 || is_black(L)) return s;
      s.L = L;
      s.wi = wi;
      s.dist = dist;
      s.pdf = use_spherical(omega) ? 1 / omega : d2 / (cos_l * l.area);
      s.point = y;
      return s;
    }
    case LightType::Point: {
      Vec3 d = l.p0 - p;
      float d2 = length_sq(d);
      if (!(d2 > 0)) return s;
      s.dist = std::sqrt(d2);
      s.wi = d / s.dist;
      s.L = l.radiance / d2;
      s.pdf = 1;
      s.point = l.p0;
      return s;
    }
    case LightType::Directional:
      s.wi = l.p0;
      s.dist = kInf;
      s.L = l.radiance;
      s.pdf = 1;
      return s;
  }
  return s;
}

float pdf_li(const Light& l, const Vec3& p, const Vec3& y) {
  if (l.type != LightType::Triangle || l.area <= 0) return 0;
  Vec3 d = y - p;
  float d2 = length_sq(d);
  if (!(d2 > 0)) return 0;
  float omega = triangle_solid_angle(p, l.p0, l.p1, l.p2);
  if (use_spherical(omega)) return 1 / omega;
  float cos_l = std::abs(dot(l.n, d)) / std::sqrt(d2);
  return cos_l > 0 ? d2 / (cos_l * l.area) : 0;
}

float light_power(const Light& l, float scene_radius) {
  float lum = luminance(l.radiance);
  switch (l.type) {
    case LightType::Triangle: return kPi * l.area * lum * (l.two_sided ? 2.0f : 1.0f);
    case LightType::Point: return 4 * kPi * lum;
    case LightType::Directional: return kPi * scene_radius * scene_radius * lum;
  }
  return 0;
}

}  // namespace rll
