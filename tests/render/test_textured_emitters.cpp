// Textured emitters as the renderer sees them: the irradiance a point receives from a textured
// emissive plane (the integral of the texture times the geometry, by fine quadrature) estimated
// by light sampling (the pieces' power pmf times sample_li's pdf) and by cosine-sampled rays
// that find the emission at their hits, each within its confidence bound; and a render of the
// emitter itself, which shows the texture's picture.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "rll/accel/accel.h"
#include "rll/core/rng.h"
#include "rll/core/sampling.h"
#include "rll/scene/builder.h"
#include "rll/scene/interaction.h"
#include "rll/scene/scene_view.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;

namespace {

// A 2 x 2 quad at z = 0 facing +z, emitting factor x a random 16 x 12 texture.
Scene textured_plane(const Rgb& factor) {
  Scene s;
  s.source = "test";
  SceneBuilder b(s);
  Image tex(16, 12);
  Pcg32 rng(41);
  for (size_t i = 0; i < tex.pixel_count(); ++i)
    tex[i] = Rgb(rng.next_float(), rng.next_float() * rng.next_float(), 0.2f);
  s.textures.push_back(tex);
  Material m;
  m.name = "screen";
  m.emission = factor;
  m.emission_texture = 0;
  b.quad(Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 2, 0), b.material(m));
  s.mesh.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  s.camera.position = Vec3(1, 1, 1);
  s.camera.target = Vec3(1, 1, 0);
  s.camera.fov = 40;
  s.has_camera = true;
  s.width = s.height = 32;
  return s;
}

struct Mean {
  double sum = 0, sum2 = 0;
  long n = 0;
  void add(double v) {
    sum += v;
    sum2 += v * v;
    ++n;
  }
  double mean() const { return sum / double(n); }
  double stderr_() const { return std::sqrt(std::max(0.0, sum2 / double(n) - mean() * mean()) / double(n)); }
};

}  // namespace

TEST(TexturedEmitterRender, IrradianceFromAPlaneIsTheIntegralOfItsTexture) {
  const Rgb factor(3, 2, 1);
  Scene s = textured_plane(factor);
  s.finalize();
  ASSERT_GT(s.lights.size(), 50u);  // split into pieces
  SceneData data(s);
  const SceneView& v = data.view();
  const Vec3 p(0.7f, 1.2f, 0.6f), n(0, 0, -1);
  // The reference: luminance irradiance by a 1500^2 midpoint rule over the plane (the lookup
  // times cos_p cos_x / d^2).
  double reference = 0;
  {
    const int g = 1500;
    const double h = 2.0 / g;
    for (int i = 0; i < g; ++i)
      for (int j = 0; j < g; ++j) {
        const double x = (i + 0.5) * h, y = (j + 0.5) * h;
        const double dx = x - p.x, dy = y - p.y, dz = -double(p.z), d2 = dx * dx + dy * dy + dz * dz;
        const double c = double(p.z) / std::sqrt(d2);  // both cosines
        const Rgb L = factor * sample_texture(s.textures[0], Vec2{float(x / 2), float(y / 2)});
        reference += double(luminance(L)) * c * c / d2 * h * h;
      }
  }
  // Light sampling: a piece by its power, a point on it by sample_li.
  std::vector<double> cdf;
  double total = 0;
  for (const Light& l : s.lights) cdf.push_back(total += light_power(l, s.radius));
  Pcg32 rng(43);
  Mean nee, bsdf;
  for (int k = 0; k < 800000; ++k) {
    const double u = rng.next_double() * total;
    const size_t i = std::min(size_t(std::upper_bound(cdf.begin(), cdf.end(), u) - cdf.begin()),
                              cdf.size() - 1);
    const double pmf = double(light_power(s.lights[i], s.radius)) / total;
    const LightLiSample ls = sample_li(v, s.lights[i], p, Vec2{rng.next_float(), rng.next_float()});
    const float c = dot(ls.wi, n);
    nee.add(ls.pdf > 0 && c > 0 ? double(luminance(ls.L)) * c / (ls.pdf * pmf) : 0.0);
  }
  // Cosine-sampled rays from p: pi times the emission they hit.
  Accel accel(s.mesh);
  const Frame frame(n);
  for (int k = 0; k < 200000; ++k) {
    const Vec3 d = frame.to_world(sample_cosine_hemisphere(Vec2{rng.next_float(), rng.next_float()}));
    Ray ray;
    ray.o = p;
    ray.d = d;
    Hit hit;
    double value = 0;
    if (accel.intersect(ray, hit)) {
      const SurfaceHit sh = make_surface_hit(v.mesh, hit);
      if (sh.light >= 0) value = kPi * double(luminance(emitted_radiance(v, v.lights[sh.light], sh, -d)));
    }
    bsdf.add(value);
  }
  EXPECT_NEAR(nee.mean(), reference, 4.5 * nee.stderr_() + 1e-4 * reference)
      << "light sampling: " << nee.mean() << " +- " << nee.stderr_() << " vs " << reference;
  EXPECT_NEAR(bsdf.mean(), reference, 4.5 * bsdf.stderr_() + 1e-4 * reference)
      << "cosine rays: " << bsdf.mean() << " +- " << bsdf.stderr_() << " vs " << reference;
  // The bounds are tight enough to see a 1% error.
  EXPECT_LT(4.5 * nee.stderr_(), 0.01 * reference);
  EXPECT_LT(4.5 * bsdf.stderr_(), 0.01 * reference);
}

TEST(TexturedEmitterRender, RenderOfTheEmitterShowsItsPicture) {
  const Rgb factor(3, 2, 1);
  Scene s = textured_plane(factor);
  s.finalize();
  RenderRequest r;
  r.sampler = "tree";
  r.integrator.type = IntegratorType::Direct;
  r.spp = 16;
  const Image img = render_scene(s, r);
  // Each pixel against the texture at the uv its centre sees (the camera looks straight down at
  // the plane; the pixel's mean of a bilinear picture is close to its centre's value).
  double max_error = 0, max_value = 0;
  for (int y = 0; y < s.height; ++y)
    for (int x = 0; x < s.width; ++x) {
      const Ray ray = s.camera.generate_ray(x + 0.5f, y + 0.5f);
      const float t = -ray.o.z / ray.d.z;
      const Vec3 q = ray.o + ray.d * t;
      const Rgb expected = factor * sample_texture(s.textures[0], Vec2{q.x / 2, q.y / 2});
      for (int c = 0; c < 3; ++c) {
        max_error = std::max(max_error, double(std::abs(img.at(x, y)[c] - expected[c])));
        max_value = std::max(max_value, double(expected[c]));
      }
    }
  EXPECT_LT(max_error, 0.04 * max_value) << "largest pixel error " << max_error;
}
