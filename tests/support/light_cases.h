// Triangle lights seen from shading points the tests sweep (head-on, close, far, grazing, a
// sliver, a two-sided light from behind), with the analytic solid angle and vector irradiance of
// a triangle to check light sampling against.
#pragma once

#include <array>
#include <cmath>
#include <ostream>
#include <string>
#include <vector>

#include "rll/scene/light.h"

namespace rll::test {

struct LightCase {
  std::string name;
  Light light;
  Vec3 p;  // the shading point
  // Seen as a needle (a sliver's tip, a grazing view): thinner in direction space than any
  // quadrature grid can be trusted to find, so only the Monte Carlo moments test it.
  bool thin = false;
  friend void PrintTo(const LightCase& c, std::ostream* os) { *os << c.name; }
};

inline std::vector<LightCase> triangle_light_cases() {
  const Rgb le(1, 2, 3);
  auto tri = [&](Vec3 a, Vec3 b, Vec3 c, bool two_sided = false) {
    return make_triangle_light(a, b, c, le, two_sided, 0);
  };
  // A unit right triangle in the plane z = 1 facing down (-z) towards the origin.
  const Light down = tri({0, 0, 1}, {0, 1, 1}, {1, 0, 1});
  return {
      {"head_on", down, {0.3f, 0.3f, 0}},
      {"off_axis", down, {-1.5f, 2.0f, 0.2f}},
      {"close", down, {0.3f, 0.3f, 0.97f}},
      {"far", down, {20, -30, -100}},
      {"grazing", down, {3, 0.3f, 0.9f}, true},
      {"sliver", tri({0, 0, 1}, {0, 0.02f, 1}, {2, 0.05f, 1}), {0.5f, -0.5f, 0}, true},
      {"two_sided_back", tri({0, 0, 1}, {1, 0, 1}, {0, 1, 1}, true), {0.2f, 0.4f, 0}},
  };
}

// Solid angle of triangle (a, b, c) seen from p (Van Oosterom and Strackee 1983), in double
// precision: the reference the renderer's float triangle_solid_angle and its samplers are held to.
inline double reference_solid_angle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  auto d = [&](const Vec3& v) {
    Vec3 w = v - p;
    return std::array<double, 3>{w.x, w.y, w.z};
  };
  auto ra = d(a), rb = d(b), rc = d(c);
  auto dot3 = [](const std::array<double, 3>& u, const std::array<double, 3>& v) {
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
  };
  auto len = [&](const std::array<double, 3>& u) { return std::sqrt(dot3(u, u)); };
  std::array<double, 3> bxc{rb[1] * rc[2] - rb[2] * rc[1], rb[2] * rc[0] - rb[0] * rc[2],
                            rb[0] * rc[1] - rb[1] * rc[0]};
  double num = std::abs(dot3(ra, bxc));
  double den = len(ra) * len(rb) * len(rc) + dot3(ra, rb) * len(rc) + dot3(ra, rc) * len(rb) +
               dot3(rb, rc) * len(ra);
  double omega = 2 * std::atan2(num, den);
  return omega < 0 ? omega + 4 * M_PI : omega;
}

// The integral of the direction w over the triangle's solid angle seen from p (Lambert's
// polygon formula): half the sum over edges of the edge's angle times the unit normal of the
// plane through p and the edge. Its dot product with a unit normal is the form factor times pi.
inline std::array<double, 3> triangle_vector_irradiance(const Vec3& p, const Vec3& a, const Vec3& b,
                                                        const Vec3& c) {
  std::array<std::array<double, 3>, 3> u;
  const Vec3 v[3] = {a, b, c};
  for (int i = 0; i < 3; ++i) {
    double x = double(v[i].x) - p.x, y = double(v[i].y) - p.y, z = double(v[i].z) - p.z;
    double l = std::sqrt(x * x + y * y + z * z);
    u[i] = {x / l, y / l, z / l};
  }
  std::array<double, 3> phi{0, 0, 0};
  for (int i = 0; i < 3; ++i) {
    const auto &s = u[i], &t = u[(i + 1) % 3];
    std::array<double, 3> n{s[1] * t[2] - s[2] * t[1], s[2] * t[0] - s[0] * t[2],
                            s[0] * t[1] - s[1] * t[0]};
    double nl = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    double angle = std::atan2(nl, s[0] * t[0] + s[1] * t[1] + s[2] * t[2]);
    for (int k = 0; k < 3; ++k) phi[k] += 0.5 * angle * n[k] / nl;
  }
  // The winding decides the sign; the flux points towards the triangle.
  double towards = 0;
  for (int k = 0; k < 3; ++k) towards += phi[k] * (u[0][k] + u[1][k] + u[2][k]);
  if (towards < 0)
    for (double& x : phi) x = -x;
  return phi;
}

}  // namespace rll::test
