// save_json_scene: a saved scene reads back as the same scene (geometry bit for bit, materials,
// textures, lights, sky, camera), and the files it writes are ones a person can read.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "rll/core/error.h"
#include "rll/scene/builtin.h"
#include "rll/io/load.h"
#include "rll/io/save.h"
#include "support/test_support.h"

using namespace rll;
using rll::test::TempDir;

namespace {


void expect_same_material(const Material& a, const Material& b, size_t tri) {
  EXPECT_EQ(a.type, b.type) << "triangle " << tri;
  EXPECT_EQ(a.emission, b.emission) << "triangle " << tri;
  EXPECT_EQ(a.two_sided_emission, b.two_sided_emission) << "triangle " << tri;
  EXPECT_EQ(a.albedo_texture >= 0, b.albedo_texture >= 0) << "triangle " << tri;
  if (a.type != MaterialType::Conductor) {
    EXPECT_EQ(a.albedo, b.albedo) << "triangle " << tri;
  }
  if (a.type != MaterialType::Diffuse) {
    EXPECT_EQ(a.specular, b.specular) << "triangle " << tri;
    EXPECT_EQ(a.roughness, b.roughness) << "triangle " << tri;
  }
  if (a.type == MaterialType::Conductor) {
    EXPECT_EQ(a.eta, b.eta) << "triangle " << tri;
    EXPECT_EQ(a.k, b.k) << "triangle " << tri;
  }
  if (a.type != MaterialType::Diffuse && a.type != MaterialType::Conductor) {
    EXPECT_EQ(a.ior, b.ior) << "triangle " << tri;
  }
  EXPECT_EQ(a.thickness, b.thickness) << "triangle " << tri;
  EXPECT_EQ(a.roughness_texture >= 0, b.roughness_texture >= 0) << "triangle " << tri;
}

// Both scenes finalized: same mesh, materials per triangle, lights, camera and film.
void expect_same_scene(const Scene& a, const Scene& b) {
  ASSERT_EQ(a.mesh.triangle_count(), b.mesh.triangle_count());
  ASSERT_EQ(a.mesh.positions.size(), b.mesh.positions.size());
  EXPECT_EQ(a.sky_first_triangle, b.sky_first_triangle);
  EXPECT_EQ(a.sky_triangle_count, b.sky_triangle_count);
  for (size_t i = 0; i < a.mesh.positions.size(); ++i)
    ASSERT_EQ(a.mesh.positions[i], b.mesh.positions[i]) << i;
  EXPECT_EQ(a.mesh.triangles, b.mesh.triangles);
  ASSERT_EQ(a.mesh.normals.size(), b.mesh.normals.size());
  for (size_t i = 0; i < a.mesh.normals.size(); ++i)
    ASSERT_EQ(a.mesh.normals[i], b.mesh.normals[i]) << i;
  for (size_t t = 0; t < a.mesh.triangle_count(); ++t)
    expect_same_material(a.materials[a.mesh.material[t]], b.materials[b.mesh.material[t]], t);
  ASSERT_EQ(a.lights.size(), b.lights.size());
  for (size_t i = 0; i < a.lights.size(); ++i) {
    EXPECT_EQ(a.lights[i].type, b.lights[i].type) << i;
    EXPECT_EQ(a.lights[i].radiance, b.lights[i].radiance) << i;
    EXPECT_NEAR(length(a.lights[i].p0 - b.lights[i].p0), 0, 1e-6f) << i;
  }
  EXPECT_EQ(a.camera.position, b.camera.position);
  EXPECT_EQ(a.camera.target, b.camera.target);
  EXPECT_EQ(a.camera.up, b.camera.up);
  EXPECT_EQ(a.camera.fov, b.camera.fov);
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  EXPECT_EQ(a.bounds.lo, b.bounds.lo);
  EXPECT_EQ(a.bounds.hi, b.bounds.hi);
}

Scene finalized_builtin(const std::string& name) {
  Scene s = make_builtin_scene(name);
  s.source = "builtin:" + name;
  s.finalize();
  return s;
}

}  // namespace

TEST(SaveJson, BuiltinScenesReadBackAsTheSameScene) {
  for (const char* name : {"cornell-box", "arch-interior", "furnace"}) {
    SCOPED_TRACE(name);
    TempDir dir;
    Scene a = finalized_builtin(name);
    save_json_scene(a, dir / "saved.json");
    Scene b = load_scene((dir / "saved.json").string());
    expect_same_scene(a, b);
    EXPECT_EQ(a.sky.has_value(), b.sky.has_value());
    if (a.sky) {
      EXPECT_EQ(a.sky->triangles, b.sky->triangles);
      EXPECT_EQ(a.sky->radiance, b.sky->radiance);
      EXPECT_EQ(a.sky->up, b.sky->up);
      EXPECT_EQ(a.sky->radius_scale, b.sky->radius_scale);
    }
  }
}

