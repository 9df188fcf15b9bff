// Small vector math for the renderer: float 3-vectors, boxes, orthonormal frames.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "rll/core/device.h"

namespace rll {

inline constexpr float kPi = 3.14159265358979323846f;
inline constexpr float kInvPi = 0.31830988618379067154f;
inline constexpr float kInf = std::numeric_limits<float>::infinity();

struct Vec2 {
  float x = 0, y = 0;
};

struct Vec3 {
  float x = 0, y = 0, z = 0;
  constexpr Vec3() = default;
  RLL_HD constexpr Vec3(float a, float b, float c) : x(a), y(b), z(c) {}
  RLL_HD constexpr explicit Vec3(float s) : x(s), y(s), z(s) {}
  RLL_HD float operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  RLL_HD float& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
  RLL_HD Vec3 operator-() const { return {-x, -y, -z}; }
  RLL_HD Vec3& operator+=(const Vec3& o) {
    x += o.x;
    y += o.y;
    z += o.z;
    return *this;
  }
  RLL_HD Vec3& operator-=(const Vec3& o) {
    x -= o.x;
    y -= o.y;
    z -= o.z;
    return *this;
  }
  RLL_HD Vec3& operator*=(const Vec3& o) {
    x *= o.x;
    y *= o.y;
    z *= o.z;
    return *this;
  }
  RLL_HD Vec3& operator*=(float s) {
    x *= s;
    y *= s;
    z *= s;
    return *this;
  }
  RLL_HD Vec3& operator/=(float s) { return *this *= 1.0f / s; }
};

// RGB radiance and reflectance share the vector type; the alias documents intent.
using Rgb = Vec3;

RLL_HD inline Vec3 operator+(Vec3 a, const Vec3& b) {
  return a += b;
}
RLL_HD inline Vec3 operator-(Vec3 a, const Vec3& b) {
  return a -= b;
}
RLL_HD inline Vec3 operator*(Vec3 a, const Vec3& b) {
  return a *= b;
}
RLL_HD inline Vec3 operator*(Vec3 a, float s) {
  return a *= s;
}
RLL_HD inline Vec3 operator*(float s, Vec3 a) {
  return a *= s;
}
RLL_HD inline Vec3 operator/(Vec3 a, float s) {
  return a *= 1.0f / s;
}
RLL_HD inline Vec3 operator/(const Vec3& a, const Vec3& b) {
  return {a.x / b.x, a.y / b.y, a.z / b.z};
}
RLL_HD inline bool operator==(const Vec3& a, const Vec3& b) {
  return a.x == b.x && a.y == b.y && a.z == b.z;
}

RLL_HD inline float dot(const Vec3& a, const Vec3& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
RLL_HD inline float absdot(const Vec3& a, const Vec3& b) {
  return std::abs(dot(a, b));
}
RLL_HD inline Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
RLL_HD inline float length_sq(const Vec3& a) {
  return dot(a, a);
}
RLL_HD inline float length(const Vec3& a) {
  return std::sqrt(dot(a, a));
}
RLL_HD inline Vec3 normalize(const Vec3& a) {
  return a / length(a);
}
RLL_HD inline Vec3 min(const Vec3& a, const Vec3& b) {
  return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)};
}
RLL_HD inline Vec3 max(const Vec3& a, const Vec3& b) {
  return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)};
}
RLL_HD inline Vec3 abs(const Vec3& a) {
  return {std::abs(a.x), std::abs(a.y), std::abs(a.z)};
}
RLL_HD inline float max_component(const Vec3& a) {
  return std::max(a.x, std::max(a.y, a.z));
}
RLL_HD inline float min_component(const Vec3& a) {
  return std::min(a.x, std::min(a.y, a.z));
}
RLL_HD inline Vec3 lerp(float t, const Vec3& a, const Vec3& b) {
  return a * (1 - t) + b * t;
}
RLL_HD inline bool is_finite(const Vec3& a) {
  return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z);
}
RLL_HD inline bool is_black(const Rgb& c) {
  return c.x == 0 && c.y == 0 && c.z == 0;
}
// Rec. 709 luminance of linear RGB.
RLL_HD inline float luminance(const Rgb& c) {
  return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z;
}
RLL_HD inline Vec3 face_forward(const Vec3& n, const Vec3& v) {
  return dot(n, v) < 0 ? -n : n;
}
RLL_HD inline Vec3 reflect(const Vec3& wo, const Vec3& n) {
  return -wo + n * (2 * dot(wo, n));
}

template <typename T>
RLL_HD inline T clamp(T v, T lo, T hi) {
  return v < lo ? lo : (v > hi ? hi : v);
}
RLL_HD inline float sqr(float x) {
  return x * x;
}
RLL_HD inline float safe_sqrt(float x) {
  return std::sqrt(std::max(0.0f, x));
}
RLL_HD inline float safe_acos(float x) {
  return std::acos(clamp(x, -1.0f, 1.0f));
}
RLL_HD inline float radians(float deg) {
  return deg * (kPi / 180.0f);
}

// Axis-aligned box; empty when lo > hi.
struct Bounds3 {
  Vec3 lo{kInf, kInf, kInf};
  Vec3 hi{-kInf, -kInf, -kInf};
  RLL_HD bool empty() const { return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z; }
  RLL_HD void expand(const Vec3& p) {
    lo = min(lo, p);
    hi = max(hi, p);
  }
  RLL_HD void expand(const Bounds3& b) {
    lo = min(lo, b.lo);
    hi = max(hi, b.hi);
  }
  RLL_HD Vec3 center() const { return (lo + hi) * 0.5f; }
  RLL_HD Vec3 diagonal() const { return hi - lo; }
  RLL_HD bool contains(const Vec3& p) const {
    return p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y && p.z >= lo.z && p.z <= hi.z;
  }
};
RLL_HD inline Bounds3 merge(Bounds3 a, const Bounds3& b) {
  a.expand(b);
  return a;
}

// Orthonormal frame around a unit normal (Duff et al. 2017, branchless).
struct Frame {
  Vec3 s, t, n;
  RLL_HD Frame() : s(1, 0, 0), t(0, 1, 0), n(0, 0, 1) {}
  RLL_HD explicit Frame(const Vec3& normal) : n(normal) {
    float sign = std::copysign(1.0f, n.z);
    float a = -1.0f / (sign + n.z);
    float b = n.x * n.y * a;
    s = Vec3(1 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    t = Vec3(b, sign + n.y * n.y * a, -n.y);
  }
  // Frame with a given normal whose first tangent follows `tangent` projected onto the plane.
  RLL_HD Frame(const Vec3& normal, const Vec3& tangent) : n(normal) {
    Vec3 tt = tangent - n * dot(n, tangent);
    float l = length(tt);
    if (!(l > 1e-6f)) {
      *this = Frame(normal);
      return;
    }
    s = tt / l;
    t = cross(n, s);
  }
  RLL_HD Vec3 to_local(const Vec3& v) const { return {dot(v, s), dot(v, t), dot(v, n)}; }
  RLL_HD Vec3 to_world(const Vec3& v) const { return s * v.x + t * v.y + n * v.z; }
};

struct Ray {
  Vec3 o, d;
  float tmin = 0, tmax = kInf;
};

// Offset for spawning rays off a surface, scaled with the magnitude of the position so that
// large scenes do not self-intersect.
RLL_HD inline float ray_epsilon(const Vec3& p) {
  return 1e-4f * std::max(1.0f, max_component(abs(p)));
}

}  // namespace rll
