// Scene file loaders: JSON scenes and Wavefront OBJ/MTL read the right geometry, materials and
// camera, and every malformed input is an rll::Error naming the file and the line or field.
#include <gtest/gtest.h>

#include <cmath>

#include "rll/core/error.h"
#include "rll/io/load.h"
#include "support/test_support.h"

using namespace rll;
using rll::test::error_of;
using rll::test::expect_mentions;
using rll::test::TempDir;

namespace {

Scene read_obj(const TempDir& dir, const std::string& obj, const std::string& name = "m.obj") {
  Scene s;
  load_obj(dir.write(name, obj), s);
  return s;
}

Scene read_json(const TempDir& dir, const std::string& text) {
  Scene s;
  load_json_scene(dir.write("scene.json", text), s);
  return s;
}

std::string obj_error(const TempDir& dir, const std::string& obj) {
  return error_of([&] { read_obj(dir, obj); });
}

std::string json_error(const TempDir& dir, const std::string& text) {
  return error_of([&] { read_json(dir, text); });
}

const char* kQuadObj =
    "v 0 0 0\n"
    "v 1 0 0\n"
    "v 1 1 0\n"
    "v 0 1 0\n";

}  // namespace

// ---------------------------------------------------------------------------------------------
// Mesh::append, which every loader goes through

TEST(MeshAppend, KeepsPerVertexArraysEmptyOrFull) {
  auto tri = [](bool normals, bool uvs) {
    Mesh m;
    m.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
    if (normals) m.normals.assign(3, Vec3(0, 0, 1));
    if (uvs) m.uvs.assign(3, Vec2{0.5f, 0.5f});
    m.triangles = {{0, 1, 2}};
    m.material = {0};
    m.light = {-1};
    return m;
  };
  Mesh a = tri(false, false);
  a.append(tri(false, false), 0);
  EXPECT_TRUE(a.normals.empty());  // no uvs anywhere must stay no uvs (barycentric fallback)
  EXPECT_TRUE(a.uvs.empty());
  a.append(tri(true, true), 0);
  ASSERT_EQ(a.normals.size(), 9u);
  ASSERT_EQ(a.uvs.size(), 9u);
  EXPECT_EQ(a.normals[0], Vec3(0));
  EXPECT_EQ(a.normals[8], Vec3(0, 0, 1));
  a.append(tri(false, false), 0);
  EXPECT_EQ(a.normals.size(), 12u);
  EXPECT_EQ(a.uvs.size(), 12u);
  EXPECT_EQ(a.triangles[3][0], 9u);
}

// ---------------------------------------------------------------------------------------------
// OBJ / MTL

TEST(ObjLoader, TriangulatesPolygonsAndKeepsCounts) {
  TempDir dir;
  Scene s = read_obj(dir, std::string(kQuadObj) + "v 0.5 1.5 0\nf 1 2 3 4\nf 1 2 3 5 4\n");
  EXPECT_EQ(s.mesh.triangle_count(), 2u + 3u);
  EXPECT_EQ(s.mesh.positions.size(), 5u);
  EXPECT_TRUE(s.mesh.normals.empty());
  EXPECT_TRUE(s.mesh.uvs.empty());
  ASSERT_EQ(s.materials.size(), 1u);  // the default material for faces without usemtl
  EXPECT_EQ(s.materials[0].type, MaterialType::Diffuse);
  for (auto m : s.mesh.material) EXPECT_EQ(m, 0u);
  EXPECT_NEAR(s.mesh.area(0) + s.mesh.area(1), 1.0f, 1e-6f);
}

