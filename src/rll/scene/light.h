// Lights: every emissive triangle is one, and so are point, spot and directional (sun) lights.
// Light is trivially copyable and its sampling functions are RLL_HD: kernels read an array of
// lights (SceneView::lights).
#pragma once

#include <cstdint>
#include <string>

#include "rll/core/image.h"
#include "rll/core/math.h"
#include "rll/core/sampling.h"

namespace rll {

enum class LightType : uint8_t { Triangle, Point, Directional, Spot, Goniometric, Projection };

struct Light {
  LightType type = LightType::Triangle;
  // Triangle: the three vertices. Point and spot: p0 is the position. Directional: p0 is the
  // unit direction *towards* the light (the sun's direction). Spot: p1.x and p1.y are the
  // cosines of the cone's half-angles where the falloff starts and where it ends (pbrt-v4's
  // cosFalloffStart >= cosFalloffEnd). Goniometric and projection (pbrt-v4's image lights): p0
  // is the position; p1, p2 and n are the rows of the map from world directions to the light's
  // frame, where a goniometric light looks its equal-area image up and a projection light
  // projects its image onto the plane z = 1 (rows scaled so that the image spans [-1, 1]^2).
  Vec3 p0, p1, p2;
  Vec3 n;          // triangle: unit normal of the emitting side (front face); spot: unit axis
  float area = 0;  // triangle area; image lights: power per unit luminance of `radiance`
  // Triangle: emitted radiance. Point and spot: intensity (a spot's on its axis). Directional:
  // irradiance.
  Rgb radiance;
  bool two_sided = false;
  // A triangle light whose material has an emission texture: `radiance` is the exact mean of
  // its emission over the triangle (its power and bounds follow from it), and the radiance at a
  // point is the material's emission times the texture there (scene_view.h).
  bool textured = false;
  uint32_t triangle = ~0u;  // the mesh triangle of a triangle light; an image light's texture

