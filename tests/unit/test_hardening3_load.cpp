// Scene and image readers under hostile or careless input (issue 42): every size a header claims
// is checked against its data and the memory budget before it is allocated (PNG, JPEG, HDR, EXR,
// PLY and .ply.gz), a light's image with a negative or non-finite texel is refused naming the
// texel (environment maps as the other image lights), pbrt-v4 parameters rll clamps or ignores
// are said, and messages name the file, the line, the light and what was wrong.
#include <gtest/gtest.h>
#include <stb/stb_image_write.h>
#include <zlib.h>

#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>

#include "rll/core/error.h"
#include "rll/core/image.h"
#include "rll/core/memory_budget.h"
#include "rll/io/load.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;
namespace fs = std::filesystem;

namespace {

// --- images ---

std::string png_chunk(const char* type, const std::string& data) {
  std::string out;
  const auto n = uint32_t(data.size());
  for (int s = 24; s >= 0; s -= 8) out += char((n >> s) & 0xff);
  out += std::string(type, 4) + data;
  uLong crc = crc32(0, reinterpret_cast<const Bytef*>(type), 4);
  crc = crc32(crc, reinterpret_cast<const Bytef*>(data.data()), uInt(data.size()));
  for (int s = 24; s >= 0; s -= 8) out += char((crc >> s) & 0xff);
  return out;
}

// A PNG whose header claims w x h 8-bit RGB pixels, with `idat` as its compressed data.
std::string png_claiming(uint32_t w, uint32_t h, const std::string& idat) {
  std::string ihdr;
  for (uint32_t v : {w, h})
    for (int s = 24; s >= 0; s -= 8) ihdr += char((v >> s) & 0xff);
  ihdr += std::string("\x08\x02\x00\x00\x00", 5);
  return std::string("\x89PNG\r\n\x1a\n", 8) + png_chunk("IHDR", ihdr) + png_chunk("IDAT", idat) +
         png_chunk("IEND", "");
}

std::string zlib_zeros(size_t n) {
  std::string in(n, '\0'), out(compressBound(uLong(n)), '\0');
  uLongf size = uLongf(out.size());
  compress2(reinterpret_cast<Bytef*>(out.data()), &size, reinterpret_cast<const Bytef*>(in.data()),
            uLong(n), 9);
  out.resize(size);
  return out;
}

// --- PLY ---

std::string ply_header(size_t vertices, size_t faces) {
  return "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(vertices) +
         "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
         std::to_string(faces) + "\nproperty list uchar int vertex_indices\nend_header\n";
}
// A binary PLY of `vertices` vertices at the origin and one face.
std::string ply_with(size_t vertices) {
  std::string out = ply_header(vertices, 1) + std::string(vertices * 12, '\0') + '\3';
  for (int32_t i : {0, 1, 2}) out.append(reinterpret_cast<const char*>(&i), 4);
  return out;
}

// --- pbrt ---

const char* kPbrtHead =
    "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"\n"
    "Film \"rgb\" \"integer xresolution\" [ 8 ] \"integer yresolution\" [ 8 ]\nWorldBegin\n";
const char* kQuad =
    "Shape \"bilinearmesh\" \"point3 P\" [ -1 -1 0 1 -1 0 -1 1 0 1 1 0 ] \"point2 uv\" "
    "[ 0 0 1 0 0 1 1 1 ]\n";
const char* kLight = "LightSource \"point\" \"rgb I\" [ 1 1 1 ] \"point3 from\" [ 0 0 3 ]\n";

LoadOptions quiet() {
  LoadOptions o;
  o.print_warnings = false;
  return o;
}

// The scene file's text, loaded quietly from `dir`.
Scene load_text(const TempDir& dir, const std::string& name, const std::string& text) {
  return load_scene(dir.write(name, text).string(), quiet());
}

std::string all_warnings(const Scene& s) {
  std::string out;
  for (const auto& w : s.warnings) out += w + "\n";
  return out;
}

// A 2x2 EXR with `bad` at texel (1, 0) and 0.5 elsewhere.
fs::path exr_with(const TempDir& dir, const std::string& name, Rgb bad) {
  Image img(2, 2, Rgb(0.5f));
  img.at(1, 0) = bad;
  const fs::path p = dir / name;
  write_image(p, img);
  return p;
}

}  // namespace