TEST(ObjLoader, SplitsVerticesWithDifferentNormalsOrUvs) {
  TempDir dir;
  // Two quads share the edge 2-3 in position but not in normal; vt only on the first.
  std::string obj = std::string(kQuadObj) +
                    "v 2 0 0\nv 2 1 0\n"
                    "vn 0 0 1\nvn 0 0.6 0.8\n"
                    "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                    "f 1/1/1 2/2/1 3/3/1 4/4/1\n"
                    "f 2//2 5//2 6//2 3//2\n";
  Scene s = read_obj(dir, obj);
  ASSERT_EQ(s.mesh.triangle_count(), 4u);
  EXPECT_EQ(s.mesh.positions.size(), 8u);  // 4, then 2 positions again with the other normal, 2 new
  ASSERT_EQ(s.mesh.normals.size(), 8u);
  ASSERT_EQ(s.mesh.uvs.size(), 8u);
  for (uint32_t t = 0; t < 4; ++t)
    for (uint32_t v : s.mesh.triangles[t]) {
      const Vec3& p = s.mesh.positions[v];
      if (t < 2) {
        EXPECT_EQ(s.mesh.normals[v], Vec3(0, 0, 1));
        EXPECT_EQ(s.mesh.uvs[v].x, p.x);  // the first quad's vt equal its x, y
        EXPECT_EQ(s.mesh.uvs[v].y, p.y);
      } else {
        EXPECT_EQ(s.mesh.normals[v], Vec3(0, 0.6f, 0.8f));
        EXPECT_EQ(s.mesh.uvs[v].x, 0.0f);  // no vt on the second quad
      }
    }
}

TEST(ObjLoader, RelativeIndicesCountBackFromTheLastVertex) {
  TempDir dir;
  Scene s = read_obj(dir, std::string(kQuadObj) + "f -4 -3 -2\n");
  ASSERT_EQ(s.mesh.triangle_count(), 1u);
  EXPECT_EQ(s.mesh.vertex(0, 0), Vec3(0, 0, 0));
  EXPECT_EQ(s.mesh.vertex(0, 2), Vec3(1, 1, 0));
}