  RLL_HD bool is_delta() const { return type != LightType::Triangle; }
  RLL_HD bool has_image() const {
    return type == LightType::Goniometric || type == LightType::Projection;
  }
  RLL_HD bool has_position() const { return type != LightType::Directional; }
  RLL_HD Vec3 centroid() const { return type == LightType::Triangle ? (p0 + p1 + p2) / 3.0f : p0; }
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
// A spot light at `position` shining along `axis` with intensity `intensity` on the axis, full
// within the cone of half-angle acos(cos_falloff_start), falling off smoothly (pbrt-v4's
// smoothstep in the cosine) to nothing at acos(cos_falloff_end).
Light make_spot_light(const Vec3& position, const Vec3& axis, const Rgb& intensity,
                      float cos_falloff_start, float cos_falloff_end);

// pbrt-v4's smoothstep: 0 at x <= a, 1 at x >= b, 3t^2 - 2t^3 between (t = (x - a) / (b - a));
// a step at a where a == b.
RLL_HD inline float smooth_step(float x, float a, float b) {
  if (a == b) return x < a ? 0.0f : 1.0f;
  const float t = clamp((x - a) / (b - a), 0.0f, 1.0f);
  return t * t * (3 - 2 * t);
}

// pbrt-v4's equal-area octahedral map (Clarberg) from unit directions to [0, 1]^2, with +z at
// the square's centre and -z at its corners.
RLL_HD inline Vec2 equal_area_sphere_to_square(const Vec3& d) {
  // The radius in the square grows as sqrt(1 - |z|) (equal area), the angle within each octant
  // linearly; the lower hemisphere folds out to the corners.
  const float ax = std::abs(d.x), ay = std::abs(d.y), az = std::abs(d.z);
  const float r = safe_sqrt(1 - az);
  const float big = std::max(ax, ay), small = std::min(ax, ay);
  float phi = big == 0 ? 0 : std::atan(small / big) * (2 / kPi);  // in [0, 1]
  if (ay > ax) phi = 1 - phi;
  float sv = phi * r, su = r - sv;
  if (d.z < 0) {
    const float t = su;
    su = 1 - sv;
    sv = 1 - t;
  }
  su = std::copysign(su, d.x);
  sv = std::copysign(sv, d.y);
  return Vec2{0.5f * (su + 1), 0.5f * (sv + 1)};
}

// An image light's intensity along unit direction w (away from the light): `radiance` times the
// nearest texel of its image (pbrt-v4's LookupNearest), v down the image. A goniometric light
// looks the direction up in its equal-area image; a projection light projects it through the
// image's rectangle and emits nothing outside it or behind pbrt-v4's near plane (z < 1e-3).
RLL_HD inline Rgb image_light_intensity(const Light& l, const TexelView& image, const Vec3& w) {
  const Vec3 wl(dot(l.p1, w), dot(l.p2, w), dot(l.n, w));
  Vec2 uv;
  if (l.type == LightType::Goniometric) {
    const float len2 = length_sq(wl);
    if (!(len2 > 0)) return Rgb(0);
    uv = equal_area_sphere_to_square(wl / std::sqrt(len2));
  } else {
    if (!(wl.z >= 1e-3f)) return Rgb(0);
    const float s = wl.x / wl.z, t = wl.y / wl.z;
    if (!(s >= -1 && s < 1 && t >= -1 && t < 1)) return Rgb(0);
    uv = Vec2{0.5f * (s + 1), 0.5f * (t + 1)};
  }
  if (image.width <= 0 || image.height <= 0) return Rgb(0);
  const int x = std::min(std::max(int(uv.x * float(image.width)), 0), image.width - 1);
  const int y = std::min(std::max(int(uv.y * float(image.height)), 0), image.height - 1);
  return l.radiance * image.at(x, y);
}

// The fraction of a spot light's axial intensity it emits along unit direction w (pointing away
// from the light).
RLL_HD inline float spot_falloff(const Light& l, const Vec3& w) {
  return smooth_step(dot(l.n, w), l.p1.y, l.p1.x);
}

// Radiance a triangle light emits from its surface towards direction w (pointing away); for a
// textured light, its mean radiance (the emission at a point: emitted_radiance of interaction.h).
RLL_HD inline Rgb emitted_radiance(const Light& l, const Vec3& w) {
  if (l.type != LightType::Triangle) return Rgb(0);
  float c = dot(l.n, w);
  return (c > 0 || (l.two_sided && c < 0)) ? l.radiance : Rgb(0);
}

// Solid angle of a triangle seen from p (Van Oosterom & Strackee).
RLL_HD inline float triangle_solid_angle(const Vec3& p, const Vec3& a, const Vec3& b,
                                         const Vec3& c) {
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

// Triangle lights are sampled uniformly in the solid angle they subtend (Arvo 1995) where that
// pays, by area elsewhere (small or far triangles); sample_li and pdf_li apply the same rule.
// Below 0.01 sr the pdf of area sampling varies little over the triangle, and the spherical
// warp's trigonometry is not worth its cost (a sky dome's triangles are ~3e-3 sr).
inline constexpr float kMinSphericalSolidAngle = 1e-2f, kMaxSphericalSolidAngle = 6.2f;

namespace light_detail {

// Double-precision 3-vectors for the spherical warp below, whose angle differences lose most
// of a float's precision on thin triangles.
struct D3 {
  double x, y, z;
};
RLL_HD inline D3 d3(const Vec3& v) {
  return {v.x, v.y, v.z};
}
RLL_HD inline D3 operator+(D3 a, D3 b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
RLL_HD inline D3 operator-(D3 a, D3 b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
RLL_HD inline D3 operator*(D3 a, double s) {
  return {a.x * s, a.y * s, a.z * s};
}
RLL_HD inline double ddot(D3 a, D3 b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
RLL_HD inline D3 dcross(D3 a, D3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
RLL_HD inline double dlen(D3 a) {
  return std::sqrt(ddot(a, a));
}
RLL_HD inline D3 dnorm(D3 a) {
  return a * (1 / dlen(a));
}
// The angle between x and y, given their lengths.
RLL_HD inline double angle(D3 x, double lx, D3 y, double ly) {
  return std::acos(clamp(ddot(x, y) / (lx * ly), -1.0, 1.0));
}

// Uniform direction in the spherical triangle spanned by directions a, b, c (Arvo 1995):
// choose the sub-triangle area u.x * omega, which fixes a point C' on arc AC, then a point on
// arc BC' with the right density.
RLL_HD inline Vec3 sample_spherical_triangle(const Vec3& a, const Vec3& b, const Vec3& c, Vec2 u) {
  D3 A = dnorm(d3(a)), B = dnorm(d3(b)), C = dnorm(d3(c));
  // Angles at the vertices, from the normals of the planes through the origin and two vertices.
  D3 n_ab = dcross(A, B), n_ac = dcross(A, C), n_bc = dcross(B, C);
  double l_ab = dlen(n_ab), l_ac = dlen(n_ac), l_bc = dlen(n_bc);
  if (!(l_ab > 0 && l_ac > 0 && l_bc > 0)) return a;
  double alpha = angle(n_ab, l_ab, n_ac, l_ac);
  double beta = angle(n_ab * -1.0, l_ab, n_bc, l_bc);
  double gamma = angle(n_ac, l_ac, n_bc, l_bc);
  double omega = alpha + beta + gamma - M_PI;
  double cos_alpha = std::cos(alpha), sin_alpha = std::sin(alpha), cos_c = ddot(A, B);
  double area = u.x * omega;
  double s = std::sin(area - alpha), t = std::cos(area - alpha);
  double uu = t - cos_alpha, vv = s + sin_alpha * cos_c;
  double q =
      clamp(((vv * t - uu * s) * cos_alpha - vv) / ((vv * s + uu * t) * sin_alpha), -1.0, 1.0);
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

RLL_HD inline bool use_spherical(float omega) {
  return omega > kMinSphericalSolidAngle && omega < kMaxSphericalSolidAngle;
}

// The solid angle a triangle light subtends at p where spherical sampling may use it, else 0.
// A triangle inside a sphere of radius r around its centroid, seen from distance d > r,
// subtends at most area / (d - r)^2: when that bound is already below the spherical threshold
// (a sky dome's triangles, far lamps) the exact formula, with its three normalisations and an
// arctangent, is skipped. The decision is the same as with the exact angle.
RLL_HD inline float spherical_solid_angle(const Light& l, const Vec3& p) {
  const Vec3 c = l.centroid();
  const float r2 =
      std::max(std::max(length_sq(l.p0 - c), length_sq(l.p1 - c)), length_sq(l.p2 - c));
  const float d2 = length_sq(p - c);
  if (d2 > r2) {
    const float gap = std::sqrt(d2) - std::sqrt(r2);
    if (l.area < kMinSphericalSolidAngle * 0.5f * gap * gap) return 0;
  }
  return triangle_solid_angle(p, l.p0, l.p1, l.p2);
}

}  // namespace light_detail

// Samples a point on the light as seen from p; pdf 0 when nothing is emitted towards p. An image
// light needs its image (SceneView's sample_li passes it); without one it emits nothing.
RLL_HD inline LightLiSample sample_li(const Light& l, const Vec3& p, Vec2 u,
                                      const TexelView* image = nullptr) {
  using namespace light_detail;
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
    case LightType::Point:
    case LightType::Spot:
    case LightType::Goniometric:
    case LightType::Projection: {
      Vec3 d = l.p0 - p;
      float d2 = length_sq(d);
      if (!(d2 > 0)) return s;
      s.dist = std::sqrt(d2);
      s.wi = d / s.dist;
      Rgb I = l.radiance;
      if (l.type == LightType::Spot) I *= spot_falloff(l, -s.wi);
      if (l.has_image()) I = image ? image_light_intensity(l, *image, -s.wi) : Rgb(0);
      if (is_black(I)) return LightLiSample{};
      s.L = I / d2;
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

// Solid-angle pdf that sample_li produced point y on a triangle light, seen from p along wi.
RLL_HD inline float pdf_li(const Light& l, const Vec3& p, const Vec3& y) {
  using namespace light_detail;
  if (l.type != LightType::Triangle || l.area <= 0) return 0;
  Vec3 d = y - p;
  float d2 = length_sq(d);
  if (!(d2 > 0)) return 0;
  float omega = spherical_solid_angle(l, p);
  if (use_spherical(omega)) return 1 / omega;
  float cos_l = std::abs(dot(l.n, d)) / std::sqrt(d2);
  return cos_l > 0 ? d2 / (cos_l * l.area) : 0;
}

// Total emitted power (luminance units): phi = pi * A * L (x2 if two-sided), 4 pi I for a
// point light, 2 pi I ((1 - cos_start) + (cos_start - cos_end) / 2) for a spot light (pbrt-v4's
// integral of its smoothstep falloff), pi r^2 E for a directional light over a scene of radius r.
float light_power(const Light& light, float scene_radius);
// An image light of pbrt-v4 (goniometric or projection) at `position`; `to_light` holds the rows
// of the map from world directions to its frame (see Light), `image` its texture index and
// `power_factor` its power per unit luminance of `scale`.
Light make_image_light(LightType type, const Vec3& position, const Vec3 to_light[3],
                       const Rgb& scale, uint32_t image, float power_factor);

// An image light's power per unit luminance of its `radiance` (its Light::area), from its image
// as pbrt-v4's Phi computes it: goniometric 4 pi x the image's mean (first channel); projection
// A x the mean of luminance x cos^3 over the pixels, A the image's area on the plane z = 1.
float image_light_power_factor(const Light& l, const Image& image);

// A spot light's cone angle and falloff width in degrees, as pbrt-v4 and rll's JSON state them
// (coneangle = acos(cos_falloff_end), conedeltaangle = coneangle - acos(cos_falloff_start)).
struct SpotAngles {
  double cone = 0, delta = 0;
};
SpotAngles spot_angles(const Light& spot);
// A spot light's power per unit of axial intensity: the solid angle its falloff integrates to.
float spot_solid_angle(float cos_falloff_start, float cos_falloff_end);
// Updates a triangle light's cached normal and area after its vertices moved.
void refresh_triangle_light(Light& light);

// The kind of a light as messages and files name it: "triangle", "point", "directional",
// "spot", "goniometric", "projection".
const char* light_type_name(LightType type);
// What no light may have, "" when it has none: a non-finite position, direction or frame, or a
// non-finite or negative emission, named as the light's kind calls it and with its values
// ("its intensity (inf, inf, inf) is not finite"). Readers ask it of each light they make, to
// name the file and line; Scene::finalize asks it of every light.
std::string light_parameter_problem(const Light& light);

}  // namespace rll
