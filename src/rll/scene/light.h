// Lights: every emissive triangle is one, and so are point and directional (sun) lights.
#pragma once

#include <cstdint>

#include "rll/core/math.h"

namespace rll {

enum class LightType : uint8_t { Triangle, Point, Directional };

struct Light {
  LightType type = LightType::Triangle;
  // Triangle: the three vertices. Point: p0 is the position. Directional: p0 is the unit
  // direction *towards* the light (the sun's direction).
  Vec3 p0, p1, p2;
  Vec3 n;          // triangle: unit normal of the emitting side (front face)
  float area = 0;  // triangle area
  Rgb radiance;    // Triangle: emitted radiance. Point: intensity. Directional: irradiance.
  bool two_sided = false;
  uint32_t triangle = ~0u;  // the mesh triangle of a triangle light

  bool is_delta() const { return type != LightType::Triangle; }
  bool has_position() const { return type != LightType::Directional; }
  Vec3 centroid() const { return type == LightType::Triangle ? (p0 + p1 + p2) / 3.0f : p0; }
};

// A light sample as seen from a shading point: incident radiance along wi, distance to the
// sampled point (infinite for a directional light), and the solid-angle pdf of the point given
// the light (1 for delta lights).
struct LightLiSample {
  Rgb L;
  Vec3 wi;
  float dist = 0;
  float pdf = 0;
  Vec3 point;  // the sampled point on the light (triangle/point lights)
};

Light make_triangle_light(const Vec3& a, const Vec3& b, const Vec3& c, const Rgb& radiance,
                          bool two_sided, uint32_t triangle);
Light make_point_light(const Vec3& position, const Rgb& intensity);
Light make_directional_light(const Vec3& direction_to_light, const Rgb& irradiance);

// Solid angle of a triangle seen from p (Van Oosterom & Strackee).
float triangle_solid_angle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);
// Triangle lights are sampled uniformly in the solid angle they subtend (Arvo 1995) where that
// pays, by area elsewhere (small or far triangles); sample_li and pdf_li apply the same rule.
// Below 0.01 sr the pdf of area sampling varies little over the triangle, and the spherical
// warp's trigonometry is not worth its cost (a sky dome's triangles are ~3e-3 sr).
inline constexpr float kMinSphericalSolidAngle = 1e-2f, kMaxSphericalSolidAngle = 6.2f;

// Samples a point on the light as seen from p; pdf 0 when nothing is emitted towards p.
LightLiSample sample_li(const Light& light, const Vec3& p, Vec2 u);
// Solid-angle pdf that sample_li produced point y on a triangle light, seen from p along wi.
float pdf_li(const Light& light, const Vec3& p, const Vec3& y);
// Radiance a triangle light emits from its surface towards direction w (pointing away).
Rgb emitted_radiance(const Light& light, const Vec3& w);
// Total emitted power (luminance units): phi = pi * A * L (x2 if two-sided), 4 pi I for a
// point light, pi r^2 E for a directional light over a scene of radius r.
float light_power(const Light& light, float scene_radius);
// Updates a triangle light's cached normal and area after its vertices moved.
void refresh_triangle_light(Light& light);

}  // namespace rll