// --- class 3: memory from small inputs ---

TEST(Hardening3Memory, PngClaimsAreCheckedAgainstTheirCompressedData) {
  // stb_image allocates what the header claims (805 MB for 16384^2 RGB) before it inflates: an
  // 80-byte file is refused by its IDAT size, which inflates to 4 KB at most.
  TempDir dir;
  const std::string png = png_claiming(16384, 16384, zlib_zeros(4096));
  ASSERT_LT(png.size(), 100u);
  const auto p = dir.write("huge.png", png);
  expect_mentions(error_of([&] { read_image(p); }),
                  {"huge.png", "16384x16384", "compressed data (IDAT)", "inflate to at most"});
  // As glTF images and textures in memory are decoded.
  expect_mentions(error_of([&] {
                    decode_image(reinterpret_cast<const unsigned char*>(png.data()), png.size(),
                                 true, "scene.gltf: image 0");
                  }),
                  {"scene.gltf: image 0", "16384x16384", "IDAT"});
}

TEST(Hardening3Memory, ImageDecodingIsHeldToTheMemoryBudget) {
  // The issue's case: 16384^2 pixels in an 800 KB PNG (compressed data enough to hold them)
  // take about 4 GB to decode; under a 1 GiB budget that is refused before stb_image starts.
  BudgetScope budget(size_t(1) << 30);
  TempDir dir;
  const auto p = dir.write("big.png", png_claiming(16384, 16384, std::string(800000, '\0')));
  expect_mentions(error_of([&] { read_image(p); }),
                  {"big.png", "16384x16384 pixels take 3.8 GiB to decode",
                   "more than the 1.0 GiB a scene may use", "use a smaller image"});
}

TEST(Hardening3Memory, EveryImageFormatIsHeldToTheBudget) {
  // Variants: a Radiance HDR (run-length coded, so small), an EXR, and a JPEG whose header
  // claims more 8x8 blocks than the file has bits.
  TempDir dir;
  const int w = 400, h = 300;
  std::vector<float> px(size_t(w) * h * 3, 0.5f);
  std::string hdr;
  auto append = [](void* context, void* data, int size) {
    static_cast<std::string*>(context)->append(static_cast<const char*>(data), size_t(size));
  };
  ASSERT_TRUE(stbi_write_hdr_to_func(append, &hdr, w, h, 3, px.data()));
  const auto hdr_path = dir.write("sky.hdr", hdr);
  write_image(dir / "sky.exr", Image(w, h, Rgb(0.5f)));
  EXPECT_EQ(read_image(hdr_path).width(), w);  // within the default budget: read
  {
    BudgetScope budget(size_t(1) << 20);
    expect_mentions(error_of([&] { read_image(hdr_path); }),
                    {"sky.hdr", "400x300 pixels take 2.7 MiB to decode", "1.0 MiB"});
    expect_mentions(error_of([&] { read_image(dir / "sky.exr"); }),
                    {"sky.exr", "400x300 pixels take 1.4 MiB once read", "1.0 MiB"});
  }
  // A BMP cut in half read as black below the cut, and a binary PPM with no data at all.
  std::vector<unsigned char> rgb(size_t(64) * 64 * 3, 200);
  std::string bmp;
  ASSERT_TRUE(stbi_write_bmp_to_func(append, &bmp, 64, 64, 3, rgb.data()));
  expect_mentions(
      error_of([&] { read_image(dir.write("cut.bmp", bmp.substr(0, bmp.size() / 2))); }),
      {"cut.bmp", "64x64 pixels, 12288 bytes of uncompressed BMP data", "truncated or hostile"});
  expect_mentions(error_of([&] { read_image(dir.write("empty.ppm", "P6\n4096 4096\n255\n")); }),
                  {"empty.ppm", "4096x4096", "binary PNM"});
  // SOI, a baseline frame of 16384 x 16384 grey pixels, EOI: 17 bytes for 4 M blocks.
  const std::string jpeg = std::string(
      "\xff\xd8\xff\xc0\x00\x0b\x08\x40\x00\x40\x00\x01\x01\x11\x00"
      "\xff\xd9",
      17);
  expect_mentions(error_of([&] { read_image(dir.write("huge.jpg", jpeg)); }),
                  {"huge.jpg", "16384x16384", "4194304 blocks", "only 17 bytes", "JPEG"});
}

