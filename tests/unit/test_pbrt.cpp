// pbrt-v4 reader: transforms, attributes, instances and includes place geometry where pbrt
// does; shapes, materials and lights map as docs/scene-format.md says; unsupported directives
// are skipped with one warning naming them and the line; syntax errors name file and line.
#include <gtest/gtest.h>

#include <fmt/format.h>
#include <zlib.h>

#include <cmath>

#include "rll/io/load.h"
#include "rll/io/save.h"
#include "rll/io/text_scan.h"
#include "support/test_support.h"

using namespace rll;
using rll::test::error_of;
using rll::test::expect_mentions;
using rll::test::TempDir;

namespace {

Scene read_pbrt(const TempDir& dir, const std::string& text, const std::string& name = "s.pbrt") {
  Scene s;
  load_pbrt(dir.write(name, text), s);
  return s;
}

std::string pbrt_error(const TempDir& dir, const std::string& text) {
  return error_of([&] { read_pbrt(dir, text, "bad.pbrt"); });
}

bool near(const Vec3& a, const Vec3& b, float eps = 1e-5f) {
  return length(a - b) <= eps;
}

// A camera with pbrt's usual mirror fix (Scale -1 1 1), so that rll keeps the world as it is.
const char* kCamera =
    "Scale -1 1 1\n"
    "LookAt 0 0 5  0 0 0  0 1 0\n"
    "Camera \"perspective\" \"float fov\" [ 40 ]\n"
    "Film \"rgb\" \"integer xresolution\" [ 64 ] \"integer yresolution\" 32\n"
    "WorldBegin\n";

const char* kTriangle =
    "Shape \"trianglemesh\" \"point3 P\" [ 0 0 0  1 0 0  0 1 0 ] \"integer indices\" [ 0 1 2 ]\n";

bool has_warning(const Scene& s, std::initializer_list<std::string> parts) {
  for (const auto& w : s.warnings) {
    bool all = true;
    for (const auto& p : parts) all = all && w.find(p) != std::string::npos;
    if (all) return true;
  }
  return false;
}

}  // namespace

TEST(PbrtReader, CameraFilmMeshMaterialAndAreaLight) {
  TempDir dir;
  Scene s =
      read_pbrt(dir, std::string(kCamera) +
                         "AttributeBegin\n"
                         "  Material \"diffuse\" \"rgb reflectance\" [ 0.2 0.4 0.6 ]\n"
                         "  AreaLightSource \"diffuse\" \"rgb L\" [ 1 2 3 ] \"float scale\" 2 "
                         "\"bool twosided\" true\n"
                         "  Translate 1 2 3\n" +
                         kTriangle +
                         "AttributeEnd\n"
                         "# after the attributes: the default material, no light\n" +
                         kTriangle);
  EXPECT_EQ(s.width, 64);
  EXPECT_EQ(s.height, 32);
  ASSERT_TRUE(s.has_camera);
  EXPECT_TRUE(near(s.camera.position, Vec3(0, 0, 5)));
  EXPECT_TRUE(near(normalize(s.camera.target - s.camera.position), Vec3(0, 0, -1)));
  EXPECT_TRUE(near(s.camera.up, Vec3(0, 1, 0)));
  EXPECT_FLOAT_EQ(s.camera.fov, 40);  // the shorter side is the vertical one
  ASSERT_EQ(s.mesh.triangle_count(), 2u);
  EXPECT_TRUE(near(s.mesh.vertex(0, 1), Vec3(2, 2, 3)));
  EXPECT_TRUE(near(s.mesh.vertex(1, 1), Vec3(1, 0, 0)));
  const Material& lit = s.materials[s.mesh.material[0]];
  EXPECT_EQ(lit.type, MaterialType::Diffuse);
  EXPECT_TRUE(near(lit.albedo, Rgb(0.2f, 0.4f, 0.6f)));
  EXPECT_TRUE(near(lit.emission, Rgb(2, 4, 6)));
  EXPECT_TRUE(lit.two_sided_emission);
  const Material& plain = s.materials[s.mesh.material[1]];
  EXPECT_FALSE(plain.is_emissive());
  EXPECT_TRUE(near(plain.albedo, Rgb(0.5f)));  // pbrt's default material
  EXPECT_TRUE(s.warnings.empty());
}

TEST(PbrtReader, FovSpansTheShorterSide) {
  TempDir dir;
  std::string portrait = kCamera;
  portrait.replace(portrait.find("[ 64 ]"), 6, "[ 16 ]");
  Scene s = read_pbrt(dir, portrait + kTriangle);
  const double expected = 2 * std::atan(std::tan(20 * M_PI / 180) * 32 / 16) * 180 / M_PI;
  EXPECT_NEAR(s.camera.fov, expected, 1e-3);
}

TEST(PbrtReader, LeftHandedCameraMirrorsTheWorld) {
  TempDir dir;
  // Without "Scale -1 1 1", pbrt's image shows world +x on the left: rll mirrors the scene so
  // that its right-handed camera renders the same image.
  std::string camera = kCamera;
  camera.erase(0, camera.find('\n') + 1);
  Scene mirrored =
      read_pbrt(dir, camera + kTriangle + "LightSource \"point\" \"point3 from\" [ 3 0 0 ]");
  EXPECT_TRUE(near(mirrored.mesh.positions[1], Vec3(-1, 0, 0)));
  EXPECT_TRUE(near(mirrored.lights[0].p0, Vec3(-3, 0, 0)));
  // The mirror turns the winding around, so the front face still faces +z.
  EXPECT_GT(mirrored.mesh.face_cross(0).z, 0);
  Scene kept = read_pbrt(dir, std::string(kCamera) + kTriangle);
  EXPECT_TRUE(near(kept.mesh.vertex(0, 1), Vec3(1, 0, 0)));
  EXPECT_GT(kept.mesh.face_cross(0).z, 0);
}

TEST(PbrtReader, TransformsComposeLikePbrt) {
  TempDir dir;
  Scene s = read_pbrt(
      dir, std::string(kCamera) +
               "AttributeBegin\n Translate 10 0 0\n Rotate 90 0 0 1\n Scale 2 2 2\n" + kTriangle +
               "AttributeEnd\n"
               "AttributeBegin\n Transform [ 1 0 0 0  0 1 0 0  0 0 1 0  5 6 7 1 ]\n" +
               kTriangle + " ConcatTransform [ 2 0 0 0  0 2 0 0  0 0 2 0  0 0 0 1 ]\n" + kTriangle +
               "AttributeEnd\n"
               "TransformBegin\n Translate 0 0 1\n" +
               kTriangle + "TransformEnd\n" + kTriangle);
  ASSERT_EQ(s.mesh.triangle_count(), 5u);
  // (1, 0, 0): scaled to (2, 0, 0), rotated to (0, 2, 0), translated to (10, 2, 0).
  EXPECT_TRUE(near(s.mesh.vertex(0, 1), Vec3(10, 2, 0)));
  EXPECT_TRUE(near(s.mesh.vertex(1, 1), Vec3(6, 6, 7)));  // Transform lists columns
  EXPECT_TRUE(near(s.mesh.vertex(2, 1), Vec3(7, 6, 7)));  // ConcatTransform applies first
  EXPECT_TRUE(near(s.mesh.vertex(3, 0), Vec3(0, 0, 1)));
  EXPECT_TRUE(near(s.mesh.vertex(4, 0), Vec3(0, 0, 0)));  // TransformEnd restored
}

