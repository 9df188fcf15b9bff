// Every material type through every format rll writes: JSON keeps every field exactly, pbrt-v4
// and glTF keep what they can express (and the writers name what they cannot); the JSON reader
// rejects fields that do not apply, the glTF reader maps transmission and ior to glass.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <fstream>
#include <sstream>

#include "rll/core/error.h"
#include "rll/io/load.h"
#include "rll/io/save.h"
#include "support/test_support.h"

using namespace rll;
using rll::test::error_of;
using rll::test::TempDir;

namespace {


bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

bool any_contains(const std::vector<std::string>& v, const std::string& part) {
  for (const auto& s : v)
    if (contains(s, part)) return true;
  return false;
}

bool near(const Rgb& a, const Rgb& b, float tol = 1e-5f) {
  return std::abs(a.x - b.x) <= tol && std::abs(a.y - b.y) <= tol && std::abs(a.z - b.z) <= tol;
}

// One material of every type, each with values other than the defaults, on one triangle each
// (with uvs), and a roughness texture; a point light so that the scene can be finalized.
Scene every_material_scene() {
  Scene a;
  a.source = "test:every-material";
  Image albedo(2, 2);
  for (size_t i = 0; i < albedo.pixel_count(); ++i)
    albedo[i] = Rgb(0.2f + 0.1f * float(i), 0.5f, 0.7f);
  a.textures.push_back(albedo);  // 0: albedo
  Image rough(2, 2);
  for (size_t i = 0; i < rough.pixel_count(); ++i) rough[i] = Rgb(0.04f + 0.2f * float(i));
  a.textures.push_back(rough);  // 1: roughness

  Material diffuse;
  diffuse.name = "diffuse";
  diffuse.albedo = Rgb(0.6f, 0.5f, 0.4f);
  Material metal;
  metal.name = "metal";
  metal.type = MaterialType::Conductor;
  metal.eta = Rgb(0.18f, 0.42f, 1.37f);
  metal.k = Rgb(3.42f, 2.35f, 1.77f);
  metal.roughness = 0.15f;
  Material plastic;
  plastic.name = "plastic";
  plastic.type = MaterialType::Plastic;
  plastic.albedo = Rgb(0.1f, 0.3f, 0.6f);
  plastic.roughness = 0.05f;
  plastic.ior = 1.4f;
  Material glass;
  glass.name = "glass";
  glass.type = MaterialType::Dielectric;
  glass.ior = 1.33f;
  glass.roughness = 0.09f;
  Material pane;
  pane.name = "pane";
  pane.type = MaterialType::ThinDielectric;
  pane.ior = 1.52f;
  pane.roughness = 0;
  Material coated;
  coated.name = "coated";
  coated.type = MaterialType::CoatedDiffuse;
  coated.albedo = Rgb(0.7f, 0.2f, 0.1f);
  coated.roughness = 0.01f;
  coated.ior = 1.6f;
  coated.thickness = 0.05f;
  Material textured;  // a textured albedo and a textured roughness
  textured.name = "textured";
  textured.type = MaterialType::CoatedDiffuse;
  textured.albedo = Rgb(1);
  textured.albedo_texture = 0;
  textured.roughness_texture = 1;
  textured.ior = 1.5f;
  Material rough_metal;
  rough_metal.name = "rough metal";
  rough_metal.type = MaterialType::Conductor;
  rough_metal.eta = kTintableEta;
  rough_metal.k = kTintableK;
  rough_metal.roughness_texture = 1;
  Material lamp;
  lamp.name = "lamp";
  lamp.albedo = Rgb(0);
  lamp.emission = Rgb(3, 2, 1);
  lamp.two_sided_emission = true;
  for (const Material& m :
       {diffuse, metal, plastic, glass, pane, coated, textured, rough_metal, lamp})
    a.materials.push_back(m);
  for (uint32_t k = 0; k < a.materials.size(); ++k) {
    const uint32_t v = uint32_t(a.mesh.positions.size());
    const float x = float(k);
    a.mesh.positions.insert(a.mesh.positions.end(), {{x, 0, 0}, {x + 1, 0, 0}, {x, 1, 0.5f}});
    a.mesh.uvs.insert(a.mesh.uvs.end(), {{0, 0}, {1, 0}, {0, 1}});
    a.mesh.triangles.push_back({v, v + 1, v + 2});
    a.mesh.material.push_back(k);
  }
  a.mesh.light.assign(a.mesh.triangle_count(), -1);
  a.lights.push_back(make_point_light(Vec3(1, 2, 3), Rgb(4, 5, 6)));
  a.width = 32;
  a.height = 24;
  return a;
}

const Material& material_of(const Scene& s, uint32_t triangle) {
  return s.materials[s.mesh.material[triangle]];
}

void expect_same_texture(const Scene& a, int ia, const Scene& b, int ib, float tol) {
  ASSERT_EQ(ia >= 0, ib >= 0);
  if (ia < 0) return;
  const Image &x = a.textures[size_t(ia)], &y = b.textures[size_t(ib)];
  ASSERT_EQ(x.width(), y.width());
  ASSERT_EQ(x.height(), y.height());
  for (size_t i = 0; i < x.pixel_count(); ++i) EXPECT_TRUE(near(x[i], y[i], tol)) << "pixel " << i;
}

// Every field of every material, exactly (the JSON round trip).
void expect_identical(const Scene& a, const Material& x, const Scene& b, const Material& y) {
  SCOPED_TRACE(x.name);
  EXPECT_EQ(x.type, y.type);
  EXPECT_EQ(x.albedo, y.albedo);
  EXPECT_EQ(x.specular, y.specular);
  EXPECT_EQ(x.eta, y.eta);
  EXPECT_EQ(x.k, y.k);
  EXPECT_EQ(x.ior, y.ior);
  EXPECT_EQ(x.roughness, y.roughness);
  EXPECT_EQ(x.thickness, y.thickness);
  EXPECT_EQ(x.emission, y.emission);
  EXPECT_EQ(x.two_sided_emission, y.two_sided_emission);
  expect_same_texture(a, x.albedo_texture, b, y.albedo_texture, 0);
  expect_same_texture(a, x.roughness_texture, b, y.roughness_texture, 0);
}

// The scene as `rll convert` has it when it reads the JSON file rll wrote of it.
Scene converted_source(const TempDir& dir) {
  save_json_scene(every_material_scene(), dir / "source.json");
  return read_scene((dir / "source.json").string());
}

}  // namespace

