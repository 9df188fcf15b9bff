// pbrt-v4's light sources in rll (issue 32): the spot's smoothstep cone, point, spot, distant and
// area lights normalized to a stated "power" or "illuminance", their light-tree bounds, and how
// the readers and writers (pbrt-v4, JSON, glTF) keep each kind. Spot lights' pbrt-v4 definition
// is restated here in double, independently of rll's code.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <cmath>

#include "rll/core/rng.h"
#include "rll/io/load.h"
#include "rll/io/save.h"
#include "rll/lighttree/light_bounds.h"
#include "rll/scene/builder.h"
#include "support/test_support.h"

using namespace rll;
using rll::test::error_of;
using rll::test::expect_mentions;
using rll::test::TempDir;

namespace {

constexpr double kPiD = 3.14159265358979323846;

Scene read_pbrt(const TempDir& dir, const std::string& world, const std::string& name = "s.pbrt") {
  Scene s;
  load_pbrt(dir.write(name, "WorldBegin\n" + world), s);
  return s;
}

std::string pbrt_error(const TempDir& dir, const std::string& world) {
  return error_of([&] { read_pbrt(dir, world, "bad.pbrt"); });
}

// pbrt-v4's spot intensity at cos theta = c from its axis, in double.
double pbrt_spot_at(double I, double c, double cone_deg, double delta_deg) {
  const double cos_end = std::cos(cone_deg * kPiD / 180),
               cos_start = std::cos((cone_deg - delta_deg) * kPiD / 180);
  if (cos_end == cos_start) return c < cos_end ? 0 : I;
  const double t = std::clamp((c - cos_end) / (cos_start - cos_end), 0.0, 1.0);
  return I * t * t * (3 - 2 * t);
}

// The same along direction w (unit, away from the light).
double pbrt_spot(double I, const Vec3& axis, const Vec3& w, double cone_deg, double delta_deg) {
  return pbrt_spot_at(I, double(axis.x) * w.x + double(axis.y) * w.y + double(axis.z) * w.z,
                      cone_deg, delta_deg);
}

TEST(SpotLight, SampleLiIsPbrtV4sSmoothstepConeOverDistanceSquared) {
  const Vec3 pos(0.5f, 3, -1), axis = normalize(Vec3(0.2f, -1, 0.1f));
  const float cone = 25, delta = 7;
  const Light l = make_spot_light(pos, axis, Rgb(2, 1, 0.5f), std::cos(radians(cone - delta)),
                                  std::cos(radians(cone)));
  Pcg32 rng(5);
  int inside = 0, falloff = 0, outside = 0;
  for (int i = 0; i < 20000; ++i) {
    const Vec3 p(8 * rng.next_float() - 4, 3 * rng.next_float() - 1, 8 * rng.next_float() - 4);
    const LightLiSample s = sample_li(l, p, {rng.next_float(), rng.next_float()});
    const Vec3 d = p - pos;
    const double d2 = double(length_sq(d));
    const double expected = pbrt_spot(1, axis, normalize(d), cone, delta) / d2;
    const double cos_w = dot(axis, normalize(d));
    if (expected == 0) {
      ++outside;
      EXPECT_EQ(s.pdf, 0) << "a sample outside the cone at cos " << cos_w;
      continue;
    }
    (cos_w >= std::cos(radians(cone - delta)) ? inside : falloff) += 1;
    ASSERT_EQ(s.pdf, 1);
    // Within what float rounding of the cosine (a few 1e-7) allows in the falloff's slope.
    const double lo = pbrt_spot_at(1, cos_w - 1e-6, cone, delta) / d2,
                 hi = pbrt_spot_at(1, cos_w + 1e-6, cone, delta) / d2;
    EXPECT_GE(s.L.x, 2 * lo * (1 - 1e-5)) << "cos " << cos_w;
    EXPECT_LE(s.L.x, 2 * hi * (1 + 1e-5)) << "cos " << cos_w;
    EXPECT_NEAR(s.L.z, 0.25 * s.L.x, 1e-6 * s.L.x);
    EXPECT_NEAR(s.dist, std::sqrt(d2), 1e-5 * std::sqrt(d2));
    EXPECT_LT(length(s.wi + normalize(d)), 1e-5f);
    EXPECT_EQ(s.point, pos);
    EXPECT_EQ(pdf_li(l, p, s.point), 0);  // a delta light: no BSDF sample finds it
  }
  // The points span the full cone, the falloff and the dark outside.
  EXPECT_GT(inside, 500);
  EXPECT_GT(falloff, 500);
  EXPECT_GT(outside, 5000);
}

TEST(SpotLight, PowerIsTheIntegralOfItsFalloff) {
  // 2 pi I ((1 - cos_start) + (cos_start - cos_end) / 2), against a quadrature of pbrt's
  // smoothstep over the sphere (in cos theta: 200,000 midpoints).
  for (const auto& [cone, delta] : {std::pair{30.0, 5.0}, {60.0, 60.0}, {10.0, 0.0}, {170.0, 30.0}}) {
    const Light l = make_spot_light(Vec3(0), Vec3(0, 0, 1), Rgb(3), float(std::cos((cone - delta) * kPiD / 180)),
                                    float(std::cos(cone * kPiD / 180)));
    double sum = 0;
    const int n = 200000;
    for (int i = 0; i < n; ++i) {
      const double c = -1 + 2 * (i + 0.5) / n;
      const Vec3 w(float(std::sqrt(1 - c * c)), 0, float(c));
      sum += pbrt_spot(3, Vec3(0, 0, 1), w, cone, delta);
    }
    const double phi = 2 * kPiD * sum * 2 / n;
    EXPECT_NEAR(light_power(l, 1), phi, 1e-3 * phi) << cone << " " << delta;
  }
}

TEST(SpotLight, BoundsAreZeroOnlyWhereTheSpotCannotContribute) {
  // Importance of a spot's own bounds: positive wherever the spot lights the point (and the
  // point's normal faces it), zero outside its cone, at many random points and normals.
  Pcg32 rng(9);
  for (int k = 0; k < 50; ++k) {
    const Vec3 axis = normalize(Vec3(rng.next_float() - 0.5f, rng.next_float() - 0.5f,
                                     rng.next_float() - 0.5f));
    const float cone = 1 + 120 * rng.next_float(), delta = cone * rng.next_float();
    const Light l = make_spot_light(Vec3(0), axis, Rgb(1), std::cos(radians(cone - delta)),
                                    std::cos(radians(cone)));
    const LightBounds b = light_bounds(l);
    int zero = 0, lit = 0;
    for (int i = 0; i < 400; ++i) {
      const Vec3 p = Vec3(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() - 0.5f) * 10;
      const Vec3 n = normalize(-p + Vec3(rng.next_float() - 0.5f, rng.next_float() - 0.5f,
                                         rng.next_float() - 0.5f) * 8);
      const float imp = light_importance(b, p, n);
      const bool contributes = dot(-p, n) > 0 && spot_falloff(l, normalize(p)) > 0;
      if (contributes) {
        ++lit;
        EXPECT_GT(imp, 0) << "cone " << cone << " delta " << delta << " cos "
                          << dot(axis, normalize(p));
      }
      if (!(spot_falloff(l, normalize(p)) > 0) &&
          dot(axis, normalize(p)) < std::cos(radians(cone) + 1e-3f)) {
        ++zero;
        EXPECT_EQ(imp, 0) << "outside the cone, cone " << cone;
      }
    }
    (void)zero;
    (void)lit;
  }
}

TEST(PbrtLights, SpotReadsEveryParameterAsPbrtV4) {
  TempDir dir;
  Scene s = read_pbrt(dir,
                      "Translate 1 0 0\n"
                      "LightSource \"spot\" \"rgb I\" [ 2 1 1 ] \"float scale\" 3 \"point3 from\" "
                      "[ 0 4 0 ] \"point3 to\" [ 0 0 0 ] \"float coneangle\" 40 "
                      "\"float conedeltaangle\" 10\n");
  ASSERT_EQ(s.lights.size(), 1u);
  const Light& l = s.lights[0];
  ASSERT_EQ(l.type, LightType::Spot);
  EXPECT_EQ(l.p0, Vec3(1, 4, 0));
  EXPECT_EQ(l.n, Vec3(0, -1, 0));
  EXPECT_EQ(l.radiance, Rgb(6, 3, 3));
  EXPECT_FLOAT_EQ(l.p1.x, std::cos(radians(30)));
  EXPECT_FLOAT_EQ(l.p1.y, std::cos(radians(40)));
  EXPECT_TRUE(s.warnings.empty());
  // pbrt-v4's defaults: from (0,0,0) to (0,0,1), cone 30, delta 5, I 1.
  Scene d = read_pbrt(dir, "LightSource \"spot\"\n");
  EXPECT_EQ(d.lights[0].n, Vec3(0, 0, 1));
  EXPECT_FLOAT_EQ(d.lights[0].p1.y, std::cos(radians(30)));
  EXPECT_FLOAT_EQ(d.lights[0].p1.x, std::cos(radians(25)));
  EXPECT_EQ(d.lights[0].radiance, Rgb(1));
}

TEST(PbrtLights, PowerAndIlluminanceNormalizeAsPbrtV4) {
  TempDir dir;
  // point: I = power / (4 pi), the colour's own luminance not counted (pbrt-v4's k_e).
  Scene p = read_pbrt(dir, "LightSource \"point\" \"rgb I\" [ 1 0.5 0.25 ] \"float scale\" 2 "
                           "\"float power\" 100\n");
  EXPECT_NEAR(p.lights[0].radiance.x, 2 * 100 / (4 * kPiD), 1e-4);
  EXPECT_NEAR(p.lights[0].radiance.z, 0.5 * 100 / (4 * kPiD), 1e-4);
  // spot: I = power / (2 pi ((1 - cos_start) + (cos_start - cos_end) / 2)): power() gives back
  // the stated watts for a white spot.
  Scene sp = read_pbrt(dir, "LightSource \"spot\" \"float power\" 50 \"float coneangle\" 20 "
                            "\"float conedeltaangle\" 8\n");
  EXPECT_NEAR(light_power(sp.lights[0], 1), 50, 50 * 1e-5);
  // distant: L x illuminance.
  Scene di = read_pbrt(dir, "LightSource \"distant\" \"rgb L\" [ 1 2 3 ] \"float illuminance\" 7\n");
  EXPECT_TRUE(length(di.lights[0].radiance - Rgb(7, 14, 21)) < 1e-5f);
  // infinite: L x illuminance / pi.
  Scene in = read_pbrt(dir, "LightSource \"infinite\" \"float illuminance\" 3\n");
  ASSERT_TRUE(in.sky);
  EXPECT_NEAR(in.sky->radiance.x, 3 / kPiD, 1e-6);
  // A value that is not positive is pbrt-v4's "not given": ignored, with a warning (not -1).
  Scene z = read_pbrt(dir, "LightSource \"point\" \"float power\" 0\n");
  EXPECT_EQ(z.lights[0].radiance, Rgb(1));
  ASSERT_FALSE(z.warnings.empty());
  expect_mentions(z.warnings[0], {"s.pbrt:2:", "power", "ignored"});
  Scene m = read_pbrt(dir, "LightSource \"point\" \"float power\" -1\n");
  EXPECT_TRUE(m.warnings.empty());
}

TEST(PbrtLights, AreaPowerNormalizesEachPbrtShape) {
  TempDir dir;
  // A quad of two triangles of areas 2 and 4 (a trianglemesh): pbrt-v4 gives each triangle the
  // power; two-sided doubles the sides. A disk is one shape: its triangles share the power.
  Scene s = read_pbrt(
      dir,
      "AttributeBegin\n"
      "AreaLightSource \"diffuse\" \"rgb L\" [ 1 1 1 ] \"float power\" 10 \"bool twosided\" true\n"
      "Shape \"trianglemesh\" \"point3 P\" [ 0 0 0  2 0 0  0 2 0  4 2 0 ] \"integer indices\" "
      "[ 0 1 2  1 3 2 ]\n"
      "AttributeEnd\n"
      "AreaLightSource \"diffuse\" \"rgb L\" [ 1 0.5 0.5 ] \"float power\" 20\n"
      "Translate 0 0 5\n"
      "Shape \"disk\" \"float radius\" 2\n");
  s.finalize();
  double tri_power[2] = {0, 0}, disk = 0;
  for (const Light& l : s.lights) {
    ASSERT_EQ(l.type, LightType::Triangle);
    // pbrt-v4's power ignores the colour's luminance: measure the red channel, which is 1 x.
    const double phi = kPiD * l.area * l.radiance.x * (l.two_sided ? 2 : 1);
    if (l.triangle < 2)
      tri_power[l.triangle] = phi;
    else
      disk += phi;
  }
  EXPECT_NEAR(tri_power[0], 10, 1e-4);
  EXPECT_NEAR(tri_power[1], 10, 1e-4);
  EXPECT_NEAR(disk, 20, 20 * 1e-5);
}

TEST(PbrtLights, SeveralInfiniteLightsAreSummedIntoOneSky) {
  TempDir dir;
  // Constant ones: their radiances add, exactly.
  Scene c = read_pbrt(dir, "LightSource \"infinite\" \"rgb L\" [ 1 2 3 ]\n"
                           "LightSource \"infinite\" \"rgb L\" [ 0.5 0.5 0.5 ] \"float scale\" 2\n");
  ASSERT_TRUE(c.sky);
  EXPECT_EQ(c.sky->radiance, Rgb(2, 3, 4));
  EXPECT_FALSE(c.sky->map);
  expect_mentions(c.warnings.at(0), {"s.pbrt:3:", "several infinite lights are summed"});
  // A map (bright upper half in the map's frame, +z; the light rotated so that it is world +y)
  // and a constant: one equal-area map in the world's frame holding their sum.
  Image map(32, 32);
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x)
      map.at(x, y) = equal_area_square_to_sphere({(x + 0.5f) / 32, (y + 0.5f) / 32}).z > 0
                         ? Rgb(4, 2, 1)
                         : Rgb(0.25f);
  write_image(dir.path() / "env.exr", map);
  Scene m = read_pbrt(dir, "AttributeBegin\nRotate -90 1 0 0\n"
                           "LightSource \"infinite\" \"string filename\" \"env.exr\" \"float scale\" 2\n"
                           "AttributeEnd\n"
                           "LightSource \"infinite\" \"rgb L\" [ 1 1 1 ]\n");
  ASSERT_TRUE(m.sky && m.sky->map);
  EXPECT_EQ(m.sky->radiance, Rgb(1));
  const Rgb up = m.sky->map->lookup(Vec3(0.1f, 1, 0.2f)), down = m.sky->map->lookup(Vec3(0.2f, -1, 0.1f));
  EXPECT_TRUE(length(up - Rgb(9, 5, 3)) < 1e-4f) << up.x << " " << up.y << " " << up.z;
  EXPECT_TRUE(length(down - Rgb(1.5f)) < 1e-4f) << down.x;
}

