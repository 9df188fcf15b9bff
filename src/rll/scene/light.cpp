#include "rll/scene/light.h"

#include <fmt/format.h>

#include <algorithm>
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

Light make_spot_light(const Vec3& position, const Vec3& axis, const Rgb& intensity,
                      float cos_falloff_start, float cos_falloff_end) {
  Light l;
  l.type = LightType::Spot;
  l.p0 = position;
  l.n = normalize(axis);
  l.p1 = Vec3(cos_falloff_start, cos_falloff_end, 0);
  l.radiance = intensity;
  return l;
}

Light make_image_light(LightType type, const Vec3& position, const Vec3 to_light[3],
                       const Rgb& scale, uint32_t image, float power_factor) {
  Light l;
  l.type = type;
  l.p0 = position;
  l.p1 = to_light[0];
  l.p2 = to_light[1];
  l.n = to_light[2];
  l.radiance = scale;
  l.triangle = image;
  l.area = power_factor;
  return l;
}

float image_light_power_factor(const Light& l, const Image& image) {
  const int w = image.width(), h = image.height();
  if (w <= 0 || h <= 0) return 0;
  double sum = 0;
  if (l.type == LightType::Goniometric) {
    for (const Rgb& c : image.pixels()) sum += c.x;
    return float(4 * kPi * sum / (double(w) * h));
  }
  // The image spans [-a, a] x [-b, b] on the plane z = 1 of the light's frame.
  const double a = 1 / double(length(l.p1)), b = 1 / double(length(l.p2));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double s = a * (-1 + 2 * (x + 0.5) / w), t = b * (-1 + 2 * (y + 0.5) / h);
      const double cos = 1 / std::sqrt(1 + s * s + t * t);
      sum += double(luminance(image.at(x, y))) * cos * cos * cos;
    }
  return float(4 * a * b * sum / (double(w) * h));
}

SpotAngles spot_angles(const Light& l) {
  constexpr double kDeg = 180 / 3.14159265358979323846;
  const double end = std::acos(std::clamp(double(l.p1.y), -1.0, 1.0)) * kDeg,
               start = std::acos(std::clamp(double(l.p1.x), -1.0, 1.0)) * kDeg;
  return {end, std::max(0.0, end - start)};
}

float spot_solid_angle(float cos_falloff_start, float cos_falloff_end) {
  return 2 * kPi * ((1 - cos_falloff_start) + (cos_falloff_start - cos_falloff_end) / 2);
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
    case LightType::Spot:
      return spot_solid_angle(l.p1.x, l.p1.y) * lum;
    case LightType::Goniometric:
    case LightType::Projection:
      return l.area * lum;
  }
  return 0;
}

const char* light_type_name(LightType type) {
  switch (type) {
    case LightType::Triangle:
      return "triangle";
    case LightType::Point:
      return "point";
    case LightType::Directional:
      return "directional";
    case LightType::Spot:
      return "spot";
    case LightType::Goniometric:
      return "goniometric";
    case LightType::Projection:
      return "projection";
  }
  return "?";
}

std::string light_parameter_problem(const Light& l) {
  auto values = [](const Vec3& v) { return fmt::format("({}, {}, {})", v.x, v.y, v.z); };
  auto not_finite = [&](const char* what, const Vec3& v) {
    return fmt::format("its {} {} is not finite", what, values(v));
  };
  switch (l.type) {
    case LightType::Triangle:
      for (const Vec3* p : {&l.p0, &l.p1, &l.p2})
        if (!is_finite(*p)) return not_finite("vertex", *p);
      break;
    case LightType::Directional:
      if (!is_finite(l.p0)) return not_finite("direction", l.p0);
      break;
    case LightType::Spot:
      if (!is_finite(l.n)) return not_finite("axis", l.n);
      [[fallthrough]];
    case LightType::Point:
      if (!is_finite(l.p0)) return not_finite("position", l.p0);
      break;
    case LightType::Goniometric:
    case LightType::Projection:
      if (!is_finite(l.p0)) return not_finite("position", l.p0);
      for (const Vec3* r : {&l.p1, &l.p2, &l.n})
        if (!is_finite(*r)) return not_finite("transform's row", *r);
      break;
  }
  const char* emission = l.type == LightType::Triangle      ? "radiance"
                         : l.type == LightType::Directional ? "irradiance"
                         : l.has_image()                    ? "scale"
                                                            : "intensity";
  if (!is_finite(l.radiance)) return not_finite(emission, l.radiance);
  if (min_component(l.radiance) < 0)
    return fmt::format("its {} {} is negative", emission, values(l.radiance));
  return "";
}

}  // namespace rll