// --- JSON ---

TEST(MaterialFormats, JsonKeepsEveryMaterialTypeExactly) {
  TempDir dir;
  const Scene a = every_material_scene();
  save_json_scene(a, dir / "all.json");
  const std::string text = rll::test::read_text(dir / "all.json");
  for (const char* t : {"\"dielectric\"", "\"thindielectric\"", "\"coateddiffuse\"",
                        "\"thickness\"", "\"roughness_texture\""})
    EXPECT_TRUE(contains(text, t)) << t;
  LoadOptions quiet;
  quiet.print_warnings = false;
  const Scene b = load_scene((dir / "all.json").string(), quiet);
  EXPECT_TRUE(b.warnings.empty()) << ::testing::PrintToString(b.warnings);
  ASSERT_EQ(b.mesh.triangle_count(), a.mesh.triangle_count());
  for (uint32_t t = 0; t < a.mesh.triangle_count(); ++t)
    expect_identical(a, material_of(a, t), b, material_of(b, t));

  // A second round (JSON -> load -> save -> load) changes nothing either.
  TempDir again;
  save_json_scene(b, again / "all.json");
  const Scene c = load_scene((again / "all.json").string(), quiet);
  for (uint32_t t = 0; t < a.mesh.triangle_count(); ++t)
    expect_identical(b, material_of(b, t), c, material_of(c, t));
}

