// Textured emitters: the exact integral of the bilinear reconstruction over a triangle against
// analytic values (a constant and a linear texture) and against fine point sampling of
// sample_texture itself; the splitting of a large emitter into lights whose powers add up to the
// whole; the emission at hits and at light samples read from the texture; bad textures refused.
#include <gtest/gtest.h>

#include <cmath>

#include "rll/core/error.h"
#include "rll/core/rng.h"
#include "rll/core/sampling.h"
#include "rll/io/load.h"
#include "rll/io/save.h"
#include "rll/scene/builder.h"
#include "rll/scene/interaction.h"
#include "rll/scene/scene_view.h"
#include "rll/scene/textured_emitters.h"
#include "support/test_support.h"

using namespace rll;
using rll::test::error_of;
using rll::test::expect_mentions;

namespace {

Image random_texture(int w, int h, uint64_t seed) {
  Image img(w, h);
  Pcg32 rng(seed);
  for (size_t i = 0; i < img.pixel_count(); ++i)
    img[i] = Rgb(rng.next_float(), rng.next_float() * 2, rng.next_float() * 0.5f);
  return img;
}

std::array<Vec2, 3> random_uvs(Pcg32& rng, float lo, float hi) {
  std::array<Vec2, 3> uv;
  for (Vec2& p : uv)
    p = Vec2{lo + (hi - lo) * rng.next_float(), lo + (hi - lo) * rng.next_float()};
  return uv;
}

// The mean of sample_texture over the triangle from the centroids of n^2 equal sub-triangles: an
// independent estimate, good to O(1/n^2) for a smooth reconstruction, O(1/n) at its kinks.
Rgb supersampled_mean(const Image& tex, const std::array<Vec2, 3>& uv, int n) {
  double s[3] = {0, 0, 0};
  auto add = [&](double b1, double b2) {
    const double b0 = 1 - b1 - b2;
    const Rgb c = sample_texture(tex, Vec2{float(uv[0].x * b0 + uv[1].x * b1 + uv[2].x * b2),
                                           float(uv[0].y * b0 + uv[1].y * b1 + uv[2].y * b2)});
    s[0] += c.x, s[1] += c.y, s[2] += c.z;
  };
  for (int i = 0; i < n; ++i)
    for (int j = 0; i + j < n; ++j) {
      add((i + 1.0 / 3) / n, (j + 1.0 / 3) / n);
      if (i + j + 1 < n) add((i + 2.0 / 3) / n, (j + 2.0 / 3) / n);
    }
  const double k = double(n) * n;
  return Rgb(float(s[0] / k), float(s[1] / k), float(s[2] / k));
}

}  // namespace

TEST(TexturedEmitters, ConstantTextureIntegratesToItsValueAtAnyTiling) {
  const Image tex(7, 5, Rgb(0.25f, 1.5f, 3.0f));
  Pcg32 rng(3);
  for (int k = 0; k < 50; ++k) {
    const auto uv = random_uvs(rng, -2.3f, 3.1f);  // wraps many times
    const TextureIntegral I = integrate_texture(tex.texel_view(), uv);
    ASSERT_TRUE(I.exact);
    const Rgb m = I.mean();
    EXPECT_NEAR(m.x, 0.25, 1e-6);
    EXPECT_NEAR(m.y, 1.5, 1e-6);
    EXPECT_NEAR(m.z, 3.0, 2e-6);
  }
}

TEST(TexturedEmitters, LinearTextureIntegratesToItsValueAtTheCentroid) {
  // Texels linear in x and y: inside the texel centres' hull the reconstruction is the linear
  // function itself, whose mean over a triangle is its value at the centroid.
  const int w = 16, h = 12;
  Image tex(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) tex.at(x, y) = Rgb(0.5f + 0.25f * x, 2.0f + 0.1f * y, 1.0f);
  Pcg32 rng(5);
  for (int k = 0; k < 50; ++k) {
    std::array<Vec2, 3> uv;
    for (Vec2& p : uv)  // texel coordinates X in [0, w-1], Y in [0, h-1]
      p = Vec2{(0.5f + (w - 1) * rng.next_float()) / w, 1 - (0.5f + (h - 1) * rng.next_float()) / h};
    const TextureIntegral I = integrate_texture(tex.texel_view(), uv);
    double X = 0, Y = 0;
    for (const Vec2& p : uv) X += (double(p.x) * w - 0.5) / 3, Y += ((1 - double(p.y)) * h - 0.5) / 3;
    const Rgb m = I.mean();
    EXPECT_NEAR(m.x, 0.5 + 0.25 * X, 1e-5) << k;
    EXPECT_NEAR(m.y, 2.0 + 0.1 * Y, 1e-5) << k;
    EXPECT_NEAR(m.z, 1.0, 1e-6);
  }
}