TEST(PbrtReader, ObjectInstancesAndIncludes) {
  TempDir dir;
  dir.write(
      "parts/object.pbrt",
      "ObjectBegin \"tri\"\n"
      "  Material \"conductor\" \"spectrum eta\" \"metal-Au-eta\" \"spectrum k\" \"metal-Au-k\" "
      "\"float roughness\" 0.04\n" +
          std::string(kTriangle) + "ObjectEnd\n");
  Scene s =
      read_pbrt(dir, std::string(kCamera) +
                         "Include \"parts/object.pbrt\"\n"
                         "AttributeBegin Translate 0 0 -1 ObjectInstance \"tri\" AttributeEnd\n"
                         "AttributeBegin Translate 0 0 -2 ObjectInstance \"tri\" AttributeEnd\n");
  ASSERT_EQ(s.mesh.triangle_count(), 2u);  // the definition itself is not rendered
  EXPECT_TRUE(near(s.mesh.vertex(0, 0), Vec3(0, 0, -1)));
  EXPECT_TRUE(near(s.mesh.vertex(1, 2), Vec3(0, 1, -2)));
  const Material& gold = s.materials[s.mesh.material[0]];
  EXPECT_EQ(gold.type, MaterialType::Conductor);
  EXPECT_NEAR(gold.eta.z, 1.44248f, 1e-4);
  EXPECT_NEAR(gold.roughness, 0.2f, 1e-6);  // remapped: alpha = sqrt(roughness)
}

TEST(PbrtReader, SphereDiskAndBilinearPatchesAreTessellated) {
  TempDir dir;
  Scene s = read_pbrt(dir, std::string(kCamera) + "Shape \"sphere\" \"float radius\" 2\n");
  EXPECT_EQ(s.mesh.triangle_count(), 2208u);  // 48 segments x 24 rings, single-vertex poles
  double area = 0;
  for (uint32_t t = 0; t < s.mesh.triangle_count(); ++t) {
    area += s.mesh.area(t);
    const Vec3 c = (s.mesh.vertex(t, 0) + s.mesh.vertex(t, 1) + s.mesh.vertex(t, 2)) / 3.0f;
    EXPECT_GT(dot(s.mesh.face_cross(t), c), 0) << "triangle " << t << " faces inwards";
  }
  EXPECT_NEAR(area / (4 * M_PI * 4), 1.0, 0.01);
  for (const Vec3& p : s.mesh.positions) EXPECT_NEAR(length(p), 2.0f, 1e-5);

  Scene inside = read_pbrt(dir, std::string(kCamera) + "ReverseOrientation Shape \"sphere\"\n");
  const Vec3 c = (inside.mesh.vertex(5, 0) + inside.mesh.vertex(5, 1) + inside.mesh.vertex(5, 2));
  EXPECT_LT(dot(inside.mesh.face_cross(5), c), 0);

  Scene disk = read_pbrt(dir, std::string(kCamera) + "Shape \"disk\" \"float radius\" 1\n");
  EXPECT_EQ(disk.mesh.triangle_count(), 64u);
  double disk_area = 0;
  for (uint32_t t = 0; t < disk.mesh.triangle_count(); ++t) {
    disk_area += disk.mesh.area(t);
    EXPECT_GT(disk.mesh.face_cross(t).z, 0);
  }
  EXPECT_NEAR(disk_area / M_PI, 1.0, 0.01);

  Scene flat =
      read_pbrt(dir, std::string(kCamera) +
                         "Shape \"bilinearmesh\" \"point3 P\" [ 0 0 0  1 0 0  0 1 0  1 1 0 ]\n");
  EXPECT_EQ(flat.mesh.triangle_count(), 2u);
  EXPECT_GT(flat.mesh.face_cross(0).z, 0);
  Scene saddle =
      read_pbrt(dir, std::string(kCamera) +
                         "Shape \"bilinearmesh\" \"point3 P\" [ 0 0 0  1 0 0  0 1 0  1 1 1 ] "
                         "\"integer indices\" [ 0 1 2 3 ]\n");
  EXPECT_EQ(saddle.mesh.triangle_count(), 128u);
  EXPECT_TRUE(near(saddle.mesh.positions[40], Vec3(4 / 8.0f, 4 / 8.0f, 0.25f)));  // p(0.5, 0.5)
}

TEST(PbrtReader, PlyMeshTextureAndMaterialMapping) {
  TempDir dir;
  Mesh quad;
  quad.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  quad.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  quad.triangles = {{0, 1, 2}, {0, 2, 3}};
  dir.write("meshes/quad.ply", ply_bytes(quad, PlyEncoding::BinaryLittleEndian));
  Image tex(2, 2, Rgb(0.25f));
  write_image(dir / "tex.exr", tex);
  Scene s = read_pbrt(dir, std::string(kCamera) +
                               "Texture \"wood\" \"spectrum\" \"imagemap\" \"string filename\" "
                               "\"tex.exr\" \"float scale\" 2\n"
                               "Material \"coateddiffuse\" \"texture reflectance\" \"wood\" "
                               "\"float roughness\" 0.01 \"bool remaproughness\" false\n"
                               "Shape \"plymesh\" \"string filename\" \"meshes/quad.ply\"\n"
                               "Material \"dielectric\" \"float eta\" 1.33\n" +
                               kTriangle + "Material \"dielectric\"\n" + kTriangle);
  ASSERT_EQ(s.mesh.triangle_count(), 4u);
  ASSERT_EQ(s.mesh.uvs.size(), s.mesh.positions.size());
  const Material& coated = s.materials[s.mesh.material[0]];
  EXPECT_EQ(coated.type, MaterialType::CoatedDiffuse);
  EXPECT_FLOAT_EQ(coated.roughness, 0.01f);
  ASSERT_GE(coated.albedo_texture, 0);
  EXPECT_FLOAT_EQ(s.textures[size_t(coated.albedo_texture)].at(0, 0).x, 0.25f);
  EXPECT_TRUE(near(coated.albedo, Rgb(2)));
  const Material& glass = s.materials[s.mesh.material[2]];
  EXPECT_EQ(glass.type, MaterialType::Dielectric);
  EXPECT_FLOAT_EQ(glass.ior, 1.33f);
  EXPECT_FLOAT_EQ(glass.roughness, 0);  // pbrt's default: smooth
  EXPECT_FLOAT_EQ(s.materials[s.mesh.material[3]].ior, 1.5f);
  EXPECT_TRUE(s.warnings.empty());
}