TEST(PbrtLights, PortalIsNamedInAWarning) {
  TempDir dir;
  Scene s = read_pbrt(dir, "LightSource \"infinite\" \"point3 portal\" [ 0 0 0  1 0 0  1 1 0  0 1 0 ]\n");
  ASSERT_EQ(s.warnings.size(), 1u);
  expect_mentions(s.warnings[0], {"s.pbrt:2:", "portal", "ignored"});
}

TEST(PbrtLights, BadSpotParametersAreRefusedWithFileAndLine) {
  TempDir dir;
  expect_mentions(pbrt_error(dir, "LightSource \"spot\" \"float coneangle\" -5\n"),
                  {"bad.pbrt:2:", "coneangle"});
  expect_mentions(pbrt_error(dir, "LightSource \"spot\" \"float coneangle\" 200\n"),
                  {"bad.pbrt:2:", "coneangle"});
  expect_mentions(pbrt_error(dir, "LightSource \"spot\" \"float coneangle\" 20 "
                                  "\"float conedeltaangle\" 25\n"),
                  {"bad.pbrt:2:", "conedeltaangle"});
  expect_mentions(pbrt_error(dir, "LightSource \"spot\" \"float conedeltaangle\" -1\n"),
                  {"bad.pbrt:2:", "conedeltaangle"});
  expect_mentions(
      pbrt_error(dir, "LightSource \"spot\" \"point3 from\" [ 1 1 1 ] \"point3 to\" [ 1 1 1 ]\n"),
      {"bad.pbrt:2:", "same point"});
  expect_mentions(pbrt_error(dir, "LightSource \"spot\" \"float power\" [ 1 2 ]\n"),
                  {"bad.pbrt:2:", "power"});
}