TEST(TexturedEmitters, IntegralMatchesFinePointSamplingOfTheLookup) {
  const Image tex = random_texture(9, 6, 11);
  Pcg32 rng(13);
  for (int k = 0; k < 12; ++k) {
    const auto uv = random_uvs(rng, -0.4f, 1.3f);
    const Rgb exact = integrate_texture(tex.texel_view(), uv).mean();
    const Rgb sampled = supersampled_mean(tex, uv, 600);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(exact[c], sampled[c], 2e-3 * (1 + sampled[c])) << k;
  }
}

TEST(TexturedEmitters, IntegralIsAdditiveOverHalves) {
  const Image tex = random_texture(32, 32, 17);
  Pcg32 rng(19);
  for (int k = 0; k < 20; ++k) {
    const auto uv = random_uvs(rng, -1.0f, 2.0f);
    const Vec2 m{0.5f * (uv[0].x + uv[1].x), 0.5f * (uv[0].y + uv[1].y)};
    const auto whole = integrate_texture(tex.texel_view(), uv);
    const auto a = integrate_texture(tex.texel_view(), std::array<Vec2, 3>{uv[0], m, uv[2]});
    const auto b = integrate_texture(tex.texel_view(), std::array<Vec2, 3>{m, uv[1], uv[2]});
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(whole.sum[c], a.sum[c] + b.sum[c], 1e-6 * (1 + std::abs(whole.sum[c])));
  }
}

TEST(TexturedEmitters, DegenerateUvsGiveThePointValue) {
  const Image tex = random_texture(4, 4, 23);
  const std::array<Vec2, 3> uv{Vec2{0.3f, 0.6f}, Vec2{0.3f, 0.6f}, Vec2{0.3f, 0.6f}};
  const TextureIntegral I = integrate_texture(tex.texel_view(), uv);
  EXPECT_TRUE(I.exact);
  const Rgb v = sample_texture(tex, uv[0]);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(I.mean()[c], v[c], 1e-6);
}

namespace {

// A 4 x 3 quad emitting `factor` times a random 40 x 30 texture, facing +z, in a scene.
Scene textured_quad_scene(const Rgb& factor, bool two_sided = false) {
  Scene s;
  s.source = "test";
  SceneBuilder b(s);
  s.textures.push_back(random_texture(40, 30, 29));
  Material m;
  m.name = "screen";
  m.emission = factor;
  m.emission_texture = 0;
  m.two_sided_emission = two_sided;
  const uint32_t mat = b.material(m);
  b.quad(Vec3(0, 0, 0), Vec3(4, 0, 0), Vec3(0, 3, 0), mat);
  s.mesh.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  b.quad(Vec3(-5, -5, -1), Vec3(10, 0, 0), Vec3(0, 10, 0), b.diffuse(Rgb(0.5f)));
  return s;
}

}  // namespace