TEST(PbrtReader, PointDistantAndInfiniteLights) {
  TempDir dir;
  Scene s = read_pbrt(
      dir, std::string(kCamera) + kTriangle +
               "AttributeBegin Translate 0 4 0\n"
               "  LightSource \"point\" \"rgb I\" [ 1 2 3 ] \"point3 from\" [ 1 0 0 ]\n"
               "AttributeEnd\n"
               "LightSource \"distant\" \"point3 from\" [ 0 10 0 ] \"point3 to\" [ 0 0 0 ] "
               "\"blackbody L\" 6500 \"float scale\" 3\n"
               "LightSource \"infinite\" \"rgb L\" [ 0.5 0.5 0.5 ]\n");
  ASSERT_EQ(s.lights.size(), 2u);
  EXPECT_EQ(s.lights[0].type, LightType::Point);
  EXPECT_TRUE(near(s.lights[0].p0, Vec3(1, 4, 0)));
  EXPECT_TRUE(near(s.lights[0].radiance, Rgb(1, 2, 3)));
  EXPECT_EQ(s.lights[1].type, LightType::Directional);
  EXPECT_TRUE(near(s.lights[1].p0, Vec3(0, 1, 0)));
  // A 6500 K blackbody is nearly white, with luminance `scale`.
  EXPECT_NEAR(luminance(s.lights[1].radiance), 3.0f, 0.05f);
  EXPECT_NEAR(s.lights[1].radiance.x / s.lights[1].radiance.z, 1.0f, 0.15f);
  ASSERT_TRUE(s.sky.has_value());
  EXPECT_TRUE(s.sky->full_sphere);
  EXPECT_TRUE(near(s.sky->radiance, Rgb(0.5f)));
  EXPECT_FALSE(s.sky->map);
}

TEST(PbrtReader, InfiniteLightImageIsAnEqualAreaMapInTheLightsFrame) {
  TempDir dir;
  // Left half of the square blue, right half red: in pbrt-v4's equal-area octahedral map, the
  // right half holds the directions with x > 0 in the light's frame.
  Image map(32, 32);
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) map.at(x, y) = x < 16 ? Rgb(0, 0, 1) : Rgb(1, 0, 0);
  write_image(dir / "sky.exr", map);
  Scene s = read_pbrt(dir, std::string(kCamera) + kTriangle +
                               "AttributeBegin Rotate 90 0 0 1\n"
                               "  LightSource \"infinite\" \"string filename\" \"sky.exr\"\n"
                               "AttributeEnd\n");
  ASSERT_TRUE(s.sky && s.sky->map);
  // The light's +x is the world's +y after the rotation.
  EXPECT_TRUE(near(s.sky->map->lookup(Vec3(0.3f, 1, 0.1f)), Rgb(1, 0, 0)));
  EXPECT_TRUE(near(s.sky->map->lookup(Vec3(0.3f, -1, -0.1f)), Rgb(0, 0, 1)));
  s.lights.push_back(make_point_light(Vec3(0, 0, 1), Rgb(1)));
  s.finalize();
  ASSERT_EQ(s.sky_triangle_count, 2048u);
  // Half the dome's solid angle is red, half blue: the triangles straddling the boundary
  // emit a mix.
  double red = 0, blue = 0;
  for (size_t t = s.sky_first_triangle; t < s.sky_first_triangle + s.sky_triangle_count; ++t) {
    const Rgb e = s.materials[s.mesh.material[t]].emission;
    red += e.x * s.mesh.area(uint32_t(t));
    blue += e.z * s.mesh.area(uint32_t(t));
    EXPECT_NEAR(e.x + e.z, 1.0f, 1e-4);
  }
  EXPECT_NEAR(red / (red + blue), 0.5, 0.01);
}

TEST(PbrtReader, UnsupportedDirectivesWarnOnceAndAreSkipped) {
  TempDir dir;
  Scene s =
      read_pbrt(dir, std::string("Sampler \"halton\" \"integer pixelsamples\" 16\n") + kCamera +
                         "Shape \"curve\" \"point3 P\" [ 0 0 0 1 1 1 2 2 2 3 3 3 ]\n"
                         "Shape \"curve\" \"point3 P\" [ 0 0 0 1 1 1 2 2 2 3 3 3 ]\n"
                         "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n"
                         "LightSource \"goniometric\" \"point3 from\" [0 1 0]\n" +
                         kTriangle);
  EXPECT_EQ(s.mesh.triangle_count(), 1u);
  EXPECT_TRUE(has_warning(s, {"s.pbrt:1:", "Sampler", "not supported"}));
  EXPECT_TRUE(has_warning(s, {"s.pbrt:7:", "Shape \"curve\"", "1 more"}));
  EXPECT_TRUE(has_warning(s, {"s.pbrt:9:", "MakeNamedMedium"}));
  EXPECT_TRUE(has_warning(s, {"s.pbrt:10:", "LightSource \"goniometric\""}));
}

