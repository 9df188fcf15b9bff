#include "rll/scene/light.h"

#include <algorithm>
#include <cmath>

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

// Double-precision 3-vectors for the spherical warp below, whose angle differences lose most
// of a float's precision on thin triangles.
struct D3 {
  double x, y, z;
};
D3 d3(const Vec3& v) { return {v.x, v.y, v.z}; }
D3 operator+(D3 a, D3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
D3 operator-(D3 a, D3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
D3 operator*(D3 a, double s) { return {a.x * s, a.y * s, a.z * s}; }
double ddot(D3 a, D3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
D3 dcross(D3 a, D3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
double dlen(D3 a) { return std::sqrt(ddot(a, a)); }
D3 dnorm(D3 a) { return a * (1 / dlen(a)); }

// Uniform direction in the spherical triangle spanned by directions a, b, c (Arvo 1995):
// choose the sub-triangle area u.x * omega, which fixes a point C' on arc AC, then a point on
// arc BC' with the right density.
Vec3 sample_spherical_triangle(const Vec3& a, const Vec3& b, const Vec3& c, Vec2 u) {
  D3 A = dnorm(d3(a)), B = dnorm(d3(b)), C = dnorm(d3(c));
  // Angles at the vertices, from the normals of the planes through the origin and two vertices.
  D3 n_ab = dcross(A, B), n_ac = dcross(A, C), n_bc = dcross(B, C);
  double l_ab = dlen(n_ab), l_ac = dlen(n_ac), l_bc = dlen(n_bc);
  if (!(l_ab > 0 && l_ac > 0 && l_bc > 0)) return a;
  auto angle = [](D3 x, double lx, D3 y, double ly) { return std::acos(std::clamp(ddot(x, y) / (lx * ly), -1.0, 1.0)); };
  double alpha = angle(n_ab, l_ab, n_ac, l_ac);
  double beta = angle(n_ab * -1.0, l_ab, n_bc, l_bc);
  double gamma = angle(n_ac, l_ac, n_bc, l_bc);
  double omega = alpha + beta + gamma - M_PI;
  double cos_alpha = std::cos(alpha), sin_alpha = std::sin(alpha), cos_c = ddot(A, B);
  double area = u.x * omega;
  double s = std::sin(area - alpha), t = std::cos(area - alpha);
  double uu = t - cos_alpha, vv = s + sin_alpha * cos_c;
  double q = std::clamp(((vv * t - uu * s) * cos_alpha - vv) / ((vv * s + uu * t) * sin_alpha), -1.0, 1.0);
  D3 c_perp = C - A * ddot(C, A);
  double lp = dlen(c_perp);
  if (!(lp > 0)) return a;
  D3 C2 = A * q + c_perp * (std::sqrt(std::max(0.0, 1 - q * q)) / lp);
  double z = 1 - u.y * (1 - ddot(C2, B));
  D3 b_perp = C2 - B * ddot(C2, B);
  double lb = dlen(b_perp);
  if (!(lb > 0)) return b;
  D3 w = dnorm(B * z + b_perp * (std::sqrt(std::max(0.0, 1 - z * z)) / lb));
  return {float(w.x), float(w.y), float(w.z)};
}

bool use_spherical(float omega) { return omega > kMinSphericalSolidAngle && omega < kMaxSphericalSolidAngle; }

// The solid angle a triangle light subtends at p where spherical sampling may use it, else 0.
// A triangle inside a sphere of radius r around its centroid, seen from distance d > r,
// subtends at most area / (d - r)^2: when that bound is already below the spherical threshold
// (a sky dome's triangles, far lamps) the exact formula, with its three normalisations and an
// arctangent, is skipped. The decision is the same as with the exact angle.
float spherical_solid_angle(const Light& l, const Vec3& p) {
  const Vec3 c = l.centroid();
  const float r2 = std::max({length_sq(l.p0 - c), length_sq(l.p1 - c), length_sq(l.p2 - c)});
  const float d2 = length_sq(p - c);
  if (d2 > r2) {
    const float gap = std::sqrt(d2) - std::sqrt(r2);
    if (l.area < kMinSphericalSolidAngle * 0.5f * gap * gap) return 0;
  }
  return triangle_solid_angle(p, l.p0, l.p1, l.p2);
}

}  // namespace

LightLiSample sample_li(const Light& l, const Vec3& p, Vec2 u) {
  LightLiSample s;
  switch (l.type) {
    case LightType::Triangle: {
      if (l.area <= 0) return s;
      float omega = spherical_solid_angle(l, p);
      Vec3 y;
      if (use_spherical(omega)) {
        Vec3 w = sample_spherical_triangle(l.p0 - p, l.p1 - p, l.p2 - p, u);
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
  float omega = spherical_solid_angle(l, p);
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