// An image light's intensity along world direction w, as every renderer reads it.
Rgb intensity(const Scene& s, const Light& l, const Vec3& w, float r = 3) {
  const TexelView image = s.textures.at(l.triangle).texel_view();
  const LightLiSample ls = sample_li(l, l.p0 + w * r, {0.5f, 0.5f}, &image);
  return ls.pdf > 0 ? ls.L * (r * r) : Rgb(0);
}

// The light's power as a Monte Carlo integral of its intensity over the sphere (luminance), with
// its standard error.
std::pair<double, double> integrated_power(const Scene& s, const Light& l, int n) {
  Pcg32 rng(3);
  double sum = 0, sum2 = 0;
  for (int i = 0; i < n; ++i) {
    const double z = 1 - 2 * double(rng.next_float()), phi = 2 * kPiD * rng.next_float();
    const double r = std::sqrt(std::max(0.0, 1 - z * z));
    const Vec3 w(float(r * std::cos(phi)), float(r * std::sin(phi)), float(z));
    const double v = 4 * kPiD * luminance(intensity(s, l, w));
    sum += v;
    sum2 += v * v;
  }
  const double mean = sum / n;
  return {mean, std::sqrt(std::max(0.0, sum2 / n - mean * mean) / n)};
}

TEST(PbrtLights, GoniometricIsItsEqualAreaProfileAroundTheLightsY) {
  TempDir dir;
  // A profile over the map's directions (brighter towards +z and +x), in colour: pbrt-v4 reads
  // the mean of R, G and B.
  Image g(16, 16);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) {
      const Vec3 d = equal_area_square_to_sphere({(x + 0.5f) / 16, (y + 0.5f) / 16});
      g.at(x, y) = Rgb(1.5f + d.z + 0.5f * d.x, 0.5f, 1 + d.z);
    }
  write_image(dir.path() / "g.exr", g);
  Scene s = read_pbrt(dir, "Translate 1 2 3\n"
                           "LightSource \"goniometric\" \"string filename\" \"g.exr\" \"rgb I\" [ 2 1 1 ]\n");
  ASSERT_EQ(s.lights.size(), 1u);
  const Light& l = s.lights[0];
  ASSERT_EQ(l.type, LightType::Goniometric);
  EXPECT_EQ(l.p0, Vec3(1, 2, 3));
  // Each pixel's direction in the map (x, y, z) is the world's (x, z, y) (pbrt-v4's swap).
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) {
      const Vec3 d = equal_area_square_to_sphere({(x + 0.5f) / 16, (y + 0.5f) / 16});
      const float mean = (g.at(x, y).x + g.at(x, y).y + g.at(x, y).z) / 3;
      const Rgb I = intensity(s, l, normalize(Vec3(d.x, d.z, d.y)));
      EXPECT_NEAR(I.x, 2 * mean, 2e-4 * mean) << x << " " << y;
      EXPECT_NEAR(I.y, mean, 2e-4 * mean) << x << " " << y;
    }
  // power(): 4 pi x the image's mean x I, and the integral of the intensity.
  const auto [phi, se] = integrated_power(s, l, 40000);
  EXPECT_NEAR(light_power(l, 1), phi, 5 * se + 1e-3 * phi);
  Scene p = read_pbrt(dir, "LightSource \"goniometric\" \"string filename\" \"g.exr\" \"float power\" 30\n");
  EXPECT_NEAR(light_power(p.lights[0], 1), 30, 30 * 1e-4);
}