TEST(TexturedEmitters, SplitLightsAddUpToTheWholeEmitter) {
  const Rgb factor(2, 1, 3);
  Scene s = textured_quad_scene(factor, true);
  // The whole quad's power from the unsplit triangles, before finalize splits them.
  double expected = 0;
  for (uint32_t t = 0; t < 2; ++t) {
    const Rgb mean = integrate_texture(s.textures[0].texel_view(), triangle_uvs(s, t)).mean();
    expected += double(kPi) * s.mesh.area(t) * 2 * luminance(factor * mean);
  }
  s.finalize();
  EXPECT_GT(s.lights.size(), 100u);  // split into many pieces
  EXPECT_LE(s.lights.size(), 2u * 40 * 30);
  double power = 0, area = 0;
  for (const Light& l : s.lights) {
    ASSERT_TRUE(l.textured);
    power += light_power(l, s.radius);
    area += l.area;
  }
  EXPECT_NEAR(area, 12.0, 1e-4);
  EXPECT_NEAR(power, expected, 2e-6 * expected);
  // Every light's mean is the texture's exact mean over its own uvs.
  for (size_t i = 0; i < s.lights.size(); i += 37) {
    const Light& l = s.lights[i];
    const Rgb mean = integrate_texture(s.textures[0].texel_view(), triangle_uvs(s, l.triangle)).mean();
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(l.radiance[c], factor[c] * mean[c], 1e-5 * (1 + factor[c]));
  }
  // Nearly equal power: the brightest piece holds a small share.
  double largest = 0;
  for (const Light& l : s.lights) largest = std::max(largest, double(light_power(l, s.radius)));
  EXPECT_LT(largest, 0.02 * power);
  // A second finalize splits nothing more.
  const size_t lights = s.lights.size(), triangles = s.mesh.triangle_count();
  s.finalize();
  EXPECT_EQ(s.lights.size(), lights);
  EXPECT_EQ(s.mesh.triangle_count(), triangles);
}

TEST(TexturedEmitters, EmissionAtHitsAndLightSamplesIsTheTexture) {
  const Rgb factor(2, 1, 3);
  Scene s = textured_quad_scene(factor);
  s.finalize();
  SceneData data(s);
  const SceneView& v = data.view();
  Pcg32 rng(31);
  int checked = 0;
  for (int k = 0; k < 400; ++k) {
    const Light& l = s.lights[rng.next_u32() % s.lights.size()];
    const Vec3 p(4 * rng.next_float(), 3 * rng.next_float(), 1 + rng.next_float());
    const LightLiSample ls = sample_li(v, l, p, Vec2{rng.next_float(), rng.next_float()});
    if (!(ls.pdf > 0)) continue;
    // The sampled point lies on the quad: its uv is its position over the quad's size.
    const Vec2 uv{ls.point.x / 4, ls.point.y / 3};
    const Rgb expected = factor * sample_texture(s.textures[0], uv);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(ls.L[c], expected[c], 1e-4 * (1 + expected[c]));
    // The same point found by a ray: its hit's emission.
    Hit hit;
    hit.tri = l.triangle;
    const Triangle& t = s.mesh.triangles[l.triangle];
    const Vec3 a = s.mesh.positions[t[0]], e1 = s.mesh.positions[t[1]] - a,
               e2 = s.mesh.positions[t[2]] - a, d = ls.point - a;
    const float d00 = dot(e1, e1), d01 = dot(e1, e2), d11 = dot(e2, e2), den = d00 * d11 - d01 * d01;
    hit.u = (d11 * dot(d, e1) - d01 * dot(d, e2)) / den;
    hit.v = (d00 * dot(d, e2) - d01 * dot(d, e1)) / den;
    const SurfaceHit sh = make_surface_hit(v.mesh, hit);
    const Rgb Le = emitted_radiance(v, l, sh, -ls.wi);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(Le[c], expected[c], 1e-4 * (1 + expected[c]));
    // One-sided: nothing behind.
    EXPECT_TRUE(is_black(emitted_radiance(v, l, sh, ls.wi)));
    ++checked;
  }
  EXPECT_GT(checked, 300);
}

TEST(TexturedEmitters, BadEmissionTexturesAreRefused) {
  {
    Scene s = textured_quad_scene(Rgb(1));
    s.textures[0].at(3, 4) = Rgb(0.5f, -1, 0);
    expect_mentions(error_of([&] { s.finalize(); }), {"test", "screen", "emission texture", "negative"});
  }
  {
    Scene s = textured_quad_scene(Rgb(1));
    s.materials[0].emission_texture = 5;
    expect_mentions(error_of([&] { s.finalize(); }), {"test", "screen", "emission texture"});
  }
}

