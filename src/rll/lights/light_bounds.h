// Conservative bounds of the light emitted by a set of lights (Conty & Kulla 2018): a box, a
// cone of emitter normals (theta_o) with an emission spread (theta_e), and total power. The
// importance of a set of lights at a shading point is an upper-bound-style estimate of their
// unoccluded contribution there.
#pragma once

#include "rll/core/math.h"
#include "rll/scene/light.h"

namespace rll {

struct LightBounds {
  Bounds3 box;               // finite lights only
  Vec3 axis{0, 0, 1};        // unit cone axis
  float cos_theta_o = 1;     // spread of the emitter normals around the axis
  float cos_theta_e = 0;     // spread of emission around each normal (cos(pi/2) for area lights)
  float power = 0;           // luminance power; for lights without position, pi * irradiance
  bool two_sided = false;
  bool infinite = false;     // lights without a position (directional)
};

// LightBounds reduced to what light_importance needs, with its derived terms precomputed (the
// tree's descents evaluate it twice per level).
struct ImportanceBounds {
  Vec3 center;
  float radius2 = 0;  // squared half-diagonal of the box
  Vec3 axis{0, 0, 1};
  float cos_o = 1;
  float sin_o = 0;
  float cos_e = 0;
  float power = 0;
  uint32_t flags = 0;  // kTwoSided | kInfinite
  static constexpr uint32_t kTwoSided = 1, kInfinite = 2;
};
ImportanceBounds importance_bounds(const LightBounds& b);
float light_importance(const ImportanceBounds& b, const Vec3& p, const Vec3& n);

LightBounds light_bounds(const Light& light);
// Bounds of the union of two sets of lights of the same kind (finite or infinite).
LightBounds merge(const LightBounds& a, const LightBounds& b);

// Importance of the lights in `b` at point p with surface normal n (n = 0: no surface). Zero
// only where none of them can contribute: behind the surface, outside every emission cone, or
// without power.
float light_importance(const LightBounds& b, const Vec3& p, const Vec3& n);

// Union of two direction cones given as (axis, cos of half-angle); exposed for tests.
void merge_cones(const Vec3& wa, float cos_a, const Vec3& wb, float cos_b, Vec3& w, float& cos_out);

}  // namespace rll