TEST(PbrtLights, ProjectionProjectsItsImageUprightThroughItsFov) {
  TempDir dir;
  // Aspect 2: the fov spans the vertical side. Fine pixels, so that pbrt-v4's power (cos^3 at
  // each pixel's centre) is the integral to within 0.1%.
  constexpr int W = 64, H = 32;
  Image im(W, H);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) im.at(x, y) = Rgb(float(1 + x / 8), float(1 + y / 8), 0.5f);
  write_image(dir.path() / "p.exr", im);
  Scene s = read_pbrt(dir, "LightSource \"projection\" \"string filename\" \"p.exr\" "
                           "\"float fov\" 60 \"float scale\" 3\n");
  ASSERT_EQ(s.lights.size(), 1u);
  const Light& l = s.lights[0];
  ASSERT_EQ(l.type, LightType::Projection);
  const double tan_half = std::tan(30 * kPiD / 180);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      // The pixel's centre on pbrt's screen [-2, 2] x [-1, 1], row 0 at the top (+y).
      const double sx = 2 * (-1 + 2 * (x + 0.5) / W), sy = -1 + 2 * (y + 0.5) / H;
      const Vec3 w = normalize(Vec3(float(sx * tan_half), float(-sy * tan_half), 1));
      const Rgb I = intensity(s, l, w);
      EXPECT_NEAR(I.x, 3 * (1 + x / 8), 1e-4) << x << " " << y;
      EXPECT_NEAR(I.y, 3 * (1 + y / 8), 1e-4) << x << " " << y;
    }
  // Nothing outside the frustum or behind the light.
  EXPECT_EQ(intensity(s, l, normalize(Vec3(float(2.2 * tan_half), 0, 1))), Rgb(0));
  EXPECT_EQ(intensity(s, l, normalize(Vec3(0, float(1.1 * tan_half), 1))), Rgb(0));
  EXPECT_EQ(intensity(s, l, Vec3(0, 0, -1)), Rgb(0));
  const auto [phi, se] = integrated_power(s, l, 200000);
  EXPECT_NEAR(light_power(l, 1), phi, 5 * se + 2e-3 * phi);
  Scene p = read_pbrt(dir, "LightSource \"projection\" \"string filename\" \"p.exr\" \"float power\" 12\n");
  EXPECT_NEAR(light_power(p.lights[0], 1), 12, 12 * 1e-4);
  // Its bounds: zero importance outside the frustum's cone only.
  const LightBounds b = light_bounds(l);
  EXPECT_GT(light_importance(b, Vec3(0.9f * float(2 * tan_half), 0.9f * float(tan_half), 1), Vec3(0)), 0);
  EXPECT_EQ(light_importance(b, Vec3(0, 0, -1), Vec3(0)), 0);
  expect_mentions(pbrt_error(dir, "LightSource \"projection\"\n"), {"bad.pbrt:2:", "filename"});
  expect_mentions(pbrt_error(dir, "LightSource \"projection\" \"string filename\" \"p.exr\" \"float fov\" 0\n"),
                  {"bad.pbrt:2:", "fov"});
  expect_mentions(pbrt_error(dir, "LightSource \"goniometric\" \"string filename\" \"p.exr\"\n"),
                  {"bad.pbrt:2:", "square"});
}