TEST(Hardening3Memory, GzipPlyClaimsAreCheckedBeforeInflating) {
  // The issue's case in small: a header claiming 300 M vertices (3.6 GB) in a gzip file of a
  // few hundred bytes, which cannot inflate to that much.
  TempDir dir;
  const auto p =
      dir.write("claims.ply.gz", gzip(ply_header(300000000, 1) + std::string(65536, '\0'), 9));
  expect_mentions(
      error_of([&] { read_ply_file(p); }),
      {"claims.ply.gz", "300000000 vertices (line 3)", "inflate to at most", "damaged or hostile"});
}

TEST(Hardening3Memory, PlyCountsAreCheckedWithTheMeshTheyMake) {
  // 1 M vertices whose data is all there (12 MB, compressed at level 1 well within deflate's
  // limit) make a mesh of 12 MB: under a 4 MiB budget the header's counts are refused before
  // the body is inflated, and a plain file before the mesh is allocated.
  TempDir dir;
  const std::string ply = ply_with(1000000);
  const auto gz = dir.write("big.ply.gz", gzip(ply, 1));
  const auto plain = dir.write("big.ply", ply);
  BudgetScope budget(size_t(4) << 20);
  expect_mentions(error_of([&] { read_ply_file(gz); }),
                  {"big.ply.gz", "1000000 vertices (line 3) and 1 face (line 7)",
                   "11.4 MiB as a mesh", "more than the 4.0 MiB a scene may use"});
  expect_mentions(error_of([&] { read_ply_file(plain); }),
                  {"big.ply", "1000000 vertices", "as a mesh", "11.4 MiB of file data"});
}

TEST(Hardening3Memory, AJsonSkyOfMillionsOfTrianglesIsCountedAsGeometry) {
  // 40 bytes of JSON asking for 4 M dome triangles (about 640 MiB with their acceleration
  // structure), refused at the field before the dome is built.
  BudgetScope budget(size_t(16) << 20);
  TempDir dir;
  const auto p = dir.write(
      "sky.json", R"({"sky": {"type": "dome", "triangles": 4194304, "radiance": [1, 1, 1]}})");
  expect_mentions(error_of([&] { read_scene(p.string()); }),
                  {"/sky/triangles", "4194304 triangles", "more than the 16.0 MiB"});
}

// --- class 4: silent wrong results ---

TEST(Hardening3Emission, InfiniteLightMapsWithBadTexelsAreRefusedAsOtherImageLights) {
  TempDir dir;
  auto scene = [&](const char* map) {
    return std::string(kPbrtHead) + "LightSource \"infinite\" \"string filename\" \"" + map +
           "\"\n" + kQuad;
  };
  exr_with(dir, "negative.exr", Rgb(-1, 0.5f, 0.5f));
  exr_with(dir, "nan.exr", Rgb(0.5f, std::nanf(""), 0.5f));
  exr_with(dir, "inf.exr", Rgb(std::numeric_limits<float>::infinity(), 0.5f, 0.5f));
  expect_mentions(error_of([&] { load_text(dir, "a.pbrt", scene("negative.exr")); }),
                  {"a.pbrt:5", "LightSource \"infinite\"", "negative.exr",
                   "texel (1, 0) is (-1, 0.5, 0.5)", "no light can emit"});
  expect_mentions(error_of([&] { load_text(dir, "b.pbrt", scene("nan.exr")); }),
                  {"b.pbrt:5", "texel (1, 0) is (0.5, nan, 0.5)"});
  expect_mentions(error_of([&] { load_text(dir, "c.pbrt", scene("inf.exr")); }),
                  {"c.pbrt:5", "texel (1, 0) is (inf, 0.5, 0.5)"});
  // The same check, naming the texel, for the other lights' images.
  expect_mentions(error_of([&] {
                    load_text(dir, "d.pbrt",
                              std::string(kPbrtHead) +
                                  "AreaLightSource \"diffuse\" \"string filename\" \"nan.exr\"\n" +
                                  kQuad);
                  }),
                  {"d.pbrt:5", "AreaLightSource", "texel (1, 0) is (0.5, nan, 0.5)"});
}