TEST(MaterialFormats, JsonNewTypesTheirDefaultsAndFields) {
  TempDir dir;
  Image rough(2, 1, Rgb(0.25f));
  write_image(dir / "r.exr", rough);
  const auto path = dir.write("s.json", R"({
    "materials": {
      "glass": {"type": "dielectric", "ior": 1.45},
      "pane": {"type": "thindielectric"},
      "coat": {"type": "coateddiffuse", "albedo": [0.5, 0.4, 0.3], "thickness": 0.2,
               "roughness_texture": "r.exr"}
    },
    "shapes": [
      {"type": "quad", "origin": [0, 0, 0], "edge1": [1, 0, 0], "edge2": [0, 1, 0], "material": "glass"},
      {"type": "quad", "origin": [0, 0, 1], "edge1": [1, 0, 0], "edge2": [0, 1, 0], "material": "pane"},
      {"type": "quad", "origin": [0, 0, 2], "edge1": [1, 0, 0], "edge2": [0, 1, 0], "material": "coat"}
    ],
    "lights": [{"type": "point", "position": [0, 0, 5], "intensity": [1, 1, 1]}]})");
  LoadOptions quiet;
  quiet.print_warnings = false;
  const Scene s = load_scene(path.string(), quiet);
  const Material &glass = material_of(s, 0), &pane = material_of(s, 2), &coat = material_of(s, 4);
  EXPECT_EQ(glass.type, MaterialType::Dielectric);
  EXPECT_EQ(glass.ior, 1.45f);
  EXPECT_EQ(glass.roughness, 0);  // smooth unless said otherwise
  EXPECT_EQ(pane.type, MaterialType::ThinDielectric);
  EXPECT_EQ(pane.ior, 1.5f);
  EXPECT_EQ(coat.type, MaterialType::CoatedDiffuse);
  EXPECT_EQ(coat.thickness, 0.2f);
  EXPECT_EQ(coat.albedo, Rgb(0.5f, 0.4f, 0.3f));
  ASSERT_GE(coat.roughness_texture, 0);
  EXPECT_EQ(s.textures[size_t(coat.roughness_texture)].at(1, 0), Rgb(0.25f));
  ASSERT_EQ(s.mesh.uvs.size(), s.mesh.positions.size());  // quads get uvs for the texture
}

TEST(MaterialFormats, JsonErrorsNameTheField) {
  TempDir dir;
  auto error = [&](const std::string& material) {
    const auto path = dir.write("e.json", R"({"materials": {"m": )" + material + R"(},
      "shapes": [{"type": "quad", "origin": [0, 0, 0], "edge1": [1, 0, 0], "edge2": [0, 1, 0], "material": "m"}],
      "lights": [{"type": "point", "position": [0, 0, 5], "intensity": [1, 1, 1]}]})");
    return error_of([&] { load_scene(path.string()); });
  };
  std::string e = error(R"({"type": "glass"})");
  EXPECT_TRUE(contains(e, "/materials/m/type")) << e;
  EXPECT_TRUE(contains(e, "thindielectric")) << e;
  e = error(R"({"type": "dielectric", "thickness": 0.1})");
  EXPECT_TRUE(contains(e, "/materials/m")) << e;
  EXPECT_TRUE(contains(e, "\"thickness\" does not apply to a dielectric")) << e;
  e = error(R"({"type": "thindielectric", "roughness": 0.1})");
  EXPECT_TRUE(contains(e, "\"roughness\" does not apply to a thindielectric")) << e;
  e = error(R"({"type": "diffuse", "roughness_texture": "r.exr"})");
  EXPECT_TRUE(contains(e, "\"roughness_texture\" does not apply to a diffuse")) << e;
  e = error(R"({"type": "coateddiffuse", "thickness": -1})");
  EXPECT_TRUE(contains(e, "/materials/m/thickness must be positive")) << e;
  e = error(R"({"type": "coateddiffuse", "roughness_texture": "missing.png"})");
  EXPECT_TRUE(contains(e, "/materials/m/roughness_texture")) << e;
  e = error(R"({"type": "coateddiffuse", "roughnes": 0.1})");
  EXPECT_TRUE(contains(e, "unknown field \"roughnes\"")) << e;
}

// --- pbrt-v4 ---