TEST(LightWriters, ImageLightsRoundTripThroughPbrtAndJson) {
  TempDir dir;
  Image g(8, 8), im(6, 4);
  for (int i = 0; i < 64; ++i) g[size_t(i)] = Rgb(float(1 + i % 5));
  for (int i = 0; i < 24; ++i) im[size_t(i)] = Rgb(float(1 + i % 7), float(1 + i % 3), 1);
  write_image(dir.path() / "g.exr", g);
  write_image(dir.path() / "p.exr", im);
  Scene s = read_pbrt(dir, "AttributeBegin\nTranslate 1 2 3\nRotate 30 1 1 0\n"
                           "LightSource \"goniometric\" \"string filename\" \"g.exr\" \"rgb I\" [ 2 1 1 ]\n"
                           "AttributeEnd\nLookAt 0 5 0  0 0 0  0 0 1\n"
                           "LightSource \"projection\" \"string filename\" \"p.exr\" \"float fov\" 40\n");
  ASSERT_EQ(s.lights.size(), 2u);
  EXPECT_TRUE(save_pbrt_scene(s, dir.path() / "o.pbrt").empty());
  save_json_scene(s, dir.path() / "o.json");
  for (const char* out : {"o.pbrt", "o.json"}) {
    SCOPED_TRACE(out);
    const Scene r = read_scene((dir.path() / out).string());
    ASSERT_EQ(r.lights.size(), 2u);
    Pcg32 rng(1);
    for (size_t k = 0; k < 2; ++k) {
      EXPECT_EQ(r.lights[k].type, s.lights[k].type);
      EXPECT_NEAR(light_power(r.lights[k], 1), light_power(s.lights[k], 1), 1e-4 * light_power(s.lights[k], 1));
      for (int i = 0; i < 500; ++i) {
        const Vec3 w = normalize(Vec3(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() - 0.5f));
        // Away from texel edges, where rounding may pick the neighbour.
        const Rgb a = intensity(s, s.lights[k], w), b = intensity(r, r.lights[k], w);
        const Rgb a2 = intensity(s, s.lights[k], normalize(w + Vec3(1e-3f, 0, 0)));
        if (length(a - a2) > 0) continue;
        EXPECT_LT(length(a - b), 1e-4f * (1 + length(a))) << k << " " << i;
      }
    }
  }
}