namespace {

Scene read_pbrt(const test::TempDir& dir, const std::string& text) {
  Scene s;
  load_pbrt(dir.write("s.pbrt", text), s);
  return s;
}

// A quad of two triangles with uvs over [0, 1]^2, as a pbrt trianglemesh.
const char* kPbrtQuad =
    "Shape \"trianglemesh\" \"point3 P\" [ 0 0 0  2 0 0  2 1 0  0 1 0 ] \"point2 uv\" "
    "[ 0 0  1 0  1 1  0 1 ] \"integer indices\" [ 0 1 2  0 2 3 ]\n";

}  // namespace

TEST(TexturedEmitters, PbrtImageAreaLight) {
  test::TempDir dir;
  write_image(dir / "glow.exr", random_texture(8, 4, 37));
  Scene s = read_pbrt(dir, std::string("AreaLightSource \"diffuse\" \"string filename\" \"glow.exr\" "
                                       "\"float scale\" 2 \"bool twosided\" true\n") +
                               kPbrtQuad);
  const Material& m = s.materials[s.mesh.material[0]];
  EXPECT_EQ(m.emission, Rgb(2));
  ASSERT_GE(m.emission_texture, 0);
  EXPECT_TRUE(m.two_sided_emission);
  EXPECT_EQ(s.textures[size_t(m.emission_texture)].width(), 8);
  // pbrt-v4's power: scale = power / (pi A x the image's mean luminance), per triangle (area 1).
  Scene p = read_pbrt(dir, std::string("AreaLightSource \"diffuse\" \"string filename\" \"glow.exr\" "
                                       "\"float power\" 10\n") +
                               kPbrtQuad);
  const Material& pm = p.materials[p.mesh.material[0]];
  double mean = 0;
  const Image& img = p.textures[size_t(pm.emission_texture)];
  for (const Rgb& c : img.pixels()) mean += luminance(c) / double(img.pixel_count());
  EXPECT_NEAR(pm.emission.x, 10 / (kPi * 1.0 * mean), 1e-4 * pm.emission.x);
  // Bad input: named with the file and line.
  auto error = [&](const std::string& text) {
    return error_of([&] { read_pbrt(dir, text); });
  };
  expect_mentions(error("AreaLightSource \"diffuse\" \"string filename\" \"glow.exr\" \"rgb L\" [ 1 1 1 ]\n"),
                  {"s.pbrt:1", "\"L\"", "\"filename\""});
  expect_mentions(error("\nAreaLightSource \"diffuse\" \"string filename\" \"missing.exr\"\n"),
                  {"s.pbrt:2", "missing.exr"});
  expect_mentions(error("AreaLightSource \"diffuse\" \"string filename\" \"glow.exr\" \"float scale\" -1\n"),
                  {"s.pbrt:1", "scale"});
}

TEST(TexturedEmitters, JsonEmissionTextureAndWritersKeepIt) {
  test::TempDir dir;
  write_image(dir / "glow.exr", random_texture(8, 4, 37));
  Scene s;
  load_json_scene(dir.write("s.json", R"({
    "materials": {"screen": {"emission_texture": "glow.exr", "emission": [1, 2, 3], "albedo": [0, 0, 0]}},
    "shapes": [{"type": "quad", "origin": [0, 0, 0], "edge1": [2, 0, 0], "edge2": [0, 1, 0], "material": "screen"}]
  })"), s);
  const Material& m = s.materials[s.mesh.material[0]];
  ASSERT_GE(m.emission_texture, 0);
  EXPECT_EQ(m.emission, Rgb(1, 2, 3));
  ASSERT_EQ(s.mesh.uvs.size(), s.mesh.positions.size());
  // Without "emission", the texture alone.
  Scene plain;
  load_json_scene(dir.write("p.json", R"({"materials": {"screen": {"emission_texture": "glow.exr"}},
    "shapes": [{"type": "quad", "origin": [0, 0, 0], "edge1": [2, 0, 0], "edge2": [0, 1, 0], "material": "screen"}]})"),
                  plain);
  EXPECT_EQ(plain.materials[plain.mesh.material[0]].emission, Rgb(1));
  expect_mentions(error_of([&] {
                    Scene b;
                    load_json_scene(dir.write("b.json", R"({"materials": {"screen": {"emission_texture": "nope.png"}}})"), b);
                  }),
                  {"b.json", "emission_texture", "nope.png"});

  // Written as JSON and as pbrt, read back: the same emitted power.
  Scene original = s;
  original.finalize();
  double power = 0;
  for (const Light& l : original.lights) power += light_power(l, original.radius);
  for (const char* name : {"out.json", "out.pbrt"}) {
    const auto path = dir / name;
    if (std::string(name) == "out.json")
      save_json_scene(s, path);
    else
      save_pbrt_scene(s, path);
    Scene back = load_scene(path.string());
    back.finalize();
    double back_power = 0;
    for (const Light& l : back.lights) {
      EXPECT_TRUE(l.textured) << name;
      back_power += light_power(l, back.radius);
    }
    EXPECT_NEAR(back_power, power, 1e-4 * power) << name;
  }
}

