// Conservative bounds of the light emitted by a set of lights (Conty & Kulla 2018): a box, a
// cone of emitter normals (theta_o) with an emission spread (theta_e), and total power. The
// importance of a set of lights at a shading point is an upper-bound-style estimate of their
// unoccluded contribution there.
#pragma once

#include <string>

#include "rll/core/math.h"
#include "rll/scene/light.h"

namespace rll {

struct Scene;

// The most power a light is sampled by: 2^100 W. pbrt-v4 defines nothing for a light whose power
// overflows a float (an area light of L 3e38): its samplers' sums turn to inf and every
// probability to NaN, which blacks out the image, the other lights' light included. rll caps the
// power the samplers weigh a light by (light_bounds, light_powers), never its radiance: the image
// stays unbiased, and sums over up to 2^27 lights of the cap stay finite floats. No physical scene
// comes near it (the sun is 4e26 W), so the cap changes nothing else.
inline constexpr float kMaxSamplingPower = 0x1p100f;

// The most importance light_importance gives: 2^120. A light of kMaxSamplingPower a hair away
// would otherwise give inf, and a descent's share inf / inf NaN; sums of 2^7 importances of the
// cap stay finite floats. Normal scenes stay far below it.
inline constexpr float kMaxImportance = 0x1p120f;

struct LightBounds {
  Bounds3 box;         // lights with a position only
  Vec3 axis{0, 0, 1};  // unit cone axis
  // Finite lights: spread of the emitter normals around the axis. Infinite ones: spread of the
  // directions towards the lights.
  float cos_theta_o = 1;
  float cos_theta_e = 0;  // spread of emission around each normal (cos(pi/2) for area lights)
  float power = 0;        // luminance power; for lights without position, pi * irradiance
  // The power a point can receive from them: a two-sided light shows one side to any point, so
  // it counts half of its power (importance compares it with one-sided lights').
  float side_power = 0;
  // Largest emitted radiance (luminance) of the lights; infinite for point lights.
  float max_radiance = 0;
  bool two_sided = false;
  // Lights seen as directions: directional lights (no position) and sky-dome triangles seen
  // from afar (distant_light_bounds). The box, where there is one, plays no part in importance.
  bool infinite = false;
  bool distant = false;  // sky-dome triangles: importance needs their DistantFrame
};

// Where a sky dome's triangles may be treated as distant lights: seen from any point within
// `reach` of `center`, each lies within a narrow cone of directions, at least `distance` away.
struct DistantFrame {
  Vec3 center;
  float reach = 0;
  float distance = 1;
};

// LightBounds reduced to what light_importance needs, with its derived terms precomputed (the
// tree's descents evaluate it twice per level).
struct ImportanceBounds {
  Vec3 center;          // of the box; of the DistantFrame for distant lights
  float radius2 = 0;    // squared half-diagonal of the box; squared reach for distant lights
  float min_dist2 = 0;  // squared distance below which the importance stops growing
  Vec3 axis{0, 0, 1};
  float cos_o = 1;
  float sin_o = 0;
  float cos_e = 0;
  float power = 0;     // for distant lights, divided by the squared distance
  uint32_t flags = 0;  // kTwoSided | kInfinite | kDistant | kGroup
  // kGroup: a light-tree node above the group roots, whose importance is its children's sum.
  static constexpr uint32_t kTwoSided = 1, kInfinite = 2, kGroup = 4, kDistant = 8;
};
// `frame` is needed where b.distant.
ImportanceBounds importance_bounds(const LightBounds& b, const DistantFrame* frame = nullptr);

namespace detail {
// cos(max(0, theta_a - theta_b)) and sin of the same, from sines and cosines.
RLL_HD inline float cos_sub_clamped(float sin_a, float cos_a, float sin_b, float cos_b) {
  return cos_a > cos_b ? 1.0f : cos_a * cos_b + sin_a * sin_b;
}
RLL_HD inline float sin_sub_clamped(float sin_a, float cos_a, float sin_b, float cos_b) {
  return cos_a > cos_b ? 0.0f : sin_a * cos_b - cos_a * sin_b;
}
}  // namespace detail

// Importance of the lights bounded by `b` at point p with surface normal n (n = 0: no surface);
// RLL_HD: the light tree's descents evaluate it on either device.
RLL_HD inline float light_importance(const ImportanceBounds& b, const Vec3& p, const Vec3& n) {
  using detail::cos_sub_clamped;
  using detail::sin_sub_clamped;
  if (!(b.power > 0)) return 0;
  const bool has_normal = n.x != 0 || n.y != 0 || n.z != 0;
  if (b.flags & ImportanceBounds::kInfinite) {
    // Distant lights' cones hold only for points within the frame's reach.
    if (!has_normal ||
        ((b.flags & ImportanceBounds::kDistant) && length_sq(p - b.center) > b.radius2))
      return clamp(b.power, 0.0f, kMaxImportance);
    // Best cosine between the normal and any direction of the cone.
    float cos_i = dot(b.axis, n), sin_i = safe_sqrt(1 - cos_i * cos_i);
    float c = cos_sub_clamped(sin_i, cos_i, b.sin_o, b.cos_o);
    return c > 0 ? clamp(b.power * c, 0.0f, kMaxImportance) : 0;
  }
  Vec3 d = p - b.center;  // from the lights to the point
  float dist2 = length_sq(d);
  // Near the lights, importance stops growing (see importance_bounds).
  float d2 = std::max(dist2, b.min_dist2);
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
    // Receiver side: the best cosine between n and a direction towards the lights' sphere. One-
    // sided (n faces the side the path arrived from, and surfaces are opaque): pbrt-v4's
    // two-sided |cos| gave 6% more error on cornell-boxes-room.
    float cos_i = -dot(wi, n), sin_i = safe_sqrt(1 - cos_i * cos_i);
    float cos_pi = cos_sub_clamped(sin_i, cos_i, sin_b, cos_b);
    if (cos_pi <= 0) return 0;
    importance *= cos_pi;
  }
  return clamp(importance, 0.0f, kMaxImportance);
}

// Power capped at kMaxSamplingPower.
LightBounds light_bounds(const Light& light);
// The same without the cap (the power may be inf): to tell which lights the cap acts on.
LightBounds light_bounds_uncapped(const Light& light);
// A sky-dome triangle as a distant light: the cone of directions towards it from any point
// within frame.reach of frame.center (its own directions from the centre, widened by the
// parallax); box and power as light_bounds gives them.
LightBounds distant_light_bounds(const Light& light, const DistantFrame& frame);
// Bounds of the union of two sets of lights. Only sets of the same kind (finite, or infinite
// and distant) give useful bounds; a union of both kinds is marked infinite.
LightBounds merge(const LightBounds& a, const LightBounds& b);

// Importance of the lights in `b` at point p with surface normal n (n = 0: no surface). Zero
// only where none of them can contribute: behind the surface, outside every emission cone, or
// without power.
float light_importance(const LightBounds& b, const Vec3& p, const Vec3& n,
                       const DistantFrame* frame = nullptr);

// A warning naming the lights whose power light_bounds caps at kMaxSamplingPower (empty: none).
std::string capped_power_warning(const Scene& scene);

// Union of two direction cones given as (axis, cos of half-angle); exposed for tests.
void merge_cones(const Vec3& wa, float cos_a, const Vec3& wb, float cos_b, Vec3& w, float& cos_out);

}  // namespace rll