// Every light kind a scene holds, as the writers and readers carry it.
Scene kinds_scene() {
  Scene s;
  SceneBuilder b(s);  // some geometry, which every format needs
  b.quad(Vec3(-1, 0, -1), Vec3(0, 0, 2), Vec3(2, 0, 0), b.diffuse(Rgb(0.5f)));
  s.lights.push_back(make_point_light(Vec3(1, 2, 3), Rgb(4, 2, 1)));
  s.lights.push_back(make_spot_light(Vec3(-1, 3, 0.5f), Vec3(0.3f, -1, 0.2f), Rgb(5, 6, 7),
                                     std::cos(radians(22)), std::cos(radians(35))));
  s.lights.push_back(make_directional_light(Vec3(0.2f, 1, 0.3f), Rgb(0.5f)));
  return s;
}

void expect_same_lights(const Scene& a, const Scene& b, const std::string& how) {
  SCOPED_TRACE(how);
  ASSERT_EQ(a.lights.size(), b.lights.size());
  for (size_t i = 0; i < a.lights.size(); ++i) {
    const Light &x = a.lights[i], &y = b.lights[i];
    ASSERT_EQ(x.type, y.type) << i;
    EXPECT_LT(length(x.p0 - y.p0), 1e-5f * (1 + length(x.p0))) << i;
    EXPECT_LT(length(x.radiance - y.radiance), 1e-5f * (1 + length(x.radiance))) << i;
    if (x.type == LightType::Spot) {
      EXPECT_LT(length(x.n - y.n), 1e-5f) << i;
      EXPECT_NEAR(x.p1.x, y.p1.x, 1e-6) << i;
      EXPECT_NEAR(x.p1.y, y.p1.y, 1e-6) << i;
    }
  }
}

