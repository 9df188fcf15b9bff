// The hot functions of scene/ and core/ on the GPU against the CPU (issue 31): the same probe
// (rll/cuda/onesource_check.h: surface data, textures, BSDF eval/pdf/sample of every material
// type, sample_li/pdf_li, emission, solid angle) run by both must agree within float rounding.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "rll/core/image.h"
#include "rll/cuda/onesource_check.h"

namespace rll {
namespace {

// A scene of one quad per material (every type, a textured albedo, a roughness texture) and
// lights of every kind, as flat arrays.
struct ProbeScene {
  Mesh mesh;
  std::vector<MaterialData> materials;
  std::vector<Image> images;
  std::vector<TexelView> textures;
  std::vector<Light> lights;

  ProbeScene() {
    Pcg32 rng(7);
    auto add_material = [&](MaterialType type, float roughness) {
      MaterialData m;
      m.type = type;
      m.roughness = roughness;
      m.albedo = Rgb(0.2f + 0.6f * rng.next_float(), 0.5f, 0.2f + 0.6f * rng.next_float());
      materials.push_back(m);
    };
    add_material(MaterialType::Diffuse, 0.3f);
    add_material(MaterialType::Conductor, 0.2f);
    add_material(MaterialType::Plastic, 0.1f);
    add_material(MaterialType::Dielectric, 0);     // smooth glass
    add_material(MaterialType::Dielectric, 0.3f);  // rough glass
    add_material(MaterialType::ThinDielectric, 0);
    add_material(MaterialType::CoatedDiffuse, 0);  // smooth coating
    add_material(MaterialType::CoatedDiffuse, 0.2f);
    add_material(MaterialType::Diffuse, 0.3f);
    materials.back().albedo_texture = 0;
    add_material(MaterialType::Conductor, 0.3f);
    materials.back().roughness_texture = 1;
    for (int t = 0; t < 2; ++t) {
      Image image(5 + t, 3 + 2 * t);
      for (Rgb& c : image.pixels()) c = Rgb(rng.next_float(), rng.next_float(), rng.next_float());
      images.push_back(std::move(image));
    }
    for (const Image& image : images) textures.push_back(image.texel_view());
    for (uint32_t m = 0; m < materials.size(); ++m) {
      // A tilted quad at x = 2m, with shading normals bent away from the face and uvs past 1.
      const uint32_t v = uint32_t(mesh.positions.size());
      const float x = 2.0f * float(m);
      for (int k = 0; k < 4; ++k) {
        const float a = float(k & 1), b = float(k >> 1);
        mesh.positions.push_back({x + a, b, 0.3f * a * b});
        mesh.normals.push_back(normalize(Vec3(0.2f * a - 0.1f, 0.1f * b, 1)));
        mesh.uvs.push_back({1.7f * a - 0.2f, 2.3f * b});
      }
      mesh.triangles.push_back({v, v + 1, v + 3});
      mesh.triangles.push_back({v, v + 3, v + 2});
      mesh.material.insert(mesh.material.end(), 2, m);
      mesh.light.insert(mesh.light.end(), 2, -1);
    }
    // Near triangles (sampled by solid angle), a far small one (by area), a point and a sun.
    lights.push_back(
        make_triangle_light({0, 0, 2}, {12, 0, 2.5f}, {6, 3, 2}, Rgb(4, 3, 2), false, 0));
    lights.push_back(
        make_triangle_light({5, 2, 1}, {5.5f, 2, 1.2f}, {5, 2.5f, 1}, Rgb(9), true, 1));
    lights.push_back(
        make_triangle_light({0, 40, 30}, {1, 40, 30}, {0, 41, 30}, Rgb(20, 10, 5), false, 2));
    lights.push_back(make_point_light({3, 1, 2}, Rgb(5)));
    lights.push_back(make_directional_light({0.3f, 0.2f, 1}, Rgb(2)));
  }