TEST(Hardening3Emission, JsonSkyMapsAndSkiesMadeInCodeAreCheckedToo) {
  TempDir dir;
  exr_with(dir, "sky.exr", Rgb(-2, 0, 0));
  const std::string json =
      R"({"shapes": [{"type": "quad", "origin": [0, 0, 0], "edge1": [1, 0, 0], "edge2": [0, 1, 0],
          "material": {"albedo": [0.5, 0.5, 0.5]}}],
          "sky": {"type": "dome", "image": "sky.exr"}})";
  expect_mentions(error_of([&] { load_text(dir, "s.json", json); }),
                  {"/sky/image", "sky.exr", "texel (1, 0) is (-2, 0, 0)"});
  // A scene made in code: finalize() refuses it, naming the sky.
  Scene s;
  s.source = "code";
  s.mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  s.mesh.triangles = {{0, 1, 2}};
  s.mesh.material = {0};
  s.mesh.light = {-1};
  s.materials.push_back(Material{});
  auto map = std::make_shared<EnvironmentMap>();
  map->image = Image(2, 2, Rgb(1));
  map->image.at(0, 1) = Rgb(std::nanf(""));
  SkyDome sky;
  sky.map = map;
  s.sky = sky;
  expect_mentions(error_of([&] { s.finalize(); }),
                  {"code: the sky's environment map", "texel (0, 1) is (nan, nan, nan)"});
}

TEST(Hardening3Obj, MapKeMakesATexturedEmitter) {
  TempDir dir;
  Image lamp(2, 2, Rgb(0.25f));
  lamp.at(0, 0) = Rgb(1, 0.5f, 0);
  write_image(dir / "lamp.png", lamp);
  const std::string obj =
      "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n"
      "usemtl lamp\nf 1/1 2/2 3/3\n";
  // No Ke: the texture's own colours, as an absent Kd with a map_Kd.
  dir.write("m.mtl", "newmtl lamp\nKd 0 0 0\nmap_Ke lamp.png\n");
  const Scene s = load_text(dir, "lamp.obj", obj);
  ASSERT_EQ(s.materials.size(), 1u);
  EXPECT_GE(s.materials[0].emission_texture, 0);
  EXPECT_EQ(s.materials[0].emission, Rgb(1));
  ASSERT_FALSE(s.lights.empty());
  EXPECT_TRUE(s.lights[0].textured);
  // Ke scales the texture.
  dir.write("m.mtl", "newmtl lamp\nKd 0 0 0\nKe 4 4 4\nmap_Ke lamp.png\n");
  EXPECT_EQ(load_text(dir, "lamp2.obj", obj).materials[0].emission, Rgb(4));
}

TEST(Hardening3Obj, MapKeThatCannotShowAndIgnoredMapsAreSaid) {
  TempDir dir;
  write_image(dir / "lamp.png", Image(2, 2, Rgb(1, 0, 0)));
  // Without texture coordinates: the mean colour, said.
  dir.write("m.mtl", "newmtl lamp\nKd 0 0 0\nKe 2 2 2\nmap_Ke lamp.png\nmap_Bump bump.png\n");
  const Scene s =
      load_text(dir, "a.obj", "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl lamp\nf 1 2 3\n");
  EXPECT_EQ(s.materials[0].emission_texture, -1);
  EXPECT_EQ(s.materials[0].emission, Rgb(2, 0, 0));
  expect_mentions(all_warnings(s),
                  {"m.mtl:4: material 'lamp': map_Ke 'lamp.png'", "no texture coordinates (vt)",
                   "mean colour", "map_Bump (", "m.mtl:5", "rll reads map_Kd and map_Ke"});
  // A black Ke hides the texture: said, naming the line of the map_Ke.
  dir.write("k.mtl", "newmtl dark\nKd 0.5 0.5 0.5\nKe 0 0 0\n\nmap_Ke lamp.png\n");
  const Scene d = read_scene(
      dir.write("b.obj", "mtllib k.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl dark\nf 1 2 3\n")
          .string());
  EXPECT_FALSE(d.materials[0].is_emissive());
  expect_mentions(all_warnings(d),
                  {"k.mtl:5: material 'dark': map_Ke 'lamp.png' has no effect", "its Ke is 0"});
}