TEST(SaveJson, SkyDomeIsWrittenAsSkyNotAsTriangles) {
  TempDir dir;
  Scene a = finalized_builtin("arch-interior");
  ASSERT_GT(a.sky_triangle_count, 0u);
  save_json_scene(a, dir / "arch.json");
  std::string obj = rll::test::read_text(dir / "arch.obj");
  size_t faces = 0;
  for (size_t p = obj.find("\nf "); p != std::string::npos; p = obj.find("\nf ", p + 1)) ++faces;
  EXPECT_EQ(faces, a.mesh.triangle_count() - a.sky_triangle_count);
  std::string json = rll::test::read_text(dir / "arch.json");
  EXPECT_NE(json.find("\"sky\""), std::string::npos);
  EXPECT_NE(json.find("\"directional\""), std::string::npos);
  EXPECT_EQ(json.find("0.7300000"),
            std::string::npos);  // floats written as their shortest decimals
}

TEST(SaveJson, TexturesUvsAndPointLightsRoundTrip) {
  TempDir src, out;
  Image tex(3, 2);
  for (size_t i = 0; i < tex.pixel_count(); ++i)
    tex[i] = Rgb(0.1f * float(i), 0.5f, 1.0f / float(i + 1));
  write_image(src / "t.exr", tex);
  src.write("m.mtl", "newmtl wood\nKd 0.9 0.8 0.7\nmap_Kd t.exr\nnewmtl lamp\nKe 3 3 3\n");
  src.write(
      "m.obj",
      "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0.25 0.5\nvt 1 0\nvt 1 1\nvn 0 0 1\n"
      "usemtl wood\nf 1/1/1 2/2/1 3/3/1\nusemtl lamp\nf 1 3 4\n");
  auto scene_json = src.write("s.json", R"({"shapes": [{"file": "m.obj"}],
    "materials": {"glow": {"type": "plastic", "emission": [1, 2, 3], "two_sided": true, "roughness": 0.05}},
    "lights": [{"type": "point", "position": [0.5, 0.5, 2], "intensity": [7, 7, 7]}],
    "film": {"width": 20, "height": 10}})");
  Scene a = load_scene(scene_json.string());
  save_json_scene(a, out / "copy.json");
  Scene b = load_scene((out / "copy.json").string());
  expect_same_scene(a, b);
  ASSERT_EQ(b.textures.size(), 1u);
  const Image& t = b.textures[size_t(b.materials[b.mesh.material[0]].albedo_texture)];
  ASSERT_EQ(t.width(), 3);
  ASSERT_EQ(t.height(), 2);
  for (size_t i = 0; i < tex.pixel_count(); ++i) EXPECT_EQ(t[i], tex[i]) << i;
  ASSERT_EQ(b.mesh.uvs.size(), a.mesh.uvs.size());
  for (size_t i = 0; i < a.mesh.uvs.size(); ++i) {
    EXPECT_EQ(a.mesh.uvs[i].x, b.mesh.uvs[i].x);
    EXPECT_EQ(a.mesh.uvs[i].y, b.mesh.uvs[i].y);
  }
  EXPECT_TRUE(std::filesystem::exists(out / "copy_tex0.exr"));
  EXPECT_TRUE(std::filesystem::exists(out / "copy.mtl"));
}

TEST(SaveJson, ThinLensAndScreenWindowRoundTripExactly) {
  TempDir dir;
  Scene a = finalized_builtin("cornell-box");
  a.camera.lens_radius = 0.0123f;
  a.camera.focal_distance = 3.71f;
  a.camera.screen_window = {-0.7f, 0.9f, -0.3f, 1.1f};
  save_json_scene(a, dir / "lens.json");
  Scene b = load_scene((dir / "lens.json").string());
  expect_same_scene(a, b);
  EXPECT_EQ(b.camera.lens_radius, a.camera.lens_radius);
  EXPECT_EQ(b.camera.focal_distance, a.camera.focal_distance);
  EXPECT_EQ(b.camera.screen_window, a.camera.screen_window);
  // A pinhole seeing the whole image writes none of them.
  Scene pin = finalized_builtin("cornell-box");
  save_json_scene(pin, dir / "pin.json");
  const std::string text = rll::test::read_text(dir / "pin.json");
  for (const char* field : {"lens_radius", "focal_distance", "screen_window"})
    EXPECT_EQ(text.find(field), std::string::npos) << field;
  EXPECT_FALSE(load_scene((dir / "pin.json").string()).camera.has_lens());
}

TEST(SaveJson, RejectsANameThatIsNotJson) {
  TempDir dir;
  Scene a = finalized_builtin("cornell-box");
  try {
    save_json_scene(a, dir / "scene.obj");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("scene.obj"), std::string::npos);
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "scene.obj"));
}