TEST(ObjLoader, AcceptsCommentsAfterValues) {
  TempDir dir;
  Scene s = read_obj(dir, "# a triangle\nv 0 0 0 # origin\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  EXPECT_EQ(s.mesh.positions.size(), 3u);
}

TEST(ObjLoader, HandlesCrLfAndCrLineEndings) {
  TempDir dir;
  Scene s = read_obj(dir, "v 0 0 0\r\nv 1 0 0\rv 0 1 0\r\nf 1 2 3\r\n");
  EXPECT_EQ(s.mesh.triangle_count(), 1u);
  std::string msg = obj_error(dir, "v 0 0 0\r\nv 1 0 0\rv 0 nan 0\r\nf 1 2 3\r\n");
  expect_mentions(msg, {"m.obj:3:"});
}

TEST(ObjLoader, MapsMtlStatementsToMaterials) {
  TempDir dir;
  dir.write("m.mtl",
            "newmtl matte\nKd 0.5\n\n"
            "newmtl shiny\nKd 0.2 0.3 0.4\nKs 0.04 0.04 0.04\nNs 198\nNi 1.4\n\n"
            "newmtl metal\nKd 0 0 0\nKs 0.9 0.8 0.7\nNs 48\n\n"
            "newmtl mirror\nKd 0.5 0.5 0.5\nKs 1 1 1\nillum 3\n\n"
            "newmtl lamp\nKd 0 0 0\nKe 4 5 6\n");
  std::string obj = "mtllib m.mtl\n" + std::string(kQuadObj) +
                    "usemtl matte\nf 1 2 3\nusemtl shiny\nf 1 3 4\nusemtl metal\nf 1 2 4\n"
                    "usemtl mirror\nf 2 3 4\nusemtl lamp\nf 1 2 3 4\n";
  Scene s = read_obj(dir, obj);
  ASSERT_EQ(s.materials.size(), 5u);
  auto mat = [&](size_t tri) { return s.materials[s.mesh.material[tri]]; };
  EXPECT_EQ(mat(0).name, "matte");
  EXPECT_EQ(mat(0).type, MaterialType::Diffuse);
  EXPECT_EQ(mat(0).albedo, Rgb(0.5f));  // one value means grey
  EXPECT_EQ(mat(1).type, MaterialType::Plastic);
  EXPECT_EQ(mat(1).albedo, Rgb(0.2f, 0.3f, 0.4f));
  EXPECT_EQ(mat(1).specular, Rgb(0.04f));
  EXPECT_NEAR(mat(1).roughness, 0.1f, 1e-6f);  // sqrt(2 / (198 + 2))
  EXPECT_FLOAT_EQ(mat(1).ior, 1.4f);
  EXPECT_EQ(mat(2).type, MaterialType::Conductor);
  EXPECT_EQ(mat(2).specular, Rgb(0.9f, 0.8f, 0.7f));
  EXPECT_NEAR(mat(2).roughness, 0.2f, 1e-6f);  // sqrt(2 / 50)
  EXPECT_EQ(mat(3).type, MaterialType::Conductor);
  EXPECT_EQ(mat(4).emission, Rgb(4, 5, 6));
  EXPECT_FALSE(mat(0).is_emissive());
  s.finalize();
  EXPECT_EQ(s.lights.size(), 2u);  // the lamp quad's two triangles
}

TEST(ObjLoader, LoadsDiffuseTexturesRelativeToTheMtl) {
  TempDir dir;
  Image tex(2, 2, Rgb(0.25f));
  std::filesystem::create_directories(dir / "mat" / "tex");
  write_image(dir / "mat" / "tex" / "t.exr", tex);
  dir.write("mat/m.mtl", "newmtl wood\nmap_Kd tex/t.exr\n");
  Scene s = read_obj(
      dir, "mtllib mat/m.mtl\n" + std::string(kQuadObj) + "vt 0 0\nusemtl wood\nf 1/1 2/1 3/1\n");
  ASSERT_EQ(s.textures.size(), 1u);
  EXPECT_EQ(s.textures[0].width(), 2);
  EXPECT_EQ(s.materials[s.mesh.material[0]].albedo_texture, 0);
  EXPECT_EQ(s.materials[s.mesh.material[0]].albedo, Rgb(1));  // no Kd: the texture alone
}

TEST(ObjLoader, BareObjGetsAFittedCameraButNeedsLights) {
  TempDir dir;
  dir.write("lamp.mtl", "newmtl lamp\nKe 1 1 1\n");
  auto lit = dir.write("lit.obj",
                       "mtllib lamp.mtl\n" + std::string(kQuadObj) + "usemtl lamp\nf 1 2 3 4\n");
  Scene s = load_scene(lit.string());
  EXPECT_TRUE(s.has_camera);
  EXPECT_EQ(s.camera.target, Vec3(0.5f, 0.5f, 0));
  EXPECT_EQ(s.lights.size(), 2u);

  auto dark = dir.write("dark.obj", std::string(kQuadObj) + "f 1 2 3 4\n");
  expect_mentions(error_of([&] { load_scene(dark.string()); }), {"dark.obj", "no lights"});
}

TEST(ObjLoader, NonFiniteOrMalformedNumbersNameTheLine) {
  TempDir dir;
  expect_mentions(obj_error(dir, "v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n"),
                  {"m.obj:3:", "'nan'", "finite"});
  expect_mentions(obj_error(dir, "v 0 0 0\nv 1 0 inf\nv 0 1 0\nf 1 2 3\n"), {"m.obj:2:", "'inf'"});
  expect_mentions(obj_error(dir, "# big\nv 1e39 0 0\n"), {"m.obj:2:", "finite"});
  expect_mentions(obj_error(dir, "v 0 0 0\nv 1 zero 0\n"), {"m.obj:2:", "'zero'", "not a number"});
  expect_mentions(obj_error(dir, "v 0 0\n"), {"m.obj:1:", "3 coordinates"});
  expect_mentions(obj_error(dir, "v 0 0 0\nvn 0 nan 1\n"), {"m.obj:2:", "normal"});
  expect_mentions(obj_error(dir, "v 0 0 0\nvt x\n"), {"m.obj:2:", "texture coordinate"});
  // A tiny value underflows to zero, as in any parser: not an error.
  Scene s = read_obj(dir, "v 1e-50 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  EXPECT_EQ(s.mesh.positions[0].x, 0.0f);
}

TEST(ObjLoader, BadFaceIndicesNameTheLine) {
  TempDir dir;
  const std::string v = kQuadObj;  // lines 1-4
  expect_mentions(obj_error(dir, v + "f 1 2 3\nf 1 2 9\nf 2 3 4\n"),
                  {"m.obj:6:", "vertex index 9", "has 4"});
  expect_mentions(obj_error(dir, v + "f 1 2 0\n"), {"m.obj:5:", "index 0"});
  expect_mentions(obj_error(dir, v + "f -5 1 2\n"), {"m.obj:5:", "-5"});
  expect_mentions(obj_error(dir, v + "vt 0 0\nf 1/1 2/2 3/1\n"),
                  {"m.obj:6:", "texture coordinate index 2"});
  expect_mentions(obj_error(dir, v + "f 1//1 2//1 3//1\n"), {"m.obj:5:", "normal index 1"});
  expect_mentions(obj_error(dir, v + "f 1 2\n"), {"m.obj:5:", "at least 3"});
  expect_mentions(obj_error(dir, v + "f 1 2 x\n"), {"m.obj:5:", "'x'"});
  expect_mentions(obj_error(dir, v + "f 1/1/1/1 2 3\n"), {"m.obj:5:"});
  // A slash and nothing after it: tinyobjloader would take the next vertex's 4 as its texture
  // coordinate, past the only one (the fuzzer's heap overflow).
  expect_mentions(obj_error(dir, v + "vt 0 0\nf 1/ 4/1 2/1\n"),
                  {"m.obj:6:", "malformed face vertex '1/'"});
  expect_mentions(obj_error(dir, v), {"m.obj", "no faces"});
}

TEST(ObjLoader, MissingOrBadMaterialFilesNameThem) {
  TempDir dir;
  const std::string v = kQuadObj;
  expect_mentions(obj_error(dir, "mtllib gone.mtl\n" + v + "f 1 2 3\n"),
                  {"m.obj:1:", "gone.mtl", "not found"});

  dir.write("a.mtl", "newmtl red\nKd 1 0 0\n");
  expect_mentions(obj_error(dir, "mtllib a.mtl\n" + v + "usemtl blue\nf 1 2 3\n"),
                  {"m.obj:6:", "'blue'", "a.mtl"});
  expect_mentions(obj_error(dir, v + "usemtl red\nf 1 2 3\n"), {"m.obj:5:", "'red'"});

  dir.write("t.mtl", "newmtl red\nKd 1 0 0\nmap_Kd missing.png\n");
  expect_mentions(obj_error(dir, "mtllib t.mtl\n" + v + "usemtl red\nf 1 2 3\n"),
                  {"t.mtl", "missing.png", "red"});

  dir.write("bad.png", "this is not a PNG");
  dir.write("b.mtl", "newmtl red\nmap_Kd bad.png\n");
  expect_mentions(obj_error(dir, "mtllib b.mtl\n" + v + "usemtl red\nf 1 2 3\n"),
                  {"b.mtl", "bad.png"});

  dir.write("n.mtl", "newmtl red\n\nKd 1 nan 0\n");
  expect_mentions(obj_error(dir, "mtllib n.mtl\n" + v + "f 1 2 3\n"), {"n.mtl:3:", "Kd"});
  dir.write("k.mtl", "newmtl red\nKe -1 0 0\n");
  expect_mentions(obj_error(dir, "mtllib k.mtl\n" + v + "f 1 2 3\n"), {"k.mtl:2:", "negative"});
  dir.write("s.mtl", "newmtl red\nKd spectral red.rfl\n");
  expect_mentions(obj_error(dir, "mtllib s.mtl\n" + v + "f 1 2 3\n"), {"s.mtl:2:", "spectral"});
}

TEST(ObjLoader, NonFiniteVertexThroughLoadSceneNamesFileAndLine) {
  TempDir dir;
  auto p = dir.write("nan.obj", "v 0 0 0\nv 1 0 0\nv 0 1 nan\nf 1 2 3\n");
  expect_mentions(error_of([&] { load_scene(p.string()); }), {"nan.obj:3:"});
}

// ---------------------------------------------------------------------------------------------
// JSON

namespace {
const char* kLamp = R"("materials": {"lamp": {"emission": [5, 5, 5], "albedo": [0, 0, 0]}})";
}

TEST(JsonLoader, ReadsCameraFilmPrimitivesLightsAndSky) {
  TempDir dir;
  Scene s = read_json(dir, std::string("{") + kLamp + R"(,
    "camera": {"position": [0, 1, 5], "target": [0, 1, 0], "up": [0, 1, 0], "fov": 50},
    "film": {"width": 40, "height": 30},
    "shapes": [
      {"type": "quad", "origin": [0, 2, 0], "edge1": [1, 0, 0], "edge2": [0, 0, 1], "material": "lamp"},
      {"type": "box", "min": [-1, 0, -1], "max": [1, 2, 1], "inward": true, "skip": ["+z"]},
      {"type": "sphere", "center": [0, 0.5, 0], "radius": 0.5, "subdivisions": 1,
       "material": {"type": "plastic", "albedo": [0.5, 0.1, 0.1], "roughness": 0.2, "ior": 1.6}},
      {"type": "triangle", "vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0]],
       "material": {"type": "conductor", "eta": [0.2, 0.9, 1.1], "k": [3.9, 2.4, 2.1], "roughness": 0.1}}
    ],
    "lights": [{"type": "directional", "direction": [0, 2, 0], "irradiance": [1, 2, 3]},
               {"type": "point", "position": [0, 1.5, 0], "intensity": [4, 4, 4]}],
    "sky": {"type": "dome", "triangles": 64, "radiance": [0.5, 0.6, 0.7], "up": [0, 0, 1], "radius_scale": 10}
  })");
  EXPECT_TRUE(s.has_camera);
  EXPECT_EQ(s.camera.position, Vec3(0, 1, 5));
  EXPECT_EQ(s.camera.fov, 50.0f);
  EXPECT_EQ(s.width, 40);
  EXPECT_EQ(s.height, 30);
  EXPECT_EQ(s.mesh.triangle_count(), 2u + 10u + 80u + 1u);
  // lamp, default (box), inline plastic, inline conductor
  ASSERT_EQ(s.materials.size(), 4u);
  EXPECT_EQ(s.materials[s.mesh.material[0]].emission, Rgb(5));
  EXPECT_EQ(s.materials[s.mesh.material[2]].name, "default");
  const Material& plastic = s.materials[s.mesh.material[12]];
  EXPECT_EQ(plastic.type, MaterialType::Plastic);
  EXPECT_FLOAT_EQ(plastic.ior, 1.6f);
  EXPECT_EQ(s.materials[s.mesh.material.back()].type, MaterialType::Conductor);
  ASSERT_EQ(s.lights.size(), 2u);
  EXPECT_EQ(s.lights[0].type, LightType::Directional);
  EXPECT_EQ(s.lights[0].p0, Vec3(0, 1, 0));  // normalized
  EXPECT_EQ(s.lights[1].radiance, Rgb(4));
  ASSERT_TRUE(s.sky.has_value());
  EXPECT_EQ(s.sky->triangles, 64);
  EXPECT_EQ(s.sky->up, Vec3(0, 0, 1));
  s.finalize();
  EXPECT_EQ(s.sky_triangle_count, 64u);
  EXPECT_EQ(s.lights.size(), 2u + 2u + 64u);  // delta lights, the lamp quad, the sky
}

TEST(JsonLoader, ReadsTheThinLensAndScreenWindow) {
  TempDir dir;
  Scene s = read_json(dir, R"({"camera": {"position": [0, 0, 5], "target": [0, 0, 0],
    "lens_radius": 0.125, "focal_distance": 4.5, "screen_window": [-0.5, 1, -0.25, 0.75]}})");
  EXPECT_EQ(s.camera.lens_radius, 0.125f);
  EXPECT_EQ(s.camera.focal_distance, 4.5f);
  EXPECT_EQ(s.camera.screen_window, (std::array<float, 4>{-0.5f, 1, -0.25f, 0.75f}));
  // Without them: a pinhole seeing the whole image plane.
  Scene pin = read_json(dir, R"({"camera": {"position": [0, 0, 5], "target": [0, 0, 0]}})");
  EXPECT_FALSE(pin.camera.has_lens());
  EXPECT_EQ(pin.camera.focal_distance, Camera().focal_distance);
  EXPECT_EQ(pin.camera.screen_window, Camera().screen_window);
  const std::string cam = R"({"camera": {"position": [0, 0, 5], "target": [0, 0, 0], )";
  expect_mentions(json_error(dir, cam + R"("lens_radius": -1}})"),
                  {"scene.json: /camera/lens_radius must not be negative"});
  expect_mentions(json_error(dir, cam + R"("focal_distance": 0}})"),
                  {"/camera/focal_distance must be positive"});
  expect_mentions(json_error(dir, cam + R"("screen_window": [0, 1, 0]}})"),
                  {"/camera/screen_window must be an array of 4 numbers", "3 values"});
  expect_mentions(json_error(dir, cam + R"("screen_window": [0, 1, "a", 1]}})"),
                  {"/camera/screen_window/2 must be a number"});
  expect_mentions(json_error(dir, cam + R"("screen_window": [1, 0, -1, 1]}})"),
                  {"/camera/screen_window needs xmin < xmax and ymin < ymax"});
  expect_mentions(json_error(dir, cam + R"("screen_window": [0, 0, 0, 0]}})"),
                  {"/camera/screen_window needs xmin < xmax"});
}