TEST(Hardening3Pbrt, ReflectanceAboveOneIsClampedAsPbrtV4DoesAndSaidOnce) {
  TempDir dir;
  const Scene s = load_text(dir, "r.pbrt",
                            std::string(kPbrtHead) + kLight +
                                "Material \"diffuse\" \"rgb reflectance\" [ 1.5 0.5 2 ]\n" + kQuad +
                                "Material \"coateddiffuse\" \"float reflectance\" 3\n" + kQuad);
  ASSERT_GE(s.materials.size(), 2u);
  EXPECT_EQ(s.materials[0].albedo, Rgb(1, 0.5f, 1));
  EXPECT_EQ(s.materials[1].albedo, Rgb(1));
  const std::string w = all_warnings(s);
  expect_mentions(w, {"r.pbrt:6", "\"rgb reflectance\" is (1.5, 0.5, 2)",
                      "clamped to [0, 1], as pbrt-v4 does", "(and 1 more times)"});
  // A texture beyond 1 (an EXR times a scale) is clamped texel by texel.
  Image tex(2, 1, Rgb(0.25f));
  tex.at(1, 0) = Rgb(0.5f, 2, 0.1f);
  write_image(dir / "t.exr", tex);
  const Scene t = load_text(dir, "t.pbrt",
                            std::string(kPbrtHead) + kLight +
                                "Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" "
                                "\"t.exr\" \"float scale\" 3\n"
                                "Material \"diffuse\" \"texture reflectance\" \"t\"\n" +
                                kQuad);
  const Material& m = t.materials[0];
  ASSERT_GE(m.albedo_texture, 0);
  EXPECT_EQ(m.albedo, Rgb(1));
  const Image& baked = t.textures[size_t(m.albedo_texture)];
  EXPECT_EQ(baked.at(0, 0), Rgb(0.75f));  // within [0, 1]: the texel times its scale
  EXPECT_EQ(baked.at(1, 0), Rgb(1, 1, 0.1f * 3));
  expect_mentions(all_warnings(t), {"t.pbrt:7", "has texels outside [0, 1]", "clamped"});
}

TEST(Hardening3Pbrt, NegativeRoughnessAndSpectraAreRefused) {
  TempDir dir;
  auto with = [&](const std::string& name, const std::string& material) {
    return error_of(
        [&] { load_text(dir, name, std::string(kPbrtHead) + kLight + material + "\n" + kQuad); });
  };
  expect_mentions(with("a.pbrt", "Material \"conductor\" \"float roughness\" -0.1"),
                  {"a.pbrt:6", "\"float roughness\"", "is negative (-0.1)", "must be 0 or more"});
  expect_mentions(with("b.pbrt", "Material \"dielectric\"\n  \"float vroughness\" -1"),
                  {"b.pbrt:7", "\"float vroughness\"", "is negative (-1)"});
  write_image(dir / "r.exr", Image(2, 2, Rgb(0.2f)));
  expect_mentions(
      with("c.pbrt",
           "Texture \"r\" \"float\" \"imagemap\" \"string filename\" \"r.exr\" \"float scale\" -1\n"
           "Material \"coateddiffuse\" \"texture roughness\" \"r\""),
      {"c.pbrt:7", "\"texture roughness\"", "at texel (0, 0)"});
  expect_mentions(with("d.pbrt", "Material \"diffuse\" \"float reflectance\" -0.5"),
                  {"d.pbrt:6", "\"float reflectance\"", "must not be negative"});
}

