// pbrt-v4 reader: transforms, attributes, instances and includes place geometry where pbrt
// does; shapes, materials and lights map as docs/scene-format.md says; unsupported directives
// are skipped with one warning naming them and the line; syntax errors name file and line.
#include <gtest/gtest.h>

#include <cmath>

#include "rll/io/load.h"
#include "rll/io/save.h"
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
  EXPECT_EQ(coated.type, MaterialType::Plastic);
  EXPECT_FLOAT_EQ(coated.roughness, 0.01f);
  ASSERT_GE(coated.albedo_texture, 0);
  EXPECT_FLOAT_EQ(s.textures[size_t(coated.albedo_texture)].at(0, 0).x, 0.25f);
  EXPECT_TRUE(near(coated.albedo, Rgb(2)));
  const Material& glass = s.materials[s.mesh.material[2]];
  EXPECT_EQ(glass.type, MaterialType::Plastic);
  EXPECT_TRUE(near(glass.albedo, Rgb(0)));
  EXPECT_FLOAT_EQ(glass.ior, 1.33f);
  // The approximation is announced once, with the number of times it was made.
  EXPECT_TRUE(has_warning(s, {"s.pbrt:9:", "dielectric", "no transmission", "1 more"}));
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
                         "LightSource \"spot\" \"point3 from\" [0 1 0]\n" +
                         kTriangle);
  EXPECT_EQ(s.mesh.triangle_count(), 1u);
  EXPECT_TRUE(has_warning(s, {"s.pbrt:1:", "Sampler", "not supported"}));
  EXPECT_TRUE(has_warning(s, {"s.pbrt:7:", "Shape \"curve\"", "1 more"}));
  EXPECT_TRUE(has_warning(s, {"s.pbrt:9:", "MakeNamedMedium"}));
  EXPECT_TRUE(has_warning(s, {"s.pbrt:10:", "LightSource \"spot\""}));
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
  ASSERT_EQ(lost.size(), 1u);  // the hemisphere, as a map with a black lower half
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
  EXPECT_EQ(p.type, MaterialType::Plastic);
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