TEST(MaterialFormats, PbrtWriterUsesPbrtV4sOwnMaterials) {
  TempDir dir;
  Scene a = every_material_scene();
  Material tinted;  // a glTF-like metal: aluminium tinted gold
  tinted.name = "tinted";
  tinted.type = MaterialType::Conductor;
  tinted.eta = kTintableEta;
  tinted.k = kTintableK;
  tinted.specular = Rgb(1, 0.8f, 0.3f);
  a.materials.push_back(tinted);
  a.mesh.triangles.push_back({0, 1, 2});
  a.mesh.material.push_back(uint32_t(a.materials.size() - 1));
  a.mesh.light.push_back(-1);
  const auto lost = save_pbrt_scene(a, dir / "all.pbrt");
  const std::string text = rll::test::read_text(dir / "all.pbrt");
  EXPECT_TRUE(
      contains(text, "PixelFilter \"box\" \"float xradius\" [ 0.5 ] \"float yradius\" [ 0.5 ]"))
      << text;
  // The untinted metal: its eta and k, its alpha as it is.
  EXPECT_TRUE(contains(text,
                       "Material \"conductor\" \"rgb eta\" [ 0.18 0.42 1.37 ] \"rgb k\" [ "
                       "3.42 2.35 1.77 ] \"float roughness\" 0.15 \"bool remaproughness\" "
                       "false"))
      << text;
  EXPECT_TRUE(contains(text,
                       "Material \"dielectric\" \"float eta\" 1.33 \"float roughness\" 0.09 "
                       "\"bool remaproughness\" false"))
      << text;
  EXPECT_TRUE(contains(text, "Material \"thindielectric\" \"float eta\" 1.52")) << text;
  EXPECT_TRUE(contains(text,
                       "Material \"coateddiffuse\" \"rgb reflectance\" [ 0.7 0.2 0.1 ] "
                       "\"float roughness\" 0.01 \"bool remaproughness\" false \"float "
                       "thickness\" 0.05 \"float eta\" 1.6"))
      << text;
  EXPECT_TRUE(contains(text, "Texture \"rough1\" \"float\" \"imagemap\"")) << text;
  EXPECT_TRUE(contains(text, "\"texture roughness\" \"rough1\"")) << text;
  // The tinted metal: its reflectance at normal incidence, specular x F0(aluminium).
  Rgb f0;
  for (int i = 0; i < 3; ++i)
    f0[i] = tinted.specular[i] * (sqr(kTintableEta[i] - 1) + sqr(kTintableK[i])) /
            (sqr(kTintableEta[i] + 1) + sqr(kTintableK[i]));
  EXPECT_TRUE(contains(text, fmt::format("\"rgb reflectance\" [ {} {} {} ]", f0.x, f0.y, f0.z)))
      << text;
  EXPECT_FALSE(contains(text, "\"rgb reflectance\" [ 1 1 1 ]")) << text;
  // What pbrt-v4 cannot render as rll does is named: the plastic and the tint, nothing else.
  ASSERT_EQ(lost.size(), 2u) << ::testing::PrintToString(lost);
  EXPECT_TRUE(any_contains(lost,
                           "material 'plastic': rll's plastic is written as pbrt-v4's "
                           "coateddiffuse"));
  EXPECT_TRUE(any_contains(lost, "material 'tinted': pbrt-v4's conductor has no specular tint"));
}

// rll's own pbrt reader gives back what the writer meant: every type pbrt-v4 has comes back as
// itself (rll's plastic, which pbrt-v4 lacks, as the coated diffuse it is written as).
// As `rll convert` does it: read_scene (JSON in), save, read_scene (pbrt in).
TEST(MaterialFormats, PbrtRoundTripKeepsEveryMaterial) {
  TempDir dir;
  const Scene a = converted_source(dir);
  save_pbrt_scene(a, dir / "all.pbrt");
  const Scene b = read_scene((dir / "all.pbrt").string());
  ASSERT_EQ(b.mesh.triangle_count(), a.mesh.triangle_count());
  for (uint32_t t = 0; t < a.mesh.triangle_count(); ++t) {
    const Material &x = material_of(a, t), &y = material_of(b, t);
    SCOPED_TRACE(x.name);
    const MaterialType expected =
        x.type == MaterialType::Plastic ? MaterialType::CoatedDiffuse : x.type;
    EXPECT_EQ(material_type_name(y.type), std::string(material_type_name(expected)));
    EXPECT_TRUE(near(y.emission, x.emission));
    EXPECT_EQ(y.two_sided_emission, x.two_sided_emission);
    switch (x.type) {
      case MaterialType::Diffuse:
        EXPECT_TRUE(near(y.albedo, x.albedo));
        break;
      case MaterialType::Conductor:
        EXPECT_TRUE(near(y.eta, x.eta));
        EXPECT_TRUE(near(y.k, x.k));
        EXPECT_TRUE(near(y.specular, x.specular));
        break;
      case MaterialType::Dielectric:
      case MaterialType::ThinDielectric:
        EXPECT_FLOAT_EQ(y.ior, x.ior);
        break;
      case MaterialType::Plastic:
      case MaterialType::CoatedDiffuse:
        EXPECT_FLOAT_EQ(y.ior, x.ior);
        if (x.albedo_texture < 0) {
          EXPECT_TRUE(near(y.albedo, x.albedo));
        }
        if (x.type == MaterialType::CoatedDiffuse) {
          EXPECT_FLOAT_EQ(y.thickness, x.thickness);
        }
        break;
    }
    if (x.type != MaterialType::Diffuse && x.type != MaterialType::ThinDielectric) {
      if (x.roughness_texture >= 0)
        expect_same_texture(a, x.roughness_texture, b, y.roughness_texture, 1e-6f);
      else
        EXPECT_FLOAT_EQ(y.roughness, x.roughness);
    }
    if (x.albedo_texture >= 0) {
      ASSERT_GE(y.albedo_texture, 0);
      EXPECT_TRUE(near(y.albedo, x.albedo));
      expect_same_texture(a, x.albedo_texture, b, y.albedo_texture, 1e-6f);
    }
  }
  EXPECT_TRUE(b.warnings.empty()) << ::testing::PrintToString(b.warnings);
}

