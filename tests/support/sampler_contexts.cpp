#include "support/sampler_contexts.h"

#include "rll/core/params.h"
#include "rll/core/rng.h"
#include "rll/core/sampling.h"
#include "rll/lighttree/light_tree.h"
#include "rll/render/render.h"
#include "rll/scene/builtin.h"
#include "rll/scene/interaction.h"
#include "support/statistics.h"

#include <gtest/gtest.h>

namespace rll::test {

SamplerScene sampler_scene(const std::string& scene_name, const std::string& sampler,
                           const std::vector<std::string>& set) {
  SamplerScene s;
  s.scene = make_builtin_scene(scene_name);
  s.scene.width = 48;
  s.scene.height = 36;
  s.scene.finalize();
  s.tree = std::make_unique<LightTree>(build_light_tree(s.scene));
  s.accel = std::make_unique<Accel>(s.scene.mesh);
  Params params = Params::parse(set);
  s.sampler = make_light_sampler(sampler, s.scene, *s.tree, params, s.accel.get());
  params.check_all_used();
  return s;
}

std::vector<LightContext> make_contexts(const Scene& scene, const Accel& accel, int count,
                                        uint64_t seed) {
  Pcg32 rng(seed);
  std::vector<LightContext> out;
  const Mesh& mesh = scene.mesh;
  std::vector<float> areas(mesh.triangle_count(), 0.0f);
  for (uint32_t t = 0; t < mesh.triangle_count(); ++t) {
    bool sky =
        t >= scene.sky_first_triangle && t < scene.sky_first_triangle + scene.sky_triangle_count;
    if (!sky) areas[t] = mesh.area(t);
  }
  DiscreteDistribution by_area(areas);
  int tries = 0;
  while (int(out.size()) < count / 2 && tries++ < count * 50) {
    float x = rng.next_float() * scene.width, y = rng.next_float() * scene.height;
    Ray ray = scene.camera.generate_ray(x, y);
    Hit hit;
    if (!accel.intersect(ray, hit)) continue;
    SurfaceHit sh = make_surface_hit(scene, hit);
    bool sky = sh.tri >= scene.sky_first_triangle &&
               sh.tri < scene.sky_first_triangle + scene.sky_triangle_count;
    if (sky) continue;
    LightContext c;
    c.p = sh.p;
    c.n = face_forward(sh.ng, -ray.d);
    c.ns = dot(sh.ns, c.n) < 0 ? -sh.ns : sh.ns;
    c.footprint = hit.t * scene.camera.pixel_angle();
    out.push_back(c);
  }
  while (int(out.size()) < count) {
    uint32_t t = uint32_t(by_area.sample(rng.next_double()));
    Vec2 b = sample_uniform_triangle({rng.next_float(), rng.next_float()});
    LightContext c;
    c.p = mesh.vertex(t, 0) * b.x + mesh.vertex(t, 1) * b.y + mesh.vertex(t, 2) * (1 - b.x - b.y);
    c.n = normalize(mesh.face_cross(t));
    if (rng.next_float() < 0.5f) c.n = -c.n;
    c.ns = c.n;
    c.footprint = 0.01f * scene.radius;
    out.push_back(c);
  }
  return out;
}

bool light_can_contribute(const Light& l, const Vec3& p, const Vec3& n) {
  if (luminance(l.radiance) <= 0) return false;
  if (l.type == LightType::Directional) return dot(l.p0, n) > 0;
  if (l.type == LightType::Point) return dot(l.p0 - p, n) > 0;
  if (l.type == LightType::Goniometric) return dot(l.p0 - p, n) > 0;  // images positive here
  if (l.type == LightType::Projection) {
    // Inside the frustum (the tests' projection images have no black texel).
    const Vec3 w = p - l.p0;
    const float z = dot(l.n, w);
    return dot(-w, n) > 0 && z > 1e-3f * length(w) && std::abs(dot(l.p1, w)) < z &&
           std::abs(dot(l.p2, w)) < z;
  }
  if (l.type == LightType::Spot) {
    const Vec3 d = p - l.p0;
    return dot(-d, n) > 0 && length_sq(d) > 0 && spot_falloff(l, normalize(d)) > 0;
  }
  // Some point of the triangle (probe points) above the surface and facing p.
  Pcg32 rng(17);
  for (int i = 0; i < 64; ++i) {
    Vec2 b = i < 3 ? Vec2{i == 0 ? 1.f : 0.f, i == 1 ? 1.f : 0.f}
                   : sample_uniform_triangle({rng.next_float(), rng.next_float()});
    Vec3 y = l.p0 * b.x + l.p1 * b.y + l.p2 * (1 - b.x - b.y);
    Vec3 d = y - p;
    if (dot(d, n) > 1e-6f * length(d) && !is_black(emitted_radiance(l, -normalize(d)))) return true;
  }
  return false;
}

void render_path_passes(const Scene& scene, const Accel& accel, LightSampler& sampler, int spp,
                        PointSet points) {
  IntegratorSettings is;
  is.type = IntegratorType::Path;
  is.max_depth = 3;
  Integrator integrator(scene, accel, sampler, is);
  Film film(scene.width, scene.height);
  RenderSettings rs;
  rs.spp = spp;
  rs.pass_spp = 1;
  rs.points = points;
  render(scene, integrator, sampler, film, rs);
}

void train_sampler(const Scene& scene, const Accel& accel, LightSampler& sampler, int passes,
                   PointSet points) {
  if (sampler.sampler_view().learns) render_path_passes(scene, accel, sampler, passes, points);
}

void expect_sampler_contract(const LightSampler& sampler, const std::vector<LightContext>& contexts,
                             uint32_t n) {
  const SamplerView v = sampler.sampler_view();
  const double alpha = sidak_alpha(0.01, 2 * 4);
  for (size_t c = 0; c < contexts.size(); ++c) {
    const LightContext& ctx = contexts[c];
    for (int k = 0; k < 32; ++k) {
      const SampledLight s = sample_light(v, ctx, SampleStream(99, c, uint64_t(k)).next_double());
      ASSERT_GT(s.pmf, 0);
      ASSERT_EQ(s.pmf, light_pmf(v, ctx, s.light)) << "context " << c << " light " << s.light;
    }
    double sum = 0;
    for (uint32_t l = 0; l < n; ++l) sum += light_pmf(v, ctx, l);
    ASSERT_NEAR(sum, 1.0, 1e-4) << "context " << c;
  }
  for (int c = 0; c < 4; ++c) {
    const LightContext& ctx = contexts[size_t(c) * 23 % contexts.size()];
    const int N = 20000;
    std::vector<double> stratified(n, 0), random(n, 0), expected(n, 0);
    for (int k = 0; k < N; ++k) {
      stratified[sample_light(v, ctx, (k + 0.5) / N).light] += 1;
      random[sample_light(v, ctx, SampleStream(4242, uint64_t(c), uint64_t(k)).next_double())
                 .light] += 1;
    }
    for (uint32_t l = 0; l < n; ++l) {
      const double p = light_pmf(v, ctx, l);
      expected[l] = p * N;
      if (p == 0)
        ASSERT_EQ(stratified[l], 0) << "light " << l << " drawn with pmf 0";
      else
        ASSERT_NEAR(stratified[l] / expected[l], 1.0, 2.0 / expected[l] + 1e-4)
            << "context " << c << " light " << l;
    }
    const ChiSquareResult chi = chi_square(random, expected);
    EXPECT_FALSE(chi.sample_in_zero_bin) << "context " << c;
    EXPECT_GT(chi.p_value, alpha) << "context " << c << ": chi2 " << chi.chi2 << " dof " << chi.dof;
  }
}

}  // namespace rll::test