TEST(PbrtReader, SyntaxErrorsNameFileAndLine) {
  TempDir dir;
  const std::string c = kCamera;  // 5 lines
  expect_mentions(pbrt_error(dir, c + "Shape \"trianglemesh\" \"point3 P\" [ 0 0 0\n"),
                  {"bad.pbrt:6:", "]"});
  expect_mentions(pbrt_error(dir, c + "Shape \"sphere\n"), {"bad.pbrt:6:", "string"});
  expect_mentions(pbrt_error(dir, c + "Shpe \"sphere\"\n"),
                  {"bad.pbrt:6:", "unknown directive 'Shpe'"});
  expect_mentions(pbrt_error(dir, "LookAt 0 0 5 0 0 0 0 1\nCamera \"perspective\"\n"),
                  {"bad.pbrt:2:", "expected a number"});
  expect_mentions(pbrt_error(dir, c + "Translate 1 x 3\n"), {"bad.pbrt:6:", "'x'"});
  expect_mentions(pbrt_error(dir, c + "Translate 1 1e39 3\n"), {"bad.pbrt:6:", "finite"});
  expect_mentions(pbrt_error(dir, c + "AttributeEnd\n"), {"bad.pbrt:6:", "without a matching"});
  expect_mentions(pbrt_error(dir, c + "AttributeBegin\n"), {"bad.pbrt", "AttributeBegin without"});
  expect_mentions(pbrt_error(dir, c + "Shape \"sphere\" \"float radius\"\n"),
                  {"bad.pbrt:6:", "value"});
  expect_mentions(pbrt_error(dir, c + "Shape \"sphere\" \"real radius\" 1\n"),
                  {"bad.pbrt:6:", "unknown parameter type 'real'"});
  expect_mentions(pbrt_error(dir, c + "Shape \"sphere\" \"float radius\" \"one\"\n"),
                  {"bad.pbrt:6:", "wrong kind"});
  expect_mentions(pbrt_error(dir, c + "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] "
                                      "\"integer indices\" [0 1 3]\n"),
                  {"bad.pbrt:6:", "index 3 is out of range"});
  expect_mentions(pbrt_error(dir, c + "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1]\n"),
                  {"bad.pbrt:6:", "multiple of 3"});
  expect_mentions(pbrt_error(dir, c + "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] "
                                      "\"normal N\" [0 0 1]\n"),
                  {"bad.pbrt:6:", "1 normals for 3 vertices"});
  expect_mentions(pbrt_error(dir, c + "NamedMaterial \"nothing\"\n"), {"bad.pbrt:6:", "nothing"});
  expect_mentions(pbrt_error(dir, c + "ObjectInstance \"nothing\"\n"),
                  {"bad.pbrt:6:", "no such object"});
  expect_mentions(pbrt_error(dir, c + "Shape \"sphere\" \"float radius\" [ 1 2 ]\n"),
                  {"bad.pbrt:6:", "needs 1 value"});
  expect_mentions(pbrt_error(dir, c + "Shape \"sphere\" \"integer radius\" 1\n"),
                  {"bad.pbrt:6:", "must be of type float"});
  expect_mentions(pbrt_error(dir, c + "1 2 3\n"), {"bad.pbrt:6:", "expected a directive"});
}

TEST(PbrtReader, MissingAndRecursiveIncludesAreErrors) {
  TempDir dir;
  expect_mentions(pbrt_error(dir, "Include \"nothere.pbrt\"\n"),
                  {"bad.pbrt:1:", "'nothere.pbrt' not found"});
  dir.write("a.pbrt", "\n\nInclude \"b.pbrt\"\n");
  dir.write("b.pbrt", "Import \"a.pbrt\"\n");
  expect_mentions(pbrt_error(dir, "Include \"a.pbrt\"\n"), {"b.pbrt:1:", "recursive"});
  expect_mentions(
      pbrt_error(dir, std::string(kCamera) + "Shape \"plymesh\" \"string filename\" \"x.ply\"\n"),
      {"bad.pbrt:6:", "'x.ply' not found"});
  expect_mentions(
      pbrt_error(dir,
                 std::string(kCamera) +
                     "Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"x.png\"\n"),
      {"bad.pbrt:6:", "'x.png' not found"});
  dir.write("bad.ply", "ply\nformat ascii 1.0\nelement vertex 1\n");
  expect_mentions(
      pbrt_error(dir, std::string(kCamera) + "Shape \"plymesh\" \"string filename\" \"bad.ply\"\n"),
      {"bad.pbrt:6:", "bad.ply", "end_header"});
  // Without file access (the fuzz targets), a reference is an error, not a read.
  ReadPolicy closed;
  closed.read_files = false;
  Scene s;
  expect_mentions(
      error_of([&] { parse_pbrt("Include \"a.pbrt\"\n", "mem.pbrt", dir.path(), s, closed); }),
      {"mem.pbrt:1:", "turned off"});
}

TEST(PbrtWriter, RoundTripKeepsMaterialsLightsCameraAndSky) {
  TempDir dir;
  Scene a;
  a.source = "test";
  Material plastic;
  plastic.type = MaterialType::Plastic;
  plastic.albedo = Rgb(0.2f, 0.3f, 0.4f);
  plastic.roughness = 0.09f;
  plastic.ior = 1.4f;
  Material gold;
  gold.type = MaterialType::Conductor;  // rll's default eta and k
  gold.roughness = 0.2f;
  Material textured;
  textured.albedo = Rgb(0.5f);
  textured.albedo_texture = 0;
  a.textures.push_back(Image(2, 2, Rgb(0.7f)));
  Material lamp;
  lamp.albedo = Rgb(0);
  lamp.emission = Rgb(3, 2, 1);
  for (const Material& m : {plastic, gold, textured, lamp}) a.materials.push_back(m);
  for (uint32_t k = 0; k < 4; ++k) {
    const uint32_t v = uint32_t(a.mesh.positions.size());
    const float x = float(k);
    a.mesh.positions.insert(a.mesh.positions.end(), {{x, 0, 0}, {x + 1, 0, 0}, {x, 1, 0}});
    a.mesh.uvs.insert(a.mesh.uvs.end(), {{0, 0}, {1, 0}, {0, 1}});
    a.mesh.triangles.push_back({v, v + 1, v + 2});
    a.mesh.material.push_back(k);
  }
  a.mesh.light.assign(4, -1);
  a.lights.push_back(make_point_light(Vec3(1, 2, 3), Rgb(4, 5, 6)));
  a.lights.push_back(make_directional_light(normalize(Vec3(0, 1, 1)), Rgb(2)));
  a.camera.position = Vec3(1, 2, 8);
  a.camera.target = Vec3(1, 0, 0);
  a.camera.fov = 35;
  a.has_camera = true;
  a.width = 30;
  a.height = 60;
  SkyDome sky;
  sky.radiance = Rgb(0.5f, 0.6f, 0.7f);
  a.sky = sky;
  const auto lost = save_pbrt_scene(a, dir / "out.pbrt");
  // The hemisphere, as a map with a black lower half, and rll's plastic, as pbrt's layered
  // coateddiffuse.
  ASSERT_EQ(lost.size(), 2u);
  Scene r;
  load_pbrt(dir / "out.pbrt", r);
  EXPECT_TRUE(r.warnings.empty()) << r.warnings.front();
  ASSERT_EQ(r.mesh.triangle_count(), 4u);
  for (uint32_t t = 0; t < 4; ++t) {
    EXPECT_TRUE(near(r.mesh.vertex(t, 1), a.mesh.vertex(t, 1)));
    EXPECT_GT(r.mesh.face_cross(t).z, 0);
  }
  const Material &p = r.materials[r.mesh.material[0]], &g = r.materials[r.mesh.material[1]],
                 &t = r.materials[r.mesh.material[2]], &l = r.materials[r.mesh.material[3]];
  EXPECT_EQ(p.type, MaterialType::CoatedDiffuse);  // pbrt's coateddiffuse reads as itself
  EXPECT_TRUE(near(p.albedo, plastic.albedo));
  EXPECT_FLOAT_EQ(p.roughness, plastic.roughness);
  EXPECT_FLOAT_EQ(p.ior, plastic.ior);
  EXPECT_EQ(g.type, MaterialType::Conductor);
  EXPECT_TRUE(near(g.eta, gold.eta));
  EXPECT_TRUE(near(g.k, gold.k));
  EXPECT_FLOAT_EQ(g.roughness, gold.roughness);
  ASSERT_GE(t.albedo_texture, 0);
  EXPECT_TRUE(near(t.albedo, Rgb(0.5f)));
  EXPECT_FLOAT_EQ(r.textures[size_t(t.albedo_texture)].at(1, 1).y, 0.7f);
  EXPECT_TRUE(near(l.emission, lamp.emission));
  EXPECT_FALSE(l.two_sided_emission);
  ASSERT_EQ(r.lights.size(), 2u);
  EXPECT_TRUE(near(r.lights[0].p0, Vec3(1, 2, 3)));
  EXPECT_TRUE(near(r.lights[1].p0, normalize(Vec3(0, 1, 1))));
  EXPECT_TRUE(near(r.camera.position, a.camera.position, 1e-4f));
  EXPECT_TRUE(near(normalize(r.camera.target - r.camera.position),
                   normalize(a.camera.target - a.camera.position), 1e-4f));
  EXPECT_NEAR(r.camera.fov, 35, 1e-3);
  EXPECT_EQ(r.width, 30);
  EXPECT_EQ(r.height, 60);
  ASSERT_TRUE(r.sky && r.sky->map);
  EXPECT_TRUE(r.sky->full_sphere);
  EXPECT_TRUE(near(r.sky->map->lookup(Vec3(0.3f, 1, 0.2f)) * r.sky->radiance, sky.radiance, 1e-3f));
  EXPECT_TRUE(near(r.sky->map->lookup(Vec3(0.3f, -1, 0.2f)), Rgb(0)));
}