// --- glTF ---

TEST(MaterialFormats, GltfRoundTripKeepsEveryMaterial) {
  TempDir dir;
  const Scene a = converted_source(dir);
  const auto lost = save_gltf_scene(a, dir / "all.gltf");
  // The coated diffuse (glTF has no layered material) and the conductor's own eta/k are named.
  EXPECT_TRUE(any_contains(lost, "material 'coated': glTF has no layered coated diffuse"));
  EXPECT_TRUE(any_contains(lost, "material 'metal': a conductor's eta and k"));
  const std::string text = rll::test::read_text(dir / "all.gltf");
  EXPECT_TRUE(contains(text, "KHR_materials_transmission"));
  EXPECT_TRUE(contains(text, "KHR_materials_volume"));
  // glTF's convention, pinned apart from the reader: the roughness texture's green channel is
  // the perceptual roughness sqrt(alpha), stored linearly; blue is metallic.
  {
    const int rough = material_of(a, 6).roughness_texture;  // "textured"
    ASSERT_GE(rough, 0);
    const Image png = read_image(dir / fmt::format("all_rough{}.png", rough), false);
    const Image png_metal = read_image(dir / fmt::format("all_rough{}_metal.png", rough), false);
    const Image& alpha = a.textures[size_t(rough)];
    for (size_t i = 0; i < alpha.pixel_count(); ++i) {
      EXPECT_NEAR(png[i].y, std::sqrt(alpha[i].x), 0.5f / 255 + 1e-6f) << i;
      EXPECT_EQ(png[i].z, 0) << i;
      EXPECT_EQ(png_metal[i].z, 1) << i;
    }
  }
  const Scene b = read_scene((dir / "all.gltf").string());
  ASSERT_EQ(b.mesh.triangle_count(), a.mesh.triangle_count());
  for (uint32_t t = 0; t < a.mesh.triangle_count(); ++t) {
    const Material &x = material_of(a, t), &y = material_of(b, t);
    SCOPED_TRACE(x.name);
    const MaterialType expected =
        x.type == MaterialType::CoatedDiffuse ? MaterialType::Plastic : x.type;
    EXPECT_EQ(material_type_name(y.type), std::string(material_type_name(expected)));
    EXPECT_TRUE(near(y.emission, x.emission, 1e-5f));
    if (x.type == MaterialType::ThinDielectric) {
      EXPECT_FLOAT_EQ(y.ior, x.ior);
      EXPECT_EQ(y.roughness, 0);
      continue;
    }
    if (x.type != MaterialType::Diffuse) {
      if (x.roughness_texture >= 0) {
        // Through an 8-bit PNG of sqrt(alpha): within one code step.
        ASSERT_GE(y.roughness_texture, 0);
        const Image &p = a.textures[size_t(x.roughness_texture)],
                    &q = b.textures[size_t(y.roughness_texture)];
        ASSERT_EQ(p.pixel_count(), q.pixel_count());
        for (size_t i = 0; i < p.pixel_count(); ++i)
          EXPECT_NEAR(std::sqrt(q[i].x), std::sqrt(p[i].x), 0.5f / 255 + 1e-6f) << i;
      } else {
        EXPECT_NEAR(y.roughness, x.roughness, 1e-6f);
      }
    }
    switch (x.type) {
      case MaterialType::Dielectric:
      case MaterialType::Plastic:
      case MaterialType::CoatedDiffuse:
        EXPECT_FLOAT_EQ(y.ior, x.ior);
        break;
      default:
        break;
    }
    if (x.type == MaterialType::Plastic || x.type == MaterialType::CoatedDiffuse ||
        x.type == MaterialType::Diffuse) {
      EXPECT_TRUE(near(y.albedo, x.albedo));
      EXPECT_EQ(y.albedo_texture >= 0, x.albedo_texture >= 0);
    }
  }
}