  SceneView view() const {
    return {mesh.view(), view_of(materials), view_of(textures), view_of(lights)};
  }
};

// Equal within float rounding: the GPU fuses multiplies and adds and has its own sin, cos, acos.
// GGX at low roughness amplifies those roundings (seen on an H100: a sampled pdf of 49.858 on
// the CPU and 49.847 on the GPU, 2.2e-4 apart), so 1e-3 relative; a wrong formula is off by O(1).
bool close(float a, float b) {
  if (a == b) return true;
  if (!std::isfinite(a) || !std::isfinite(b)) return false;
  return std::abs(a - b) <= 1e-3f * std::max({1.0f, std::abs(a), std::abs(b)});
}
bool close(const Vec3& a, const Vec3& b) {
  return close(a.x, b.x) && close(a.y, b.y) && close(a.z, b.z);
}

TEST(GpuOneSource, ProbesMatchTheCpu) {
  ProbeScene scene;
  const SceneView view = scene.view();
  std::vector<Hit> hits;
  Pcg32 rng(11);
  // 20,000 probes over every material, then 100,000 more on the two coated quads (triangles 12
  // to 15), whose walks are compared by their means (below).
  for (uint32_t i = 0; i < 120000; ++i) {
    Hit h;
    h.tri = i < 20000 ? i % uint32_t(scene.mesh.triangles.size()) : 12 + i % 4;
    h.u = rng.next_float();
    h.v = rng.next_float() * (1 - h.u);
    h.t = 1;
    hits.push_back(h);
  }
  std::vector<OneSourceResult> gpu;
  try {
    gpu = onesource_probe_gpu(view, hits);
  } catch (const std::runtime_error& e) {
    if (std::string(e.what()).find("no CUDA-capable device") != std::string::npos)
      GTEST_SKIP() << e.what();
    throw;
  }
  ASSERT_EQ(gpu.size(), hits.size());
  size_t sampled = 0, lit = 0, walk_mismatches = 0;
  // The layered model's estimates on either device, compared as distributions (below).
  // Both devices draw the same directions, so their estimates are compared in pairs: the mean
  // of the differences (the walks' noise) against its standard error, and against the mean of
  // the CPU's estimates (which a 5% bias would shift by 5%).
  struct Paired {
    double n = 0, sum_a = 0, sum_d = 0, sum_d2 = 0;
    void add(double a, double b) {
      n += 1, sum_a += a, sum_d += a - b, sum_d2 += (a - b) * (a - b);
    }
    double mean_a() const { return sum_a / n; }
    double mean_d() const { return sum_d / n; }
    double standard_error() const {
      return std::sqrt((sum_d2 / n - mean_d() * mean_d()) / (n - 1));
    }
  };
  Paired f_pair, pdf_pair, weight_pair;
  for (size_t i = 0; i < hits.size(); ++i) {
    const OneSourceResult c = onesource_probe(view, hits[i], i), &g = gpu[i];
    const MaterialData& m = scene.materials[scene.mesh.material[hits[i].tri]];
    SCOPED_TRACE("probe " + std::to_string(i) + ", material " + std::to_string(hits[i].tri / 2));
    ASSERT_TRUE(close(c.p, g.p) && close(c.ns, g.ns));
    ASSERT_TRUE(close(c.albedo, g.albedo) && close(c.roughness, g.roughness));
    ASSERT_TRUE(close(c.li, g.li) && close(c.li_pdf, g.li_pdf) && close(c.pdf_li, g.pdf_li));
    ASSERT_TRUE(close(c.le, g.le) && close(c.solid_angle, g.solid_angle));
    lit += c.li_pdf > 0;
    const bool bsdf_equal = close(c.f, g.f) && close(c.pdf, g.pdf) && c.sampled == g.sampled &&
                            close(c.wi, g.wi) && close(c.f_sampled, g.f_sampled) &&
                            close(c.pdf_sampled, g.pdf_sampled);
    sampled += c.sampled;
    if (m.type == MaterialType::CoatedDiffuse) {
      // The layered model's random walks (eval, sample and the pdf estimate alike) are seeded by
      // the bits of the directions, and a rounding difference in a direction (the GPU fuses
      // multiplies and adds) starts another walk: on an H100 2205 of 4000 probes differed. Each
      // device's walks are unbiased estimates of the same functions, so their means must agree.
      walk_mismatches += !bsdf_equal;
      f_pair.add(luminance(c.f), luminance(g.f));
      pdf_pair.add(c.pdf, g.pdf);
      weight_pair.add(c.sampled ? luminance(c.f_sampled) / c.pdf_sampled : 0,
                      g.sampled ? luminance(g.f_sampled) / g.pdf_sampled : 0);
    } else {
      ASSERT_TRUE(bsdf_equal) << c.f.x << " " << g.f.x << " " << c.pdf << " " << g.pdf << " "
                              << c.pdf_sampled << " " << g.pdf_sampled;
    }
  }
  EXPECT_GT(sampled, hits.size() / 2);
  EXPECT_GT(lit, hits.size() / 4);
  // Means within 4 standard errors of their difference; the bound must be tight enough to see a
  // 5% bias of either device, or the comparison says nothing.
  for (const auto& [name, pair] :
       {std::pair{"f", f_pair}, {"pdf", pdf_pair}, {"sample weight", weight_pair}}) {
    const double bound = 4 * pair.standard_error();
    EXPECT_LE(std::abs(pair.mean_d()), bound)
        << name << ": CPU mean " << pair.mean_a() << ", GPU mean " << pair.mean_a() - pair.mean_d()
        << " over " << pair.n << " walks (" << walk_mismatches << " differ)";
    EXPECT_LT(bound, 0.05 * pair.mean_a()) << name << ": the bound would not see a 5% bias";
  }
}

}  // namespace
}  // namespace rll