TEST(LightWriters, PbrtAndJsonKeepEveryKind) {
  TempDir dir;
  const Scene s = kinds_scene();
  save_json_scene(s, dir.path() / "k.json");
  expect_same_lights(s, read_scene((dir.path() / "k.json").string()), "json");
  EXPECT_TRUE(save_pbrt_scene(s, dir.path() / "k.pbrt").empty());
  expect_same_lights(s, read_scene((dir.path() / "k.pbrt").string()), "pbrt");
}

TEST(LightWriters, GltfKeepsPointAndSpotAndNamesWhatItCannotHold) {
  TempDir dir;
  Scene s = kinds_scene();
  const auto warnings = save_gltf_scene(s, dir.path() / "k.gltf");
  expect_same_lights(s, read_scene((dir.path() / "k.gltf").string()), "gltf");
  bool falloff = false;
  for (const auto& w : warnings) falloff |= w.find("falloff") != std::string::npos;
  EXPECT_TRUE(falloff) << "the spot's falloff shape is named";
  // A cone wider than glTF's 90 degrees is narrowed, with a warning.
  s.lights[1].p1 = Vec3(std::cos(radians(80)), std::cos(radians(120)), 0);
  bool wide = false;
  for (const auto& w : save_gltf_scene(s, dir.path() / "w.gltf"))
    wide |= w.find("120") != std::string::npos;
  EXPECT_TRUE(wide);
}