namespace {

// A glTF file of one triangle with the given material (JSON text).
std::filesystem::path one_triangle_gltf(const TempDir& dir, const std::string& material,
                                        const std::string& extensions_used) {
  // Three float positions, little endian: (0,0,0), (1,0,0), (0,1,0).
  return dir.write("t.gltf", R"({"asset": {"version": "2.0"},
    "extensionsUsed": [)" + extensions_used +
                                 R"(],
    "buffers": [{"byteLength": 36, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}],
    "bufferViews": [{"buffer": 0, "byteLength": 36}],
    "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                   "min": [0, 0, 0], "max": [1, 1, 0]}],
    "materials": [)" + material + R"(],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "material": 0}]}],
    "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}], "scene": 0})");
}

}  // namespace

TEST(MaterialFormats, GltfTransmissionAndIorMakeGlass) {
  TempDir dir;
  const std::string used =
      R"("KHR_materials_transmission", "KHR_materials_ior", "KHR_materials_volume")";
  {  // With a volume: solid glass that refracts, rough as glTF's roughness squared.
    Scene s;
    load_gltf(one_triangle_gltf(
                  dir, R"({"pbrMetallicRoughness": {"metallicFactor": 0, "roughnessFactor": 0.5},
      "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1},
                     "KHR_materials_ior": {"ior": 1.7},
                     "KHR_materials_volume": {"thicknessFactor": 0.1}}})",
                  used),
              s);
    ASSERT_EQ(s.materials.size(), 1u);
    EXPECT_EQ(s.materials[0].type, MaterialType::Dielectric);
    EXPECT_FLOAT_EQ(s.materials[0].ior, 1.7f);
    EXPECT_FLOAT_EQ(s.materials[0].roughness, 0.25f);
    EXPECT_TRUE(s.warnings.empty()) << ::testing::PrintToString(s.warnings);
  }
  {  // Without a volume: thin-walled, a pane; a partial factor and a texture are named.
    Scene s;
    load_gltf(one_triangle_gltf(
                  dir, R"({"pbrMetallicRoughness": {"metallicFactor": 0, "roughnessFactor": 0},
      "extensions": {"KHR_materials_transmission": {"transmissionFactor": 0.8, "transmissionTexture": {"index": 0}}}})",
                  used),
              s);
    EXPECT_EQ(s.materials[0].type, MaterialType::ThinDielectric);
    EXPECT_FLOAT_EQ(s.materials[0].ior, 1.5f);
    EXPECT_TRUE(
        any_contains(s.warnings, "transmissionFactor 0.8 is rendered as fully transmissive"));
    EXPECT_TRUE(any_contains(s.warnings, "transmissionTexture is not supported"));
  }
  {  // A factor below 0.5: the opaque material, with a warning.
    Scene s;
    load_gltf(one_triangle_gltf(dir, R"({"pbrMetallicRoughness": {"metallicFactor": 0},
      "extensions": {"KHR_materials_transmission": {"transmissionFactor": 0.3},
                     "KHR_materials_ior": {"ior": 1.3}}})",
                                used),
              s);
    EXPECT_EQ(s.materials[0].type, MaterialType::Plastic);
    EXPECT_FLOAT_EQ(s.materials[0].ior, 1.3f);
    EXPECT_TRUE(any_contains(s.warnings, "transmissionFactor below 0.5 (0.3) is ignored"));
  }
  {  // A metal does not transmit.
    Scene s;
    load_gltf(one_triangle_gltf(dir, R"({"pbrMetallicRoughness": {"metallicFactor": 1},
      "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1}}})",
                                used),
              s);
    EXPECT_EQ(s.materials[0].type, MaterialType::Conductor);
  }
  EXPECT_TRUE(contains(
      error_of([&] {
        Scene s;
        load_gltf(
            one_triangle_gltf(
                dir, R"({"extensions": {"KHR_materials_transmission": {"transmissionFactor": 2}}})",
                used),
            s);
      }),
      "transmissionFactor must be in [0, 1]"));
}
