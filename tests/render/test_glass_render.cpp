// Glass and the layered coating in a render: a closed room lit by a ceiling lamp that shines
// through a rough glass slab and a lamp on the back wall, with a smooth glass sphere (smooth
// shading normals), a thin pane and a coated-diffuse block. The lamp is reached through Dirac lobes
// (no light sampling there), through rough transmission (light samples behind the surface, MIS with
// both lobes) and by reflection. Independent estimators must agree: the path integrator's MIS,
// NEE-only and BSDF-only strategies, MIS under two light samplers, and `direct` with MIS against
// NEE only.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include "rll/core/params.h"
#include "rll/scene/builder.h"
#include "rll/scene/interaction.h"
#include "support/power.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;

namespace {

const Scene& glass_room() {
  static const Scene scene = [] {
    Scene s;
    s.width = 40;
    s.height = 40;
    SceneBuilder b(s);
    uint32_t white = b.diffuse(Rgb(0.7f), "white"), red = b.diffuse(Rgb(0.6f, 0.1f, 0.1f), "red");
    uint32_t lamp = b.emitter(Rgb(12, 10, 8), false, "lamp");
    uint32_t back_lamp = b.emitter(Rgb(1, 2, 3), false, "back-lamp");
    Material rough;
    rough.name = "rough-glass";
    rough.type = MaterialType::Dielectric;
    rough.roughness = 0.4f;
    rough.ior = 1.5f;
    Material smooth = rough;
    smooth.name = "glass";
    smooth.roughness = 0;
    Material thin = smooth;
    thin.name = "pane";
    thin.type = MaterialType::ThinDielectric;
    Material coat;
    coat.name = "coated";
    coat.type = MaterialType::CoatedDiffuse;
    coat.albedo = Rgb(0.2f, 0.5f, 0.3f);
    coat.roughness = 0.1f;
    uint32_t m_rough = b.material(rough), m_smooth = b.material(smooth);
    uint32_t m_thin = b.material(thin), m_coat = b.material(coat);
    b.box(Vec3(0, 0, 0), Vec3(1, 1, 1), white, true, 1u << 0);  // the room, -x wall red
    b.box(Vec3(0, 0, 0), Vec3(1, 1, 1), red, true, ~1u & 63u);
    b.quad(Vec3(0.35f, 0.999f, 0.35f), Vec3(0.3f, 0, 0), Vec3(0, 0, 0.3f), lamp);  // faces down
    // A second, dimmer lamp on the back wall, facing +z: seen through the pane and the sphere.
    b.quad(Vec3(0.15f, 0.05f, 0.001f), Vec3(0.3f, 0, 0), Vec3(0, 0.3f, 0), back_lamp);
    b.box(Vec3(0.2f, 0.8f, 0.2f), Vec3(0.8f, 0.85f, 0.8f), m_rough);  // a slab under the lamp
    b.sphere(Vec3(0.3f, 0.2f, 0.55f), 0.18f, 3, m_smooth);
    b.box(Vec3(0.55f, 0, 0.3f), Vec3(0.85f, 0.35f, 0.6f), m_coat);
    b.quad(Vec3(0.1f, 0.05f, 0.8f), Vec3(0.8f, 0, 0), Vec3(0, 0.5f, 0), m_thin);  // facing +z
    s.camera.position = Vec3(0.5f, 0.5f, 0.98f);
    s.camera.target = Vec3(0.5f, 0.4f, 0);
    s.camera.fov = 70;
    s.has_camera = true;
    s.finalize();
    return s;
  }();
  return scene;
}

TEST(GlassRender, StrategiesAndSamplersAgree) {
  const Scene& scene = glass_room();
  const int D = 4;
  Image mis = render_scene(scene, request("power", "path", D, "mis", 512, 1));
  Image tree = render_scene(scene, request("tree", "path", D, "mis", 512, 2));
  // The estimators are heavy-tailed here (light through the rough slab, seen through the pane):
  // at 64 spp the block standard errors miss the tails and regions fell 4.5-5 short now and
  // then; at these counts 10 seeds of 10 passed.
  Image nee = render_scene(scene, request("power", "path", D, "nee", 1024, 3));
  Image bsdf = render_scene(scene, request("power", "path", D, "bsdf", 2048, 4));
  EXPECT_GT(image_mean(mis), 0.02);
  expect_images_agree(mis, tree, "mis power vs tree");
  expect_images_agree(mis, nee, "mis vs nee");
  expect_images_agree(mis, bsdf, "mis vs bsdf");
  expect_images_agree(nee, bsdf, "nee vs bsdf");
  // Power, the smallest bias of the whole image each bound sees both ways (measured 5%, 5.5%, 3%,
  // 4.5%; asserted with a margin):
  expect_bound_sees(mis, tree, "mis power vs tree", 0.07);
  expect_bound_sees(mis, nee, "mis vs nee", 0.07);
  expect_bound_sees(mis, bsdf, "mis vs bsdf", 0.05);
  expect_bound_sees(nee, bsdf, "nee vs bsdf", 0.06);
}

TEST(GlassRender, DirectStrategiesAgree) {
  const Scene& scene = glass_room();
  Image mis = render_scene(scene, request("tree", "direct", 1, "", 128, 5));
  Image nee = render_scene(scene, request("tree", "direct", 1, "nee", 128, 6));
  Image path = render_scene(scene, request("power", "path", 1, "bsdf", 1024, 7));
  expect_images_agree(mis, nee, "direct mis vs nee");
  expect_images_agree(mis, path, "direct mis vs path depth 1 bsdf");
  // Both see 1.5%.
  expect_bound_sees(mis, nee, "direct mis vs nee", 0.05);
  expect_bound_sees(mis, path, "direct mis vs path depth 1 bsdf", 0.05);
}

// roughness_texture: its first channel replaces the material's roughness at the hit, and a
// texture index that was never loaded is a clean error at finalize().
TEST(GlassRender, RoughnessTexture) {
  Scene s;
  SceneBuilder b(s);
  Material m;
  m.type = MaterialType::Dielectric;
  m.roughness = 0.3f;
  m.roughness_texture = 0;
  uint32_t id = b.material(m);
  b.quad(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), id);
  b.quad(Vec3(0, 0, 1), Vec3(1, 0, 0), Vec3(0, 1, 0), b.emitter(Rgb(1)));
  EXPECT_NE(error_of([&] {
              Scene t = s;
              t.finalize();
            }).find("roughness texture"),
            std::string::npos);
  Image tex(2, 1);
  tex.at(0, 0) = Rgb(0.05f, 0.9f, 0.9f);
  tex.at(1, 0) = Rgb(0.05f, 0.9f, 0.9f);
  s.textures.push_back(tex);
  s.finalize();
  SurfaceHit hit;
  hit.material = id;
  hit.uv = {0.3f, 0.6f};
  EXPECT_NEAR(roughness_at(SceneData(s).view(), hit), 0.05f, 1e-6f);
  s.materials[id].roughness_texture = -1;
  EXPECT_EQ(roughness_at(SceneData(s).view(), hit), 0.3f);
}

}  // namespace