TEST(JsonLoader, ObjShapesTakeMaterialOverridesAndMaps) {
  TempDir dir;
  dir.write("mesh/m.mtl", "newmtl a\nKd 0.1 0.1 0.1\nnewmtl b\nKd 0.2 0.2 0.2\n");
  dir.write("mesh/m.obj",
            "mtllib m.mtl\n" + std::string(kQuadObj) + "usemtl a\nf 1 2 3\nusemtl b\nf 1 3 4\n");
  Scene s = read_json(dir, std::string("{") + kLamp + R"(,
    "shapes": [{"file": "mesh/m.obj"},
               {"file": "mesh/m.obj", "material": "lamp"},
               {"file": "mesh/m.obj", "material_map": {"b": {"albedo": [0.9, 0.9, 0.9]}}}]})");
  ASSERT_EQ(s.mesh.triangle_count(), 6u);
  auto albedo = [&](size_t t) { return s.materials[s.mesh.material[t]].albedo; };
  EXPECT_EQ(albedo(0), Rgb(0.1f));
  EXPECT_EQ(albedo(1), Rgb(0.2f));
  EXPECT_TRUE(s.materials[s.mesh.material[2]].is_emissive());
  EXPECT_TRUE(s.materials[s.mesh.material[3]].is_emissive());
  EXPECT_EQ(albedo(4), Rgb(0.1f));
  EXPECT_EQ(albedo(5), Rgb(0.9f));
}