TEST(JsonLights, SpotFieldsAndBadValues) {
  TempDir dir;
  auto read = [&](const std::string& light) {
    Scene s;
    load_json_scene(dir.write("s.json", R"({"lights": [)" + light + "]}"), s);
    return s;
  };
  Scene s = read(R"({"type": "spot", "position": [0, 2, 0], "direction": [0, -2, 0],
                     "intensity": [1, 2, 3], "cone_angle": 30, "cone_delta_angle": 10})");
  ASSERT_EQ(s.lights[0].type, LightType::Spot);
  EXPECT_EQ(s.lights[0].n, Vec3(0, -1, 0));
  EXPECT_FLOAT_EQ(s.lights[0].p1.x, std::cos(radians(20)));
  EXPECT_FLOAT_EQ(s.lights[0].p1.y, std::cos(radians(30)));
  auto error = [&](const std::string& light) { return error_of([&] { read(light); }); };
  expect_mentions(error(R"({"type": "spot", "position": [0, 2, 0], "direction": [0, -1, 0],
                            "intensity": [1, 1, 1], "cone_angle": -3})"),
                  {"/lights/0/cone_angle"});
  expect_mentions(error(R"({"type": "spot", "position": [0, 2, 0], "direction": [0, -1, 0],
                            "intensity": [1, 1, 1], "cone_angle": 30, "cone_delta_angle": 31})"),
                  {"/lights/0/cone_delta_angle"});
  expect_mentions(error(R"({"type": "spot", "position": [0, 2, 0], "direction": [0, 0, 0],
                            "intensity": [1, 1, 1], "cone_angle": 30})"),
                  {"/lights/0/direction"});
}

}  // namespace