namespace {

// The luminance flux through a sphere of radius 6 around the origin: 4 pi R^2 times the mean
// irradiance at uniform points on it (one sample_li of every light at each), with its standard
// error.
std::pair<double, double> flux_through_sphere(const Scene& s, int points) {
  SceneData data(s);
  const SceneView& v = data.view();
  const double R = 6;
  Pcg32 rng(53);
  double sum = 0, sum2 = 0;
  for (int k = 0; k < points; ++k) {
    const Vec3 d = sample_uniform_sphere(Vec2{rng.next_float(), rng.next_float()});
    const Vec3 y = d * float(R);
    double e = 0;
    for (const Light& l : s.lights) {
      const LightLiSample ls = sample_li(v, l, y, Vec2{rng.next_float(), rng.next_float()});
      const float c = -dot(ls.wi, d);
      if (ls.pdf > 0 && c > 0) e += double(luminance(ls.L)) * c / ls.pdf;
    }
    sum += e;
    sum2 += e * e;
  }
  const double area = 4 * kPi * R * R, mean = sum / points;
  return {area * mean, area * std::sqrt(std::max(0.0, sum2 / points - mean * mean) / points)};
}

}  // namespace

// pbrt-v4's "power": the flux a light emits, measured through a sphere around it, is the stated
// watts (a mesh's area light: each triangle's, as pbrt-v4 normalizes each).
TEST(TexturedEmitters, StatedWattsAreEmitted) {
  test::TempDir dir;
  write_image(dir / "glow.exr", random_texture(8, 4, 37));
  struct Case {
    std::string text;
    double watts;
  };
  const Case cases[] = {
      {"LightSource \"point\" \"rgb I\" [ 1 1 1 ] \"float power\" 10\n", 10},
      {"LightSource \"spot\" \"rgb I\" [ 1 1 1 ] \"float coneangle\" 40 \"float conedeltaangle\" 10 "
       "\"float power\" 10\n",
       10},
      {"AreaLightSource \"diffuse\" \"rgb L\" [ 1 1 1 ] \"float power\" 10\n"
       "Shape \"disk\" \"float radius\" 1\n",
       10},
      {"AreaLightSource \"diffuse\" \"rgb L\" [ 1 1 1 ] \"float power\" 10 \"bool twosided\" true\n"
       "Shape \"disk\" \"float radius\" 1\n",
       10},
      // Two triangles, each normalized to 10 W by the image's mean luminance; over the whole
      // period of the texture their exact means average to the image's mean: 20 W in all.
      {std::string("AreaLightSource \"diffuse\" \"string filename\" \"glow.exr\" \"float power\" 10\n") +
           kPbrtQuad,
       20},
  };
  for (const Case& c : cases) {
    Scene s = read_pbrt(dir, c.text);
    s.finalize();
    const auto [flux, error] = flux_through_sphere(s, 400000);
    EXPECT_NEAR(flux, c.watts, 4.5 * error + 1e-4 * c.watts) << c.text << flux << " +- " << error;
    EXPECT_LT(4.5 * error, 0.03 * c.watts) << c.text;  // the bound sees a 3% error
  }
}