TEST(JsonLoader, TransformsMoveShapesAndMirrorsKeepFrontFaces) {
  TempDir dir;
  Scene s = read_json(dir, std::string("{") + kLamp + R"(,
    "shapes": [
      {"type": "quad", "origin": [0, 0, 0], "edge1": [1, 0, 0], "edge2": [0, 1, 0], "material": "lamp",
       "transform": {"scale": 2, "rotate": {"axis": [0, 0, 1], "angle": 90}, "translate": [10, 0, 0]}},
      {"type": "quad", "origin": [0, 0, 0], "edge1": [1, 0, 0], "edge2": [0, 1, 0], "material": "lamp",
       "transform": {"matrix": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, -1, 3], [0, 0, 0, 1]]}},
      {"type": "sphere", "center": [0, 0, 0], "radius": 1, "subdivisions": 0, "material": "lamp",
       "transform": {"scale": [-1, 1, 1]}}
    ]})");
  // (1, 0, 0) scaled by 2, turned 90 degrees about z, moved by 10 along x.
  const Vec3 p = s.mesh.vertex(0, 1);
  EXPECT_NEAR(p.x, 10, 1e-5f);
  EXPECT_NEAR(p.y, 2, 1e-5f);
  EXPECT_NEAR(p.z, 0, 1e-5f);
  EXPECT_GT(s.mesh.face_cross(0).z, 0);
  // The mirrored quad (z -> 3 - z) faces -z, the mirror image of +z: a mirror turns the
  // winding around, and the loader turns it back so that front faces follow the normals.
  EXPECT_LT(s.mesh.face_cross(2).z, 0);
  EXPECT_EQ(s.mesh.vertex(2, 0).z, 3.0f);
  // A mirrored sphere still has outward faces and outward normals.
  for (size_t t = 4; t < s.mesh.triangle_count(); ++t) {
    Vec3 c = (s.mesh.vertex(uint32_t(t), 0) + s.mesh.vertex(uint32_t(t), 1) +
              s.mesh.vertex(uint32_t(t), 2)) /
             3.0f;
    EXPECT_GT(dot(s.mesh.face_cross(uint32_t(t)), c), 0) << t;
    EXPECT_GT(dot(s.mesh.normals[s.mesh.triangles[t][0]], s.mesh.vertex(uint32_t(t), 0)), 0) << t;
  }
}