TEST(Hardening3Pbrt, ParametersRllIgnoresAreSaidWhereTheyChangeTheImage) {
  TempDir dir;
  write_image(dir / "t.png", Image(2, 2, Rgb(0.5f)));
  const Scene s =
      load_text(dir, "i.pbrt",
                "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float frameaspectratio\" 2\n"
                "Film \"rgb\" \"integer xresolution\" [ 8 ] \"integer yresolution\" [ 8 ]\n"
                "  \"float whitebalance\" 5000\nWorldBegin\n" +
                    std::string(kLight) +
                    "Material \"coateddiffuse\" \"integer maxdepth\" 5 \"integer nsamples\" 4\n"
                    "Material \"diffuse\" \"string normalmap\" \"n.png\"\n"
                    "Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"t.png\" "
                    "\"string wrap\" \"clamp\"\n" +
                    kQuad);
  expect_mentions(
      all_warnings(s),
      {"i.pbrt:7: Material \"coateddiffuse\": \"integer maxdepth\" 5 is ignored",
       "i.pbrt:7: Material \"coateddiffuse\": \"integer nsamples\" 4 is ignored",
       "pbrt-v4's defaults, maxdepth 10 and nsamples 1",
       "i.pbrt:8: Material \"diffuse\": parameter \"string normalmap\" is not supported",
       "i.pbrt:4: Film: parameter \"float whitebalance\" 5000 is ignored",
       "i.pbrt:9: Texture \"t\": \"string wrap\" \"clamp\" is not supported",
       "i.pbrt:2: Camera: \"float frameaspectratio\" 2 is ignored"});
  // At pbrt-v4's defaults nothing is said.
  const Scene d = load_text(
      dir, "d.pbrt",
      std::string(kPbrtHead) + kLight +
          "Material \"coateddiffuse\" \"integer maxdepth\" 10 \"integer nsamples\" 1\n" + kQuad);
  EXPECT_EQ(all_warnings(d).find("maxdepth"), std::string::npos) << all_warnings(d);
}

// --- class 6: unclear errors ---

TEST(Hardening3Messages, ALightsBadParameterNamesTheFileLineAndLight) {
  TempDir dir;
  expect_mentions(
      error_of([&] {
        load_text(dir, "p.pbrt",
                  std::string(kPbrtHead) +
                      "LightSource \"point\" \"rgb I\" [ 3e38 3e38 3e38 ] \"float scale\" 10\n" +
                      kQuad);
      }),
      {"p.pbrt:5: LightSource \"point\"", "its intensity (inf, inf, inf) is not finite"});
  expect_mentions(error_of([&] {
                    load_text(dir, "q.pbrt",
                              "Film \"rgb\" \"float iso\" 1e38\nWorldBegin\n"
                              "LightSource \"distant\" \"rgb L\" [ 1000 1000 1000 ]\n" +
                                  std::string(kQuad));
                  }),
                  {"q.pbrt:3: LightSource \"distant\"",
                   "its irradiance (inf, inf, inf) is not finite", "imaging ratio 1e+36"});
  expect_mentions(
      error_of([&] {
        load_text(dir, "a.pbrt",
                  std::string(kPbrtHead) +
                      "AreaLightSource \"diffuse\" \"rgb L\" [ 3e38 1 1 ] \"float scale\" 10\n" +
                      kQuad);
      }),
      {"a.pbrt:5: AreaLightSource: L x scale = (inf, 10, 10) is not finite"});
  // A scene made in code: finalize() names the light and its parameter.
  Scene s;
  s.source = "code";
  s.lights.push_back(make_point_light(Vec3(0), Rgb(std::numeric_limits<float>::infinity())));
  s.lights.push_back(make_spot_light(Vec3(0), Vec3(0, 0, 1), Rgb(-1, 1, 1), 0.9f, 0.8f));
  expect_mentions(error_of([&] { s.finalize(); }),
                  {"code: light 0 of 2 (a point light)", "intensity (inf, inf, inf)"});
  s.lights.erase(s.lights.begin());
  expect_mentions(error_of([&] { s.finalize(); }),
                  {"code: light 0 of 1 (a spot light)", "its intensity (-1, 1, 1) is negative"});
}

TEST(Hardening3Messages, AGltfUriNamingAFolderIsNamed) {
  using json = nlohmann::json;
  TempDir dir;
  fs::create_directory(dir / "sub");
  const float data[15] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 1};
  dir.write("buf.bin", std::string(reinterpret_cast<const char*>(data), sizeof data));
  auto doc = [&](const std::string& buffer_uri, const std::string& image_uri) {
    return json{{"asset", {{"version", "2.0"}}},
                {"buffers", {{{"byteLength", 60}, {"uri", buffer_uri}}}},
                {"bufferViews",
                 {{{"buffer", 0}, {"byteLength", 36}},
                  {{"buffer", 0}, {"byteOffset", 36}, {"byteLength", 24}}}},
                {"accessors",
                 {{{"bufferView", 0}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}},
                  {{"bufferView", 1}, {"componentType", 5126}, {"count", 3}, {"type", "VEC2"}}}},
                {"images", {{{"uri", image_uri}}}},
                {"textures", {{{"source", 0}}}},
                {"materials", {{{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}}}},
                {"meshes",
                 {{{"primitives",
                    {{{"attributes", {{"POSITION", 0}, {"TEXCOORD_0", 1}}}, {"material", 0}}}}}}},
                {"nodes", {{{"mesh", 0}}}},
                {"scenes", {{{"nodes", {0}}}}}}
        .dump();
  };
  Scene s;
  // The issue's case: std::bad_alloc before.
  expect_mentions(error_of([&] { load_gltf(dir.write("a.gltf", doc("buf.bin", ".")), s); }),
                  {"a.gltf: image 0 ('.') could not be read", "is a folder, not a file"});
  expect_mentions(error_of([&] { load_gltf(dir.write("b.gltf", doc("buf.bin", "sub")), s); }),
                  {"image 0 ('sub')", "is a folder"});
  expect_mentions(error_of([&] { load_gltf(dir.write("c.gltf", doc("sub", "x.png")), s); }),
                  {"c.gltf", "is a folder, not a file"});
}