TEST(PbrtWriter, ThinLensAndScreenWindowRoundTripFromJson) {
  // rll JSON -> pbrt-v4 -> rll keeps the lens radius, the focal distance and the screen window:
  // exactly on a landscape film (rll's and pbrt's screen units agree), to float precision on a
  // portrait one (pbrt's units span the shorter side).
  for (const auto& [w, h] : {std::pair{64, 32}, std::pair{30, 60}}) {
    SCOPED_TRACE(w);
    TempDir dir;
    Scene a;
    load_json_scene(
        dir.write("lens.json",
                  fmt::format(R"({{"camera": {{"position": [0, 1, 5], "target": [0, 1, 0],
      "fov": 40, "lens_radius": 0.0371, "focal_distance": 4.25,
      "screen_window": [-0.3, 0.7, -0.45, 0.15]}},
      "film": {{"width": {}, "height": {}}},
      "shapes": [{{"type": "triangle", "vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0]]}}]}})",
                              w, h)),
        a);
    a.source = "test";
    save_pbrt_scene(a, dir / "lens.pbrt");
    const std::string text = rll::test::read_text(dir / "lens.pbrt");
    EXPECT_NE(text.find("\"float lensradius\" [ 0.0371 ]"), std::string::npos) << text;
    EXPECT_NE(text.find("\"float focaldistance\" [ 4.25 ]"), std::string::npos) << text;
    Scene r;
    load_pbrt(dir / "lens.pbrt", r);
    EXPECT_TRUE(r.warnings.empty()) << r.warnings.front();
    EXPECT_EQ(r.camera.lens_radius, a.camera.lens_radius);
    EXPECT_EQ(r.camera.focal_distance, a.camera.focal_distance);
    EXPECT_NEAR(r.camera.fov, 40, 1e-4);
    for (size_t i = 0; i < 4; ++i) {
      if (w > h)
        EXPECT_EQ(r.camera.screen_window[i], a.camera.screen_window[i]) << i;
      else
        EXPECT_FLOAT_EQ(r.camera.screen_window[i], a.camera.screen_window[i]) << i;
    }
    // The same rays: the pbrt file sees what the JSON scene sees.
    a.camera.setup(w, h);
    r.camera.setup(w, h);
    for (const Vec2 px : {Vec2{0, 0}, Vec2{float(w), float(h)}, Vec2{3.5f, 7.25f}})
      EXPECT_TRUE(near(r.camera.generate_ray(px.x, px.y, {0.2f, 0.7f}).d,
                       a.camera.generate_ray(px.x, px.y, {0.2f, 0.7f}).d, 1e-5f));
  }
  // A pinhole camera writes none of them, and reads back as one.
  TempDir dir;
  Scene pin;
  load_json_scene(dir.write("pin.json", R"({"camera": {"position": [0, 1, 5], "target": [0, 1, 0]},
      "shapes": [{"type": "triangle", "vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0]]}]})"),
                  pin);
  save_pbrt_scene(pin, dir / "pin.pbrt");
  const std::string text = rll::test::read_text(dir / "pin.pbrt");
  for (const char* name : {"lensradius", "focaldistance", "screenwindow"})
    EXPECT_EQ(text.find(name), std::string::npos) << name;
  Scene r;
  load_pbrt(dir / "pin.pbrt", r);
  EXPECT_FALSE(r.camera.has_lens());
  EXPECT_EQ(r.camera.screen_window, Camera().screen_window);
}

// --- the reader's later additions (issue 14) ---

TEST(PbrtReader, SummaryWarningListsEverythingLeftOut) {
  TempDir dir;
  Scene s = read_pbrt(dir, std::string(kCamera) +
                               "Shape \"curve\" \"point3 P\" [ 0 0 0 1 1 1 2 2 2 3 3 3 ]\n"
                               "Shape \"curve\" \"point3 P\" [ 0 0 0 1 1 1 2 2 2 3 3 3 ]\n"
                               "Shape \"hyperboloid\"\n"
                               "LightSource \"goniometric\" \"point3 from\" [0 1 0]\n"
                               "Material \"hair\"\n" +
                               kTriangle + "Material \"measured\"\n" + kTriangle);
  EXPECT_EQ(s.mesh.triangle_count(), 2u);
  // One warning per directive, naming it, the file and the line...
  EXPECT_TRUE(has_warning(s, {"s.pbrt:6:", "Shape \"curve\"", "1 more"}));
  EXPECT_TRUE(has_warning(s, {"s.pbrt:10:", "Material \"hair\""}));
  // ... and one at the end that adds them up.
  EXPECT_TRUE(has_warning(s, {"s.pbrt: summary: 3 shapes skipped (curve x2, hyperboloid x1)",
                              "1 light skipped (goniometric x1)",
                              "materials not supported: hair, measured (rendered as diffuse "
                              "grey)"}));
  Scene clean = read_pbrt(dir, std::string(kCamera) + kTriangle);
  EXPECT_TRUE(clean.warnings.empty());
}

TEST(PbrtReader, LoopSubdivisionSurface) {
  TempDir dir;
  // The regular tetrahedron of test_subdivide.cpp: one level ends with the vertex (1, 1, 1) at its
  // limit position (1, 1, 1) / 5 (derived there by hand).
  const std::string tetra =
      "Shape \"loopsubdiv\" \"point3 P\" [ 1 1 1  1 -1 -1  -1 1 -1  -1 -1 1 ] "
      "\"integer indices\" [ 0 1 2  0 3 1  0 2 3  1 3 2 ]";
  Scene one = read_pbrt(dir, std::string(kCamera) + tetra + " \"integer levels\" 1\n");
  ASSERT_EQ(one.mesh.triangle_count(), 16u);
  EXPECT_TRUE(near(one.mesh.positions[0], Vec3(0.2f, 0.2f, 0.2f)));
  ASSERT_EQ(one.mesh.normals.size(), one.mesh.positions.size());
  EXPECT_TRUE(near(one.mesh.normals[0], normalize(Vec3(1, 1, 1)), 1e-5f));
  Scene three = read_pbrt(dir, std::string(kCamera) + tetra + "\n");  // pbrt's default: 3 levels
  EXPECT_EQ(three.mesh.triangle_count(), 4u * 64);
  // The winding stays outward: every face's normal points away from the centre.
  for (uint32_t t = 0; t < three.mesh.triangle_count(); ++t)
    EXPECT_GT(dot(three.mesh.face_cross(t), three.mesh.vertex(t, 0)), 0);
  EXPECT_TRUE(three.warnings.empty());
  const std::string e =
      pbrt_error(dir, std::string(kCamera) +
                          "Shape \"loopsubdiv\" \"point3 P\" [ 0 0 0 1 0 0 0 1 0 0 -1 0 0 0 1 ] "
                          "\"integer indices\" [ 0 1 2  1 0 3  0 1 4 ]\n");
  expect_mentions(e, {"bad.pbrt:6:", "loopsubdiv", "not a manifold"});
  expect_mentions(pbrt_error(dir, std::string(kCamera) + tetra + " \"integer levels\" -1\n"),
                  {"bad.pbrt:6:", "levels"});
}

TEST(PbrtReader, GzippedPlyMesh) {
  TempDir dir;
  Mesh quad;
  quad.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  quad.triangles = {{0, 1, 2}, {0, 2, 3}};
  const std::string plain = ply_bytes(quad, PlyEncoding::BinaryLittleEndian);
  // gzip through zlib's gz* file interface.
  const auto gz_path = dir / "quad.ply.gz";
  gzFile f = gzopen(gz_path.string().c_str(), "wb");
  ASSERT_TRUE(f);
  ASSERT_EQ(gzwrite(f, plain.data(), unsigned(plain.size())), int(plain.size()));
  ASSERT_EQ(gzclose(f), Z_OK);
  dir.write("quad.ply", plain);
  Scene a =
      read_pbrt(dir, std::string(kCamera) + "Shape \"plymesh\" \"string filename\" \"quad.ply\"\n");
  Scene b = read_pbrt(
      dir, std::string(kCamera) + "Shape \"plymesh\" \"string filename\" \"quad.ply.gz\"\n");
  ASSERT_EQ(a.mesh.triangle_count(), 2u);
  EXPECT_EQ(a.mesh.triangles, b.mesh.triangles);
  EXPECT_EQ(a.mesh.positions.size(), b.mesh.positions.size());
  for (size_t i = 0; i < a.mesh.positions.size(); ++i)
    EXPECT_EQ(a.mesh.positions[i], b.mesh.positions[i]);
  const std::string gz = read_text_file(gz_path);
  dir.write("cut.ply.gz", gz.substr(0, gz.size() - 12));
  expect_mentions(pbrt_error(dir, std::string(kCamera) +
                                      "Shape \"plymesh\" \"string filename\" \"cut.ply.gz\"\n"),
                  {"bad.pbrt:6:", "plymesh", "cut.ply.gz", "truncated"});
}

TEST(PbrtReader, ImageFloatScaleAndMixTextures) {
  TempDir dir;
  Image wood(2, 1);
  wood.at(0, 0) = Rgb(0.2f, 0.4f, 0.6f);
  wood.at(1, 0) = Rgb(1, 1, 1);
  write_image(dir / "wood.exr", wood);
  Image rough(2, 1);
  rough.at(0, 0) = Rgb(0.25f, 0, 0);
  rough.at(1, 0) = Rgb(0.64f, 0, 0);
  write_image(dir / "rough.exr", rough);
  Scene s = read_pbrt(
      dir,
      std::string(kCamera) +
          "Texture \"wood\" \"spectrum\" \"imagemap\" \"string filename\" \"wood.exr\"\n"
          "Texture \"rough\" \"float\" \"imagemap\" \"string filename\" \"rough.exr\"\n"
          "Texture \"dim\" \"spectrum\" \"scale\" \"texture tex\" \"wood\" \"float scale\" 0.5\n"
          "Texture \"blend\" \"spectrum\" \"mix\" \"texture tex1\" \"wood\" "
          "\"rgb tex2\" [ 0 0 1 ] \"float amount\" 0.25\n"
          "Texture \"flat\" \"spectrum\" \"mix\" \"rgb tex1\" [ 1 0 0 ] "
          "\"rgb tex2\" [ 0 1 0 ]\n"
          "Material \"diffuse\" \"texture reflectance\" \"dim\"\n" +
          kTriangle +
          "Material \"coateddiffuse\" \"texture reflectance\" \"blend\" "
          "\"texture roughness\" \"rough\"\n" +
          kTriangle +
          "Material \"conductor\" \"texture roughness\" \"rough\" "
          "\"bool remaproughness\" false\n" +
          kTriangle + "Material \"diffuse\" \"texture reflectance\" \"flat\"\n" + kTriangle +
          "Material \"dielectric\" \"texture roughness\" \"rough\"\n" + kTriangle);
  ASSERT_EQ(s.mesh.triangle_count(), 5u);
  EXPECT_TRUE(s.warnings.empty()) << s.warnings.front();
  // The same remapped roughness texture is baked once.
  EXPECT_EQ(s.materials[s.mesh.material[4]].roughness_texture,
            s.materials[s.mesh.material[1]].roughness_texture);
  const Material& dim = s.materials[s.mesh.material[0]];
  // An image times a constant keeps the image and scales it.
  ASSERT_GE(dim.albedo_texture, 0);
  EXPECT_TRUE(near(dim.albedo, Rgb(0.5f)));
  EXPECT_TRUE(near(s.textures[size_t(dim.albedo_texture)].at(0, 0), Rgb(0.2f, 0.4f, 0.6f)));
  // The mix is baked: 0.75 wood + 0.25 blue.
  const Material& coated = s.materials[s.mesh.material[1]];
  ASSERT_GE(coated.albedo_texture, 0);
  EXPECT_TRUE(near(coated.albedo, Rgb(1)));
  const Image& blend = s.textures[size_t(coated.albedo_texture)];
  EXPECT_TRUE(near(blend.at(0, 0), Rgb(0.15f, 0.3f, 0.7f)));
  EXPECT_TRUE(near(blend.at(1, 0), Rgb(0.75f, 0.75f, 1)));
  // Roughness textures become images of GGX alphas: sqrt(0.25) = 0.5, sqrt(0.64) = 0.8.
  ASSERT_GE(coated.roughness_texture, 0);
  EXPECT_NEAR(s.textures[size_t(coated.roughness_texture)].at(0, 0).x, 0.5f, 1e-6);
  EXPECT_NEAR(s.textures[size_t(coated.roughness_texture)].at(1, 0).x, 0.8f, 1e-6);
  const Material& metal = s.materials[s.mesh.material[2]];
  ASSERT_GE(metal.roughness_texture, 0);
  EXPECT_NE(metal.roughness_texture, coated.roughness_texture);  // not remapped: another image
  EXPECT_NEAR(s.textures[size_t(metal.roughness_texture)].at(1, 0).x, 0.64f, 1e-6);
  // Constants mix to a constant: half red, half green.
  const Material& flat = s.materials[s.mesh.material[3]];
  EXPECT_EQ(flat.albedo_texture, -1);
  EXPECT_TRUE(near(flat.albedo, Rgb(0.5f, 0.5f, 0)));
  // A texture that was never defined is an error (as in pbrt-v4), naming it, the file and the
  // parameter's line.
  expect_mentions(
      pbrt_error(dir, std::string(kCamera) +
                          "Material \"diffuse\"\n  \"texture reflectance\" \"nosuch\"\n" +
                          kTriangle),
      {"bad.pbrt:7:", "Material \"diffuse\"", "reflectance", "texture \"nosuch\"", "not defined"});
}

TEST(PbrtReader, ConductorsFromNamedSpectraRgbFloatAndReflectance) {
  TempDir dir;
  Scene s = read_pbrt(
      dir, std::string(kCamera) +
               "Material \"conductor\" \"spectrum eta\" \"metal-Al-eta\" \"spectrum k\" "
               "\"metal-Al-k\" \"float uroughness\" 0.04 \"float vroughness\" 0.16\n" +
               kTriangle +
               "Material \"conductor\" \"rgb eta\" [ 0.2 0.3 0.4 ] \"rgb k\" [ 3 2 1 ] "
               "\"float roughness\" 0.09 \"bool remaproughness\" false\n" +
               kTriangle + "Material \"conductor\" \"float eta\" 1.7 \"float k\" 2\n" + kTriangle +
               "Material \"conductor\" \"rgb reflectance\" [ 0.5 0.2 0.9 ]\n" + kTriangle +
               "Material \"conductor\" \"spectrum eta\" \"metal-TiO2-eta\" \"spectrum k\" "
               "\"metal-TiO2-k\"\n" +
               kTriangle + "Material \"conductor\"\n" + kTriangle);
  const auto mat = [&](int i) { return s.materials[s.mesh.material[size_t(i)]]; };
  EXPECT_EQ(mat(0).type, MaterialType::Conductor);
  EXPECT_TRUE(near(mat(0).eta, Rgb(1.65746f, 0.880369f, 0.521229f)));
  EXPECT_TRUE(near(mat(0).k, Rgb(9.22387f, 6.26952f, 4.837f)));
  // Each of u and v mapped to alpha = sqrt(roughness), then averaged: (0.2 + 0.4) / 2.
  EXPECT_NEAR(mat(0).roughness, 0.3f, 1e-6);
  EXPECT_TRUE(near(mat(1).eta, Rgb(0.2f, 0.3f, 0.4f)));
  EXPECT_TRUE(near(mat(1).k, Rgb(3, 2, 1)));
  EXPECT_NEAR(mat(1).roughness, 0.09f, 1e-7);  // not remapped
  EXPECT_TRUE(near(mat(2).eta, Rgb(1.7f)));
  EXPECT_TRUE(near(mat(2).k, Rgb(2)));
  // Reflectance: eta = 1, k = 2 sqrt(r) / sqrt(1 - r), so that the Fresnel reflectance at normal
  // incidence, k^2 / (4 + k^2), is r.
  EXPECT_TRUE(near(mat(3).eta, Rgb(1)));
  const Rgb r(0.5f, 0.2f, 0.9f);
  for (int i = 0; i < 3; ++i) {
    const float k = mat(3).k[i];
    EXPECT_NEAR(k * k / (4 + k * k), r[i], 1e-5);
  }
  EXPECT_TRUE(near(mat(4).eta, Rgb(2.574f, 2.648f, 2.813f)));
  EXPECT_TRUE(near(mat(4).k, Rgb(0)));
  // pbrt's default conductor: copper, smooth.
  EXPECT_TRUE(near(mat(5).eta, Rgb(0.200438f, 0.924033f, 1.10221f)));
  EXPECT_FLOAT_EQ(mat(5).roughness, 0);
  EXPECT_TRUE(s.warnings.empty());
}

TEST(PbrtReader, DielectricThinAndCoatedDiffuseMapToRllsModels) {
  TempDir dir;
  Scene s = read_pbrt(
      dir, std::string(kCamera) +
               "Material \"dielectric\" \"float eta\" 1.33 \"float roughness\" 0.01\n" + kTriangle +
               "Material \"dielectric\" \"spectrum eta\" \"glass-BK7\"\n" + kTriangle +
               "Material \"thindielectric\" \"float eta\" 1.4\n" + kTriangle +
               "Material \"coateddiffuse\" \"rgb reflectance\" [ 0.1 0.2 0.3 ] \"float roughness\" "
               "0.25 \"float thickness\" 0.05 \"float eta\" 1.6\n" +
               kTriangle + "Material \"coateddiffuse\"\n" + kTriangle);
  const auto mat = [&](int i) { return s.materials[s.mesh.material[size_t(i)]]; };
  EXPECT_EQ(mat(0).type, MaterialType::Dielectric);
  EXPECT_FLOAT_EQ(mat(0).ior, 1.33f);
  EXPECT_NEAR(mat(0).roughness, 0.1f, 1e-7);
  EXPECT_NEAR(mat(1).ior, 1.5168f, 1e-6);
  EXPECT_EQ(mat(2).type, MaterialType::ThinDielectric);
  EXPECT_FLOAT_EQ(mat(2).ior, 1.4f);
  EXPECT_EQ(mat(3).type, MaterialType::CoatedDiffuse);
  EXPECT_TRUE(near(mat(3).albedo, Rgb(0.1f, 0.2f, 0.3f)));
  EXPECT_NEAR(mat(3).roughness, 0.5f, 1e-7);
  EXPECT_FLOAT_EQ(mat(3).thickness, 0.05f);
  EXPECT_FLOAT_EQ(mat(3).ior, 1.6f);
  // pbrt-v4's defaults: reflectance 0.5, roughness 0, thickness 0.01, eta 1.5.
  EXPECT_TRUE(near(mat(4).albedo, Rgb(0.5f)));
  EXPECT_FLOAT_EQ(mat(4).roughness, 0);
  EXPECT_FLOAT_EQ(mat(4).thickness, 0.01f);
  EXPECT_FLOAT_EQ(mat(4).ior, 1.5f);
  EXPECT_TRUE(s.warnings.empty());
}

TEST(PbrtReader, ThinLensAndScreenWindow) {
  TempDir dir;
  std::string cam = kCamera;
  cam.replace(cam.find("[ 40 ]"), 6,
              "[ 40 ] \"float lensradius\" 0.1 \"float focaldistance\" 4 "
              "\"float screenwindow\" [ 0 1 -0.5 0.5 ]");
  Scene s = read_pbrt(dir, cam + kTriangle);
  EXPECT_FLOAT_EQ(s.camera.lens_radius, 0.1f);
  EXPECT_FLOAT_EQ(s.camera.focal_distance, 4);
  EXPECT_FLOAT_EQ(s.camera.screen_window[0], 0);
  EXPECT_FLOAT_EQ(s.camera.screen_window[3], 0.5f);
  s.camera.setup(s.width, s.height);
  // The screen window [0, 1] x [-0.5, 0.5]: the image's left edge looks straight ahead, its top
  // edge up by tan(20 deg) / 2.
  const Ray left = s.camera.generate_ray(0, 16);
  EXPECT_TRUE(near(left.d, Vec3(0, 0, -1), 1e-5f));
  const Ray top = s.camera.generate_ray(0, 0);
  EXPECT_NEAR(top.d.y / -top.d.z, std::tan(20 * M_PI / 180) / 2, 1e-5);
  // Every lens sample's ray through one pixel meets the others in the plane of focus, z = 1
  // (4 in front of the camera at z = 5), and leaves from within the lens's radius.
  Vec3 focus[3];
  int i = 0;
  for (Vec2 u : {Vec2{0.5f, 0.5f}, Vec2{0.1f, 0.9f}, Vec2{0.95f, 0.3f}}) {
    const Ray r = s.camera.generate_ray(40, 10, u);
    EXPECT_LE(length(r.o - s.camera.position), 0.1f + 1e-6f);
    const float t = (1 - r.o.z) / r.d.z;
    focus[i++] = r.o + r.d * t;
  }
  EXPECT_TRUE(near(focus[0], focus[1], 1e-4f));
  EXPECT_TRUE(near(focus[0], focus[2], 1e-4f));
  EXPECT_FALSE(near(s.camera.generate_ray(40, 10, {0.1f, 0.9f}).o, s.camera.position, 1e-3f));
  // Without a lens the two-argument call is the pinhole ray, unchanged.
  Scene pin = read_pbrt(dir, std::string(kCamera) + kTriangle);
  EXPECT_FALSE(pin.camera.has_lens());
  expect_mentions(pbrt_error(dir, "Camera \"perspective\" \"float screenwindow\" [ 1 0 0 1 ]\n"),
                  {"bad.pbrt:1:", "screenwindow"});
}

TEST(PbrtReader, FilmIsoAndShutterScaleEmission) {
  TempDir dir;
  const std::string scene = kTriangle +
                            std::string(
                                "AttributeBegin AreaLightSource \"diffuse\" \"rgb L\" "
                                "[ 1 2 3 ]\n") +
                            kTriangle +
                            "AttributeEnd\n"
                            "LightSource \"point\" \"rgb I\" [ 1 1 1 ]\n"
                            "LightSource \"infinite\" \"rgb L\" [ 0.5 0.5 0.5 ]\n";
  std::string cam = kCamera;
  cam.replace(cam.find("[ 40 ]"), 6, "[ 40 ] \"float shutterclose\" 0.5");
  cam.replace(cam.find("\"integer yresolution\" 32"), 24,
              "\"integer yresolution\" 32 \"float iso\" 800");
  Scene s = read_pbrt(dir, cam + scene);
  // Imaging ratio: exposure time 0.5 * ISO 800 / 100 = 4.
  EXPECT_TRUE(near(s.materials[s.mesh.material[1]].emission, Rgb(4, 8, 12)));
  EXPECT_TRUE(near(s.lights[0].radiance, Rgb(4)));
  EXPECT_TRUE(near(s.sky->radiance, Rgb(2)));
  EXPECT_TRUE(s.warnings.empty());
  Scene plain = read_pbrt(dir, std::string(kCamera) + scene);
  EXPECT_TRUE(near(plain.materials[plain.mesh.material[1]].emission, Rgb(1, 2, 3)));
}

TEST(PbrtReader, OptionIsIgnoredAndOnlySrgbIsAColorSpace) {
  TempDir dir;
  Scene s = read_pbrt(dir,
                      "Option \"bool disablepixeljitter\" true\n"
                      "Option \"string rendercoordsys\" \"world\"\n"
                      "ColorSpace \"srgb\"\n" +
                          std::string(kCamera) + kTriangle);
  EXPECT_EQ(s.mesh.triangle_count(), 1u);
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_TRUE(has_warning(s, {"s.pbrt:1:", "Option", "ignored", "1 more"}));
  // rll's own pixel filter is pbrt's box of radius 0.5; another is announced.
  Scene box = read_pbrt(
      dir, "PixelFilter \"box\" \"float xradius\" 0.5\n" + std::string(kCamera) + kTriangle);
  EXPECT_TRUE(box.warnings.empty());
  Scene gauss = read_pbrt(dir, "PixelFilter \"gaussian\"\n" + std::string(kCamera) + kTriangle);
  EXPECT_TRUE(has_warning(gauss, {"s.pbrt:1:", "PixelFilter \"gaussian\"", "box"}));
  expect_mentions(pbrt_error(dir, "ColorSpace \"aces2065-1\"\n"),
                  {"bad.pbrt:1:", "ColorSpace \"aces2065-1\"", "srgb"});
}