TEST(JsonLoader, LoadsTexturesAndCommentsAndFitsACameraWhenNoneIsGiven) {
  TempDir dir;
  write_image(dir / "t.png", Image(4, 2, Rgb(1)));
  Scene s = read_json(dir, R"({
    // a comment
    "materials": {"tex": {"texture": "t.png"}, "lamp": {"emission": [1, 1, 1]}},
    "shapes": [{"type": "quad", "origin": [0, 0, 0], "edge1": [1, 0, 0], "edge2": [0, 1, 0], "material": "tex"},
               {"type": "quad", "origin": [0, 0, 1], "edge1": [1, 0, 0], "edge2": [0, 1, 0], "material": "lamp"}]
  })");
  ASSERT_EQ(s.textures.size(), 1u);
  EXPECT_EQ(s.textures[0].width(), 4);
  // The textured quad has uvs over [0, 1]^2 rather than per-triangle barycentrics.
  ASSERT_EQ(s.mesh.uvs.size(), s.mesh.positions.size());
  EXPECT_EQ(s.mesh.uvs[s.mesh.triangles[0][1]].x, 1.0f);
  EXPECT_EQ(s.mesh.uvs[s.mesh.triangles[0][2]].y, 1.0f);
  EXPECT_FALSE(s.has_camera);
  s.finalize();
  EXPECT_TRUE(s.has_camera);
}

