#include "rll/lights/light_bounds.h"

namespace rll {

namespace {
// cos(max(0, theta_a - theta_b)) and sin of the same, from sines and cosines.
inline float cos_sub_clamped(float sin_a, float cos_a, float sin_b, float cos_b) {
  return cos_a > cos_b ? 1.0f : cos_a * cos_b + sin_a * sin_b;
}
inline float sin_sub_clamped(float sin_a, float cos_a, float sin_b, float cos_b) {
  return cos_a > cos_b ? 0.0f : sin_a * cos_b - cos_a * sin_b;
}
// Rotates v about the unit axis k by angle theta (Rodrigues).
Vec3 rotate(const Vec3& v, const Vec3& k, float theta) {
  float c = std::cos(theta), s = std::sin(theta);
  return v * c + cross(k, v) * s + k * (dot(k, v) * (1 - c));
}
}  // namespace

void merge_cones(const Vec3& wa, float cos_a, const Vec3& wb, float cos_b, Vec3& w, float& cos_out) {
  float theta_a = safe_acos(cos_a), theta_b = safe_acos(cos_b);
  float theta_d = safe_acos(dot(wa, wb));
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
  Vec3 wr = cross(wa, wb);
  if (theta_o >= kPi || length_sq(wr) < 1e-12f) {
    w = wa;
    cos_out = -1;  // the whole sphere
    return;
  }
  w = normalize(rotate(wa, normalize(wr), theta_o - theta_a));
  // Widen by a hair so that float rounding never excludes a member direction.
  cos_out = std::cos(std::min(kPi, theta_o * (1 + 1e-5f) + 1e-6f));
}

LightBounds light_bounds(const Light& l) {
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
      b.power = kPi * l.area * luminance(l.radiance) * (l.two_sided ? 2.0f : 1.0f);
      break;
    case LightType::Point:
      b.box.expand(l.p0);
      b.cos_theta_o = -1;
      b.cos_theta_e = 0;
      b.power = 4 * kPi * luminance(l.radiance);
      break;
    case LightType::Directional:
      b.infinite = true;
      b.axis = l.p0;
      b.cos_theta_o = 1;
      b.power = kPi * luminance(l.radiance);
      break;
  }
  return b;
}

LightBounds merge(const LightBounds& a, const LightBounds& b) {
  LightBounds m;
  m.infinite = a.infinite;
  m.box = rll::merge(a.box, b.box);
  m.power = a.power + b.power;
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

ImportanceBounds importance_bounds(const LightBounds& b) {
  ImportanceBounds f;
  f.center = b.box.empty() ? Vec3(0) : b.box.center();
  f.radius2 = b.box.empty() ? 0.0f : 0.25f * length_sq(b.box.diagonal());
  f.axis = b.axis;
  f.cos_o = b.cos_theta_o;
  f.sin_o = safe_sqrt(1 - b.cos_theta_o * b.cos_theta_o);
  f.cos_e = b.cos_theta_e;
  f.power = b.power;
  f.flags = (b.two_sided ? ImportanceBounds::kTwoSided : 0) | (b.infinite ? ImportanceBounds::kInfinite : 0);
  return f;
}

float light_importance(const LightBounds& b, const Vec3& p, const Vec3& n) {
  return light_importance(importance_bounds(b), p, n);
}

float light_importance(const ImportanceBounds& b, const Vec3& p, const Vec3& n) {
  if (!(b.power > 0)) return 0;
  const bool has_normal = n.x != 0 || n.y != 0 || n.z != 0;
  if (b.flags & ImportanceBounds::kInfinite) {
    if (!has_normal) return b.power;
    // Best cosine between the normal and any direction of the cone.
    float cos_i = dot(b.axis, n), sin_i = safe_sqrt(1 - cos_i * cos_i);
    float c = cos_sub_clamped(sin_i, cos_i, b.sin_o, b.cos_o);
    return c > 0 ? b.power * c : 0;
  }
  Vec3 d = p - b.center;  // from the lights to the point
  float dist2 = length_sq(d);
  // Clamp the distance for points near or inside the box: the box may hold lights at any
  // distance from p, so importance is bounded by the box's own size there.
  float d2 = std::max(dist2, b.radius2);
  float cos_b = -1, sin_b = 0;  // half-angle of the box's bounding sphere seen from p
  if (dist2 > b.radius2) {
    float sin2 = b.radius2 / dist2;
    cos_b = std::sqrt(1 - sin2);
    sin_b = std::sqrt(sin2);
  }
  Vec3 wi = dist2 > 0 ? d * (1.0f / std::sqrt(dist2)) : Vec3(0, 0, 1);
  float cos_w = dot(b.axis, wi);
  if (b.flags & ImportanceBounds::kTwoSided) cos_w = std::abs(cos_w);
  float sin_w = safe_sqrt(1 - cos_w * cos_w);
  float cos_x = cos_sub_clamped(sin_w, cos_w, b.sin_o, b.cos_o);
  float sin_x = sin_sub_clamped(sin_w, cos_w, b.sin_o, b.cos_o);
  float cos_p = cos_sub_clamped(sin_x, cos_x, sin_b, cos_b);
  if (cos_p <= b.cos_e) return 0;
  float importance = b.power * cos_p / std::max(d2, 1e-20f);
  if (has_normal) {
    // Receiver side: the best cosine between n and a direction towards the lights' sphere.
    float cos_i = -dot(wi, n), sin_i = safe_sqrt(1 - cos_i * cos_i);
    float cos_pi = cos_sub_clamped(sin_i, cos_i, sin_b, cos_b);
    if (cos_pi <= 0) return 0;
    importance *= cos_pi;
  }
  return std::max(importance, 0.0f);
}

}  // namespace rll
