#include "rll/scene/light.h"

#include <cmath>

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

float light_power(const Light& l, float scene_radius) {
  float lum = luminance(l.radiance);
  switch (l.type) {
    case LightType::Triangle:
      return kPi * l.area * lum * (l.two_sided ? 2.0f : 1.0f);
    case LightType::Point:
      return 4 * kPi * lum;
    case LightType::Directional:
      return kPi * scene_radius * scene_radius * lum;
  }
  return 0;
}

}  // namespace rll