TEST(JsonLoader, UnknownFieldsNameTheFileAndPointer) {
  TempDir dir;
  expect_mentions(json_error(dir, R"({"camer": {}})"),
                  {"scene.json: unknown field \"camer\" in /"});
  expect_mentions(
      json_error(dir, R"({"camera": {"position": [0,0,1], "target": [0,0,0], "fovv": 3}})"),
      {"scene.json", "unknown field \"fovv\" in /camera"});
  expect_mentions(
      json_error(dir,
                 R"({"shapes": [{"type": "box", "min": [0,0,0], "max": [1,1,1], "colour": 1}]})"),
      {"unknown field \"colour\" in /shapes/0"});
  expect_mentions(json_error(dir, R"({"sky": {"type": "dome", "radiance": [1,1,1], "tilt": 3}})"),
                  {"unknown field \"tilt\" in /sky"});
  expect_mentions(json_error(dir, R"({"materials": {"a": {"albedo": [1,1,1], "rougness": 0.1}}})"),
                  {"unknown field \"rougness\" in /materials/a"});
  expect_mentions(json_error(dir, R"({"materials": {"a": {"type": "diffuse", "roughness": 0.1}}})"),
                  {"/materials/a", "\"roughness\" does not apply to a diffuse material"});
  expect_mentions(
      json_error(dir,
                 R"({"camera": {"position": [0,0,1], "target": [0,0,0], "fov": 40, "fov": 50}})"),
      {"scene.json", "duplicate field \"fov\" in /camera"});
  expect_mentions(json_error(dir, R"({"lights": [{}, {"type": "point", "type": "point"}]})"),
                  {"duplicate field \"type\" in /lights/1"});
}

TEST(JsonLoader, WrongTypesLengthsAndValuesNameThePointer) {
  TempDir dir;
  expect_mentions(
      json_error(dir, R"({"camera": {"position": [0,0,1], "target": [0,0,0], "fov": "40"}})"),
      {"scene.json: /camera/fov must be a number"});
  expect_mentions(json_error(dir, R"({"camera": {"position": [0,0], "target": [0,0,0]}})"),
                  {"/camera/position must be an array of 3 numbers (got 2 values)"});
  expect_mentions(json_error(dir, R"({"camera": {"position": [0,"a",0], "target": [0,0,0]}})"),
                  {"/camera/position/1 must be a number"});
  expect_mentions(json_error(dir, R"({"camera": {"target": [0,0,0]}})"),
                  {"/camera: missing field \"position\""});
  expect_mentions(json_error(dir, R"({"camera": {"position": [0,0,1e39], "target": [0,0,0]}})"),
                  {"/camera/position/2 must be a finite number"});
  expect_mentions(json_error(dir, R"({"film": {"width": 64.5}})"),
                  {"/film/width must be an integer"});
  expect_mentions(json_error(dir, R"({"film": {"width": 0}})"),
                  {"/film/width must be a positive integer"});
  expect_mentions(json_error(dir, R"({"shapes": {}})"), {"/shapes must be an array"});
  expect_mentions(
      json_error(dir,
                 R"({"lights": [{"type": "point", "position": [0,0,0], "intensity": [1,-1,1]}]})"),
      {"/lights/0/intensity/1 must not be negative"});
  expect_mentions(
      json_error(
          dir,
          R"({"lights": [{"type": "directional", "direction": [0,0,0], "irradiance": [1,1,1]}]})"),
      {"/lights/0/direction must be a non-zero vector"});
  expect_mentions(json_error(dir, R"({"lights": [{"type": "area"}]})"),
                  {"/lights/0/type", "unknown light type 'area'"});
  expect_mentions(json_error(dir, R"({"sky": {"type": "dome", "radiance": [-1, 0, 0]}})"),
                  {"/sky/radiance/0 must not be negative"});
  expect_mentions(json_error(dir, R"({"sky": {"type": "infinite"}})"),
                  {"unknown sky type 'infinite'"});
  expect_mentions(json_error(dir, R"({"shapes": [{"type": "cone"}]})"),
                  {"/shapes/0/type", "unknown shape type 'cone'"});
  expect_mentions(
      json_error(
          dir,
          R"({"shapes": [{"type": "quad", "origin": [0,0,0], "edge1": [1,0,0], "edge2": [2,0,0]}]})"),
      {"/shapes/0", "parallel"});
  expect_mentions(
      json_error(
          dir,
          R"({"shapes": [{"type": "sphere", "center": [0,0,0], "radius": 1, "material": "nope"}]})"),
      {"/shapes/0/material", "no material named \"nope\""});
  expect_mentions(
      json_error(
          dir,
          R"({"shapes": [{"type": "box", "min": [0,0,0], "max": [1,1,1], "transform": {"scale": 0}}]})"),
      {"/shapes/0/transform is singular"});
  expect_mentions(json_error(dir, R"({"materials": {"m": {"type": "glass"}}})"),
                  {"unknown material type 'glass'"});
}