TEST(Hardening3Messages, TransformsTooLargeForAFloatAreNotCalledSingular) {
  TempDir dir;
  auto pbrt = [&](const std::string& name, const std::string& body) {
    return error_of([&] { load_text(dir, name, std::string(kPbrtHead) + kLight + body); });
  };
  expect_mentions(pbrt("a.pbrt", "Scale 1e30 1e30 1e30\n" + std::string(kQuad)),
                  {"a.pbrt:7: Shape: the transform is too large", "scales volumes by 1e+90",
                   "lengths by about 1e+30", "scale the scene down",
                   "matrix [1e+30 0 0 0; 0 1e+30 0 0; 0 0 1e+30 0; 0 0 0 1]"});
  expect_mentions(
      pbrt("b.pbrt", "Scale 0 1 1\n" + std::string(kQuad)),
      {"b.pbrt:7: Shape: the transform is singular: its determinant is 0", "matrix [0 0 0 0;"});
  expect_mentions(pbrt("c.pbrt", "ObjectBegin \"o\"\n" + std::string(kQuad) +
                                     "ObjectEnd\nScale 1e-20 1e-20 1e-20\nObjectInstance \"o\"\n"),
                  {"c.pbrt:10: ObjectInstance: the transform is degenerate", "1e-60"});
  const std::string json =
      R"({"shapes": [{"type": "quad", "origin": [0, 0, 0], "edge1": [1, 0, 0], "edge2": [0, 1, 0],
          "material": {"emission": [1, 1, 1]}, "transform": {"scale": 1e30}}]})";
  expect_mentions(error_of([&] { load_text(dir, "t.json", json); }),
                  {"/shapes/0/transform", "scales volumes by 1e+90", "too large", "matrix [1e+30"});
}

TEST(Hardening3Messages, InfinityInAPlyIsReportedAsInfinity) {
  TempDir dir;
  const auto p = dir.write("inf.ply",
                           "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty "
                           "float y\nproperty float z\nelement face 1\nproperty list uchar int "
                           "vertex_indices\nend_header\n-inf 0 0\n1e39 0 0\nnan 0 0\n3 0 1 2\n");
  expect_mentions(error_of([&] { read_ply_file(p); }),
                  {"inf.ply:10", "vertex 0 has a non-finite position (-inf, 0, 0)"});
}

TEST(Hardening3Messages, ASkyThatEmitsNothingIsNamedNotDenied) {
  TempDir dir;
  expect_mentions(error_of([&] {
                    load_text(dir, "s.pbrt",
                              std::string(kPbrtHead) +
                                  "LightSource \"infinite\" \"rgb L\" [ 0 0 0 ]\n" + kQuad);
                  }),
                  {"s.pbrt", "it has a sky (an infinite light or environment)",
                   "the sky's radiance is (0, 0, 0)", "add a light"});
  write_image(dir / "black.exr", Image(4, 4, Rgb(0)));
  const std::string json =
      R"({"shapes": [{"type": "quad", "origin": [0, 0, 0], "edge1": [1, 0, 0], "edge2": [0, 1, 0],
          "material": {"albedo": [0.5, 0.5, 0.5]}}],
          "sky": {"type": "dome", "image": "black.exr"}})";
  expect_mentions(error_of([&] { load_text(dir, "k.json", json); }),
                  {"k.json", "it has a sky", "its map is black over the dome"});
}
