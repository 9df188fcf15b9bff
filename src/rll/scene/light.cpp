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

LightLiSample sample_li(const Light& l, const Vec3& p, Vec2 u) {
  LightLiSample s;
  switch (l.type) {
    case LightType::Triangle: {
      Vec2 b = sample_uniform_triangle(u);
      Vec3 y = l.p0 * b.x + l.p1 * b.y + l.p2 * (1 - b.x - b.y);
      Vec3 d = y - p;
      float d2 = length_sq(d);
      if (!(d2 > 0) || l.area <= 0) return s;
      float dist = std::sqrt(d2);
      Vec3 wi = d / dist;
      float cos_l = std::abs(dot(l.n, wi));
      Rgb L = emitted_radiance(l, -wi);
      if (cos_l <= 0 || is_black(L)) return s;
      s.L = L;
      s.wi = wi;
      s.dist = dist;
      s.pdf = d2 / (cos_l * l.area);
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
