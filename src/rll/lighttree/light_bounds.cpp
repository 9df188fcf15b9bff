#include "rll/lighttree/light_bounds.h"

#include <fmt/format.h>

#include <cmath>

#include "rll/scene/scene.h"

namespace rll {

namespace {
// cos of a cone's half-angle theta, widened by a hair and rounded down so that float rounding
// never excludes a member direction (near theta = 0, cos rounds to exactly 1 otherwise).
inline float widened_cos(float theta) {
  if (theta >= kPi) return -1;
  return std::nextafter(float(std::cos(std::min(double(kPi), double(theta) * (1 + 1e-5) + 1e-6))),
                        -1.0f);
}
// Rotates v about the unit axis k by angle theta (Rodrigues).
Vec3 rotate(const Vec3& v, const Vec3& k, float theta) {
  float c = std::cos(theta), s = std::sin(theta);
  return v * c + cross(k, v) * s + k * (dot(k, v) * (1 - c));
}
}  // namespace

void merge_cones(const Vec3& wa, float cos_a, const Vec3& wb, float cos_b, Vec3& w,
                 float& cos_out) {
  float theta_a = safe_acos(cos_a), theta_b = safe_acos(cos_b);
  // atan2 keeps small angles between nearly parallel axes, which acos of the dot rounds to 0.
  float theta_d = std::atan2(length(cross(wa, wb)), dot(wa, wb));
  if (std::min(theta_d + theta_b, kPi) <= theta_a) {
    w = wa;
    cos_out = cos_a;
    return;
  }
  if (std::min(theta_d + theta_a, kPi) <= theta_b) {
    w = wb;
    cos_out = cos_b;
    return;
  }
  float theta_o = 0.5f * (theta_a + theta_d + theta_b);
  if (theta_o >= kPi) {
    w = wa;
    cos_out = -1;  // the whole sphere
    return;
  }
  Vec3 wr = cross(wa, wb);
  if (length_sq(wr) < 1e-12f) {
    if (theta_d < 0.5f * kPi) {  // nearly parallel: a's axis, wide enough for b
      w = wa;
      cos_out = widened_cos(theta_d + theta_b);
      return;
    }
    wr = Frame(wa).s;  // (nearly) opposite: any rotation axis across them will do
  }
  w = normalize(rotate(wa, normalize(wr), theta_o - theta_a));
  cos_out = widened_cos(theta_o);
}

namespace {
// A light whose power exceeds kMaxSamplingPower (or overflows a float), sampled as one of that
// power: its power and side power scaled down by one factor, computed in double where they are
// finite, and its largest radiance with them, so that importance's near-field bound
// (side_power / (pi max_radiance), the light's area) stays what it was.
void cap_power(const Light& l, LightBounds& b) {
  const double lum =
      0.2126 * double(l.radiance.x) + 0.7152 * double(l.radiance.y) + 0.0722 * double(l.radiance.z);
  double side = 0;
  switch (l.type) {
    case LightType::Triangle:
      side = double(kPi) * double(l.area) * lum;
      break;
    case LightType::Point:
    case LightType::Spot:
      side = 4 * double(kPi) * lum;
      break;
    case LightType::Goniometric:
      side = double(l.area) * lum;
      break;
    case LightType::Projection: {  // 4 pi area lum / frustum, as below
      const double a = 1 / double(length(l.p1)), c = 1 / double(length(l.p2));
      side = 4 * double(kPi) * double(l.area) * lum /
             (4 * std::asin(a * c / std::sqrt((1 + a * a) * (1 + c * c))));
      break;
    }
    case LightType::Directional:
      side = double(kPi) * lum;
      break;
  }
  const double sides = l.type == LightType::Triangle && l.two_sided ? 2 : 1;
  b.power = kMaxSamplingPower;
  b.side_power = float(double(kMaxSamplingPower) / sides);
  const double f = double(kMaxSamplingPower) / (side * sides);
  if (std::isfinite(b.max_radiance) && f > 0 && std::isfinite(f)) b.max_radiance = float(lum * f);
}
}  // namespace

LightBounds light_bounds(const Light& l) {
  LightBounds b = light_bounds_uncapped(l);
  if (!(b.power <= kMaxSamplingPower)) cap_power(l, b);
  return b;
}

LightBounds light_bounds_uncapped(const Light& l) {
  LightBounds b;
  switch (l.type) {
    case LightType::Triangle:
      b.box.expand(l.p0);
      b.box.expand(l.p1);
      b.box.expand(l.p2);
      b.axis = l.n;
      b.cos_theta_o = 1;
      b.cos_theta_e = 0;
      b.two_sided = l.two_sided;
      b.side_power = kPi * l.area * luminance(l.radiance);
      b.power = b.side_power * (l.two_sided ? 2.0f : 1.0f);
      b.max_radiance = luminance(l.radiance);
      break;
    case LightType::Point:
      b.box.expand(l.p0);
      b.cos_theta_o = -1;
      b.cos_theta_e = 0;
      b.power = b.side_power = 4 * kPi * luminance(l.radiance);
      b.max_radiance = kInf;
      break;
    case LightType::Spot: {
      // pbrt-v4's split of the cone: the axis spread by the full-intensity cone (theta_o), the
      // falloff as the emission spread (theta_e), so that importance is zero only outside the
      // falloff's end, where the spot emits nothing. Both widened against rounding. theta_e
      // stays within 90 degrees (the rest joins theta_o): beyond it importance's emitter cosine
      // would turn negative inside the cone. The power is 4 pi I, as a point light's, so that
      // importance compares intensities.
      b.box.expand(l.p0);
      b.axis = l.n;
      const float theta_end = safe_acos(l.p1.y);
      const float theta_e = std::min(std::max(0.0f, theta_end - safe_acos(l.p1.x)), 0.5f * kPi);
      b.cos_theta_o = widened_cos(theta_end - theta_e);
      b.cos_theta_e = theta_e < 0.5f * kPi ? widened_cos(theta_e) : 0.0f;
      b.power = b.side_power = 4 * kPi * luminance(l.radiance);
      b.max_radiance = kInf;
      break;
    }
    case LightType::Goniometric:
      // pbrt-v4 bounds it as an isotropic point light of its power.
      b.box.expand(l.p0);
      b.cos_theta_o = -1;
      b.cos_theta_e = 0;
      b.power = b.side_power = l.area * luminance(l.radiance);
      b.max_radiance = kInf;
      break;
    case LightType::Projection: {
      // Its frustum as the emission cone around its axis (the light's z, the third row of its
      // world-to-light map); the power 4 pi times its mean intensity within the frustum, as a
      // point light's. The image spans [-a, a] x [-b, b] at z = 1.
      b.box.expand(l.p0);
      const float a = 1 / length(l.p1), c = 1 / length(l.p2);
      b.axis = normalize(l.n);
      b.cos_theta_o = 1;
      b.cos_theta_e = widened_cos(std::atan(std::sqrt(a * a + c * c)));
      const float frustum = 4 * std::asin(a * c / std::sqrt((1 + a * a) * (1 + c * c)));
      b.power = b.side_power = 4 * kPi * l.area * luminance(l.radiance) / frustum;
      b.max_radiance = kInf;
      break;
    }
    case LightType::Directional:
      b.infinite = true;
      b.axis = l.p0;
      b.cos_theta_o = 1;
      b.power = b.side_power = kPi * luminance(l.radiance);
      break;
  }
  return b;
}

LightBounds distant_light_bounds(const Light& l, const DistantFrame& frame) {
  LightBounds b = light_bounds(l);
  if (l.type != LightType::Triangle) return b;
  b.infinite = b.distant = true;
  const Vec3 v[3] = {l.p0 - frame.center, l.p1 - frame.center, l.p2 - frame.center};
  const Vec3 c = (v[0] + v[1] + v[2]) / 3.0f;
  // From p within `reach` of the centre, the direction to a point y of the triangle is within
  // asin(reach / |y - center|) of the direction from the centre, and |y - center| is at least
  // the distance of the triangle's plane.
  const float plane = std::abs(dot(v[0], l.n));
  if (!(plane > frame.reach) || !(length_sq(c) > 0)) {
    b.axis = Vec3(0, 0, 1);
    b.cos_theta_o = -1;
    return b;
  }
  b.axis = normalize(c);
  float spread = 0;
  for (const Vec3& vk : v)
    spread = std::max(spread, std::atan2(length(cross(b.axis, vk)), dot(b.axis, vk)));
  const float parallax = std::asin(std::min(1.0f, frame.reach / plane));
  b.cos_theta_o = widened_cos(spread + parallax);
  return b;
}

LightBounds merge(const LightBounds& a, const LightBounds& b) {
  LightBounds m;
  m.infinite = a.infinite || b.infinite;
  m.distant = a.distant && b.distant;
  m.box = rll::merge(a.box, b.box);
  m.power = a.power + b.power;
  m.side_power = a.side_power + b.side_power;
  m.max_radiance = std::max(a.max_radiance, b.max_radiance);
  // A light without power never contributes: its direction does not widen the cone.
  if (b.power <= 0 && a.power > 0) {
    m.axis = a.axis;
    m.cos_theta_o = a.cos_theta_o;
  } else if (a.power <= 0) {
    m.axis = b.axis;
    m.cos_theta_o = b.cos_theta_o;
  } else {
    merge_cones(a.axis, a.cos_theta_o, b.axis, b.cos_theta_o, m.axis, m.cos_theta_o);
  }
  m.cos_theta_e = std::min(a.cos_theta_e, b.cos_theta_e);
  m.two_sided = a.two_sided || b.two_sided;
  return m;
}

ImportanceBounds importance_bounds(const LightBounds& b, const DistantFrame* frame) {
  ImportanceBounds f;
  f.center = b.box.empty() ? Vec3(0) : b.box.center();
  f.radius2 = b.box.empty() ? 0.0f : 0.25f * length_sq(b.box.diagonal());
  // Lights of radiance at most L give a surface at most pi L of irradiance, wherever it is: the
  // importance, side_power / d^2 at heart, stops growing at d^2 = side_power / (pi L), the area
  // of the lights (where they share one radiance). Clamping at the box's size instead (the
  // squared half-diagonal) flattens every sparse cluster a point stands near or inside: 2.7x
  // the error on many-lights-open. Point lights have no such bound: there, the box's size.
  f.min_dist2 = b.max_radiance > 0 && b.max_radiance < kInf ? b.side_power / (kPi * b.max_radiance)
                                                            : f.radius2;
  f.axis = b.axis;
  f.cos_o = b.cos_theta_o;
  f.cos_e = b.cos_theta_e;
  f.power = b.side_power;
  f.flags = (b.two_sided ? ImportanceBounds::kTwoSided : 0) |
            (b.infinite ? ImportanceBounds::kInfinite : 0);
  if (b.distant) {
    if (frame) {
      f.flags |= ImportanceBounds::kDistant;
      f.center = frame->center;
      f.radius2 = sqr(frame->reach);
      f.power = b.side_power / std::max(sqr(frame->distance), 1e-30f);
    } else {
      f.cos_o = -1;  // no frame to tell directions by: every direction
    }
  }
  f.sin_o = safe_sqrt(1 - f.cos_o * f.cos_o);
  return f;
}

float light_importance(const LightBounds& b, const Vec3& p, const Vec3& n,
                       const DistantFrame* frame) {
  return light_importance(importance_bounds(b, frame), p, n);
}

namespace {
std::string describe_light(const Scene& scene, size_t i) {
  const Light& l = scene.lights[i];
  const Vec3& p = l.p0;
  switch (l.type) {
    case LightType::Triangle: {
      const bool known = l.triangle < scene.mesh.material.size() &&
                         scene.mesh.material[l.triangle] < scene.materials.size();
      return known ? fmt::format("light {} (emissive triangle {} of material '{}')", i, l.triangle,
                                 scene.materials[scene.mesh.material[l.triangle]].name)
                   : fmt::format("light {} (emissive triangle {})", i, l.triangle);
    }
    case LightType::Point:
      return fmt::format("light {} (point light at ({}, {}, {}))", i, p.x, p.y, p.z);
    case LightType::Spot:
      return fmt::format("light {} (spot light at ({}, {}, {}))", i, p.x, p.y, p.z);
    case LightType::Goniometric:
      return fmt::format("light {} (goniometric light at ({}, {}, {}))", i, p.x, p.y, p.z);
    case LightType::Projection:
      return fmt::format("light {} (projection light at ({}, {}, {}))", i, p.x, p.y, p.z);
    case LightType::Directional:
      return fmt::format("light {} (distant light)", i);
  }
  return fmt::format("light {}", i);
}
}  // namespace

std::string capped_power_warning(const Scene& scene) {
  std::vector<size_t> capped;
  for (size_t i = 0; i < scene.lights.size(); ++i)
    if (!(light_bounds_uncapped(scene.lights[i]).power <= kMaxSamplingPower) ||
        !(light_power(scene.lights[i], scene.radius) <= kMaxSamplingPower))
      capped.push_back(i);
  if (capped.empty()) return {};
  std::string names;
  for (size_t k = 0; k < std::min<size_t>(capped.size(), 3); ++k)
    names += (k ? ", " : "") + describe_light(scene, capped[k]);
  if (capped.size() > 3) names += fmt::format(" and {} more", capped.size() - 3);
  return fmt::format(
      "{}: {} emit{} more power than a float holds or the samplers weigh ({:.3g} W): sampled as "
      "lights of that power, so that the other lights keep their share; their own light may "
      "overflow the image's floats (such samples are dropped); lower their radiance or scale if "
      "that was not meant",
      scene.source, names, capped.size() == 1 ? "s" : "", double(kMaxSamplingPower));
}

}  // namespace rll