TEST(JsonLoader, MalformedJsonGivesLineAndColumn) {
  TempDir dir;
  expect_mentions(json_error(dir, "{\n  \"film\": {\"width\": 64,}\n}"),
                  {"scene.json:2:24:", "invalid JSON"});
  expect_mentions(json_error(dir, "{\"film\":\n  {\"width\": 64"), {"scene.json:2:15:"});
  expect_mentions(json_error(dir, ""), {"scene.json:1:1:"});
  expect_mentions(json_error(dir, R"({"film": {"width": 1e999}})"),
                  {"scene.json", "invalid JSON", "1e999"});
}

TEST(JsonLoader, MissingReferencedFilesNameBothFiles) {
  TempDir dir;
  expect_mentions(json_error(dir, R"({"shapes": [{"file": "gone.obj"}]})"),
                  {"scene.json", "/shapes/0/file", "gone.obj", "not found"});
  expect_mentions(json_error(dir, R"({"materials": {"t": {"texture": "gone.png"}}})"),
                  {"scene.json", "/materials/t/texture", "gone.png"});
  dir.write("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 nan\nf 1 2 3\n");
  expect_mentions(json_error(dir, R"({"shapes": [{"file": "bad.obj"}]})"),
                  {"scene.json", "/shapes/0", "bad.obj:3:"});
  dir.write("m.obj", std::string(kQuadObj) + "f 1 2 3\n");
  expect_mentions(json_error(dir, R"({"shapes": [{"file": "m.obj", "material_map": {"x": {}}}]})"),
                  {"/shapes/0/material_map", "no material named \"x\""});
  dir.write("m.ply", "ply\n");
  expect_mentions(json_error(dir, R"({"shapes": [{"file": "m.ply"}]})"),
                  {"/shapes/0/file", ".obj"});
}

TEST(ObjLoader, ImpossibleMtlValuesAreErrorsWithTheirLine) {
  TempDir dir;
  const std::string obj = "mtllib m.mtl\nusemtl shiny\n" + std::string(kQuadObj) + "f 1 2 3 4\n";
  const std::pair<const char*, std::vector<std::string>> cases[] = {
      {"Ni -1.5", {"m.mtl:3", "Ni", "must be positive", "-1.5"}},
      {"Ni 0", {"m.mtl:3", "Ni", "must be positive"}},
      {"d 1.5", {"m.mtl:3", "d must be in [0, 1]", "1.5"}},
      {"Tr -0.5", {"m.mtl:3", "Tr must be in [0, 1]", "-0.5"}},
  };
  for (const auto& [line, mentions] : cases) {
    dir.write("m.mtl", std::string("newmtl shiny\nKd 0.5\n") + line + "\nKs 0.1\n");
    const std::string e = error_of([&] { read_obj(dir, obj); });
    for (const auto& part : mentions) EXPECT_NE(e.find(part), std::string::npos) << e;
  }
}
