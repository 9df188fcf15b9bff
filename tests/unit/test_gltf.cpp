// glTF reader (and writer): node transforms, primitives, the material mapping, emission with
// its strength and textures, KHR_lights_punctual, the camera; .glb; and malformed files as
// rll::Errors naming the file and what is wrong.
#include <gtest/gtest.h>

#include <cstring>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>

#include "rll/scene/builder.h"
#include "rll/io/load.h"
#include "rll/io/save.h"
#include "support/test_support.h"

using namespace rll;
using json = nlohmann::json;
using rll::test::error_of;
using rll::test::expect_mentions;
using rll::test::TempDir;

namespace {

bool near(const Vec3& a, const Vec3& b, float eps = 1e-5f) {
  return length(a - b) <= eps;
}

// A glTF document under construction, its binary data in one buffer (buf.bin or the GLB chunk).
struct Doc {
  json j = {{"asset", {{"version", "2.0"}}}};
  std::string bin;

  template <typename T>
  int accessor(const std::vector<T>& data, int component, const char* type, size_t count) {
    while (bin.size() % 4) bin.push_back('\0');
    j["bufferViews"].push_back(
        {{"buffer", 0}, {"byteOffset", bin.size()}, {"byteLength", data.size() * sizeof(T)}});
    bin.append(reinterpret_cast<const char*>(data.data()), data.size() * sizeof(T));
    j["accessors"].push_back({{"bufferView", j["bufferViews"].size() - 1},
                              {"componentType", component},
                              {"count", count},
                              {"type", type}});
    return int(j["accessors"].size() - 1);
  }
  int positions(const std::vector<float>& p) { return accessor(p, 5126, "VEC3", p.size() / 3); }
  int indices(const std::vector<uint16_t>& i) { return accessor(i, 5123, "SCALAR", i.size()); }

  // A mesh of one triangle primitive; returns its index.
  int mesh(int position_accessor, int index_accessor = -1, int material = -1, int mode = -1) {
    json prim = {{"attributes", {{"POSITION", position_accessor}}}};
    if (index_accessor >= 0) prim["indices"] = index_accessor;
    if (material >= 0) prim["material"] = material;
    if (mode >= 0) prim["mode"] = mode;
    j["meshes"].push_back({{"primitives", json::array({prim})}});
    return int(j["meshes"].size() - 1);
  }
  int node(json n) {
    j["nodes"].push_back(std::move(n));
    return int(j["nodes"].size() - 1);
  }
  void scene(std::vector<int> roots) { j["scenes"] = json::array({{{"nodes", roots}}}); }

  // Writes NAME.gltf with buf.bin beside it.
  std::filesystem::path write_gltf(const TempDir& dir, const std::string& name = "s.gltf") {
    j["buffers"] = json::array({{{"byteLength", bin.size()}, {"uri", "buf.bin"}}});
    dir.write("buf.bin", bin);
    return dir.write(name, j.dump());
  }
  std::string glb() {
    json copy = j;
    copy["buffers"] = json::array({{{"byteLength", bin.size()}}});
    std::string text = copy.dump();
    while (text.size() % 4) text += ' ';
    std::string data = bin;
    while (data.size() % 4) data.push_back('\0');
    std::string out = "glTF";
    auto u32 = [&](uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); };
    u32(2);
    u32(uint32_t(12 + 8 + text.size() + 8 + data.size()));
    u32(uint32_t(text.size()));
    u32(0x4E4F534A);  // JSON
    out += text;
    u32(uint32_t(data.size()));
    u32(0x004E4942);  // BIN
    out += data;
    return out;
  }
};

const std::vector<float> kTriangle = {0, 0, 0, 1, 0, 0, 0, 1, 0};

Scene read(const std::filesystem::path& p) {
  Scene s;
  load_gltf(p, s);
  return s;
}

std::string gltf_error(const TempDir& dir, Doc& d) {
  auto p = d.write_gltf(dir, "bad.gltf");
  return error_of([&] { read(p); });
}

bool has_warning(const Scene& s, const std::string& part) {
  for (const auto& w : s.warnings)
    if (w.find(part) != std::string::npos) return true;
  return false;
}

}  // namespace

TEST(GltfReader, NodeTransformsComposeAndMeshesInstance) {
  TempDir dir;
  Doc d;
  const int m = d.mesh(d.positions(kTriangle));
  const int child = d.node({{"mesh", m}, {"scale", {2, 2, 2}}});
  const int rotated = d.node({{"mesh", m}, {"rotation", {0, 0, 0.7071068, 0.7071068}}});  // 90 z
  const int parent = d.node({{"translation", {10, 0, 0}}, {"children", {child}}});
  const int matrix = d.node(
      {{"mesh", m}, {"matrix", {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, -1, 0, 0, 0, 5, 1}}});  // mirror z
  d.scene({parent, rotated, matrix});
  Scene s = read(d.write_gltf(dir));
  ASSERT_EQ(s.mesh.triangle_count(), 3u);
  EXPECT_TRUE(near(s.mesh.vertex(0, 1), Vec3(12, 0, 0)));
  EXPECT_TRUE(near(s.mesh.vertex(1, 1), Vec3(0, 1, 0)));
  // The mirrored instance faces -z, the mirror image of its +z: glTF winds the triangles of a
  // node with a negative determinant clockwise.
  EXPECT_TRUE(near(s.mesh.positions[6], Vec3(0, 0, 5)));
  EXPECT_LT(s.mesh.face_cross(2).z, 0);
  // glTF's default material: metallic 1, roughness 1, base colour 1.
  EXPECT_EQ(s.materials[s.mesh.material[0]].type, MaterialType::Conductor);
}

TEST(GltfReader, StripsFansAndIndices) {
  TempDir dir;
  Doc d;
  const int p = d.positions({0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0});
  const int strip = d.mesh(p, -1, -1, 5), fan = d.mesh(p, d.indices({0, 1, 3, 2}), -1, 6);
  d.scene({d.node({{"mesh", strip}}), d.node({{"mesh", fan}})});
  Scene s = read(d.write_gltf(dir));
  ASSERT_EQ(s.mesh.triangle_count(), 4u);
  for (uint32_t t = 0; t < 4; ++t) EXPECT_GT(s.mesh.face_cross(t).z, 0) << t;
}

TEST(GltfReader, MaterialsEmissionAndLights) {
  TempDir dir;
  Doc d;
  d.j["materials"] = json::array(
      {{{"pbrMetallicRoughness",
         {{"baseColorFactor", {0.5, 0.25, 0.125, 1}}, {"metallicFactor", 0}}},
        {"extensions", {{"KHR_materials_specular", {{"specularFactor", 0}}}}}},
       {{"pbrMetallicRoughness", {{"metallicFactor", 0}, {"roughnessFactor", 0.5}}},
        {"extensions", {{"KHR_materials_ior", {{"ior", 1.33}}}}}},
       {{"pbrMetallicRoughness",
         {{"baseColorFactor", {0.9, 0.6, 0.3, 1}}, {"roughnessFactor", 0.2}}},
        {"emissiveFactor", {1, 0.5, 0.25}},
        {"doubleSided", true},
        {"extensions", {{"KHR_materials_emissive_strength", {{"emissiveStrength", 8}}}}}}});
  const int p = d.positions(kTriangle);
  std::vector<int> roots;
  for (int k = 0; k < 3; ++k) roots.push_back(d.node({{"mesh", d.mesh(p, -1, k)}}));
  json lights = json::array({{{"type", "point"}, {"color", {1, 0.5, 0.5}}, {"intensity", 4}},
                             {{"type", "directional"}, {"intensity", 2}},
                             {{"type", "spot"}, {"spot", json::object()}}});
  d.j["extensions"]["KHR_lights_punctual"]["lights"] = lights;
  roots.push_back(d.node(
      {{"translation", {1, 2, 3}}, {"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}}));
  // Rotated -90 degrees about x: the light shines along -z, which turns to -y (down); the
  // direction towards it is +y.
  roots.push_back(d.node({{"rotation", {-0.7071068, 0, 0, 0.7071068}},
                          {"extensions", {{"KHR_lights_punctual", {{"light", 1}}}}}}));
  roots.push_back(d.node({{"extensions", {{"KHR_lights_punctual", {{"light", 2}}}}}}));
  d.j["cameras"] =
      json::array({{{"type", "perspective"},
                    {"perspective", {{"yfov", 0.5}, {"aspectRatio", 2.0}, {"znear", 0.1}}}}});
  roots.push_back(d.node({{"camera", 0}, {"translation", {0, 0, 7}}}));
  d.scene(roots);
  Scene s = read(d.write_gltf(dir));
  ASSERT_EQ(s.mesh.triangle_count(), 3u);
  const Material &diffuse = s.materials[s.mesh.material[0]],
                 &plastic = s.materials[s.mesh.material[1]],
                 &metal = s.materials[s.mesh.material[2]];
  EXPECT_EQ(diffuse.type, MaterialType::Diffuse);
  EXPECT_TRUE(near(diffuse.albedo, Rgb(0.5f, 0.25f, 0.125f)));
  EXPECT_EQ(plastic.type, MaterialType::Plastic);
  EXPECT_FLOAT_EQ(plastic.roughness, 0.25f);  // alpha = roughness^2
  EXPECT_FLOAT_EQ(plastic.ior, 1.33f);
  EXPECT_EQ(metal.type, MaterialType::Conductor);
  EXPECT_TRUE(near(metal.specular, Rgb(0.9f, 0.6f, 0.3f)));
  EXPECT_TRUE(near(metal.emission, Rgb(8, 4, 2)));
  EXPECT_TRUE(metal.two_sided_emission);
  ASSERT_EQ(s.lights.size(), 3u);
  EXPECT_TRUE(near(s.lights[0].p0, Vec3(1, 2, 3)));
  EXPECT_TRUE(near(s.lights[0].radiance, Rgb(4, 2, 2)));
  EXPECT_TRUE(near(s.lights[1].p0, Vec3(0, 1, 0)));
  EXPECT_TRUE(near(s.lights[1].radiance, Rgb(2)));
  // glTF's default spot: inner 0, outer pi/4, shining along the node's -z; its falloff is read
  // as pbrt-v4's smoothstep, with a warning.
  ASSERT_EQ(s.lights[2].type, LightType::Spot);
  EXPECT_TRUE(near(s.lights[2].n, Vec3(0, 0, -1)));
  EXPECT_FLOAT_EQ(s.lights[2].p1.x, 1.0f);
  EXPECT_NEAR(s.lights[2].p1.y, std::cos(M_PI / 4), 1e-6);
  EXPECT_TRUE(has_warning(s, "spot"));
  ASSERT_TRUE(s.has_camera);
  EXPECT_TRUE(near(s.camera.position, Vec3(0, 0, 7)));
  EXPECT_TRUE(near(s.camera.target, Vec3(0, 0, 6)));
  EXPECT_NEAR(s.camera.fov, 0.5 * 180 / M_PI, 1e-4);
  EXPECT_EQ(s.width, 2 * s.height);
}

TEST(GltfReader, EmissiveTextureIsTheMaterialsEmissionTexture) {
  TempDir dir;
  // Left half red, right half black, as PNG (sRGB 255 is linear 1).
  Image tex(8, 8);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 4; ++x) tex.at(x, y) = Rgb(1, 0, 0);
  write_image(dir / "glow.png", tex);
  Doc d;
  d.j["images"] = json::array({{{"uri", "glow.png"}}});
  d.j["textures"] = json::array({{{"source", 0}}});
  d.j["materials"] = json::array(
      {{{"emissiveFactor", {1, 1, 1}},
        {"emissiveTexture", {{"index", 0}}},
        {"extensions", {{"KHR_materials_emissive_strength", {{"emissiveStrength", 5}}}}}}});
  // Two triangles, one over each half of the texture.
  const int p = d.positions({0, 0, 0, 1, 0, 0, 0, 1, 0, 2, 0, 0, 3, 0, 0, 2, 1, 0});
  const int uv = d.accessor(std::vector<float>{0.05f, 0.05f, 0.2f, 0.05f, 0.05f, 0.2f, 0.8f, 0.8f,
                                               0.95f, 0.8f, 0.8f, 0.95f},
                            5126, "VEC2", 6);
  d.j["meshes"] =
      json::array({{{"primitives",
                     {{{"attributes", {{"POSITION", p}, {"TEXCOORD_0", uv}}}, {"material", 0}}}}}});
  d.scene({d.node({{"mesh", 0}})});
  Scene s = read(d.write_gltf(dir));
  ASSERT_EQ(s.mesh.triangle_count(), 2u);
  // One material: the factor times the strength, and the texture (read from sRGB).
  EXPECT_EQ(s.mesh.material[0], s.mesh.material[1]);
  const Material& m = s.materials[s.mesh.material[0]];
  EXPECT_TRUE(near(m.emission, Rgb(5, 5, 5), 1e-4f));
  ASSERT_GE(m.emission_texture, 0);
  EXPECT_TRUE(near(s.textures[size_t(m.emission_texture)].at(0, 0), Rgb(1, 0, 0), 1e-4f));
  s.finalize();
  // Each triangle a light of the texture's exact mean over it: the first mostly red, the second
  // (over the black half, reaching red only through the wrapped bilinear edge) much dimmer.
  ASSERT_GE(s.lights.size(), 1u);
  double red[2] = {0, 0};
  for (const Light& l : s.lights) {
    EXPECT_TRUE(l.textured);
    red[l.triangle] = l.radiance.x;
    EXPECT_EQ(l.radiance.y, 0.0f);
  }
  EXPECT_GT(red[0], 3.0);
  EXPECT_LT(red[1], 0.5 * red[0]);
}

TEST(GltfReader, BaseColourTextureIsDecodedFromSrgb) {
  TempDir dir;
  Image tex(2, 2, Rgb(0.5f));  // written as sRGB 188, read back as linear 0.5 (to 8 bits)
  write_image(dir / "wood.png", tex);
  Doc d;
  d.j["images"] = json::array({{{"uri", "wood.png"}}});
  d.j["textures"] = json::array({{{"source", 0}}});
  d.j["materials"] = json::array({{{"pbrMetallicRoughness",
                                    {{"baseColorTexture", {{"index", 0}}},
                                     {"baseColorFactor", {1, 0.5, 1, 1}},
                                     {"metallicFactor", 0}}}}});
  d.scene({d.node({{"mesh", d.mesh(d.positions(kTriangle), -1, 0)}})});
  Scene s = read(d.write_gltf(dir));
  const Material& m = s.materials[s.mesh.material[0]];
  ASSERT_EQ(m.albedo_texture, 0);
  EXPECT_TRUE(near(m.albedo, Rgb(1, 0.5f, 1)));
  EXPECT_NEAR(s.textures[0].at(1, 1).y, 0.5f, 0.005f);
}

TEST(GltfReader, BinaryGlbReadsLikeText) {
  TempDir dir;
  Doc d;
  d.scene({d.node({{"mesh", d.mesh(d.positions(kTriangle), d.indices({0, 1, 2}))}})});
  auto p = dir.write("s.glb", d.glb());
  Scene s = read(p);
  ASSERT_EQ(s.mesh.triangle_count(), 1u);
  EXPECT_TRUE(near(s.mesh.vertex(0, 2), Vec3(0, 1, 0)));
  // Truncated anywhere: an error, never a crash.
  const std::string glb = d.glb();
  for (size_t cut = 0; cut < glb.size(); cut += 9) {
    auto q = dir.write("cut.glb", glb.substr(0, cut));
    error_of([&] { read(q); });
  }
}

TEST(GltfReader, WriterRoundTripKeepsMaterialsLightsAndCamera) {
  TempDir dir;
  Scene a;
  a.source = "test";
  SceneBuilder b(a);
  Material plastic;
  plastic.type = MaterialType::Plastic;
  plastic.albedo = Rgb(0.2f, 0.3f, 0.4f);
  plastic.roughness = 0.09f;
  plastic.ior = 1.4f;
  Material metal;
  metal.type = MaterialType::Conductor;
  metal.eta = kTintableEta;
  metal.k = kTintableK;
  metal.specular = Rgb(0.9f, 0.8f, 0.7f);
  metal.roughness = 0.16f;
  b.box(Vec3(0), Vec3(1), b.diffuse(Rgb(0.7f)), true);
  b.sphere(Vec3(0.5f), 0.2f, 2, b.material(plastic));
  b.quad(Vec3(0.2f, 0.1f, 0.2f), Vec3(0.2f, 0, 0), Vec3(0, 0, 0.2f), b.material(metal));
  b.quad(Vec3(0.4f, 0.99f, 0.4f), Vec3(0, 0, 0.2f), Vec3(0.2f, 0, 0),
         b.emitter(Rgb(10, 8, 6), true));
  a.lights.push_back(make_point_light(Vec3(0.5f, 0.5f, 0.5f), Rgb(1, 2, 3)));
  a.lights.push_back(make_directional_light(normalize(Vec3(1, 2, 3)), Rgb(4)));
  a.width = 40;
  a.height = 30;
  a.camera.position = Vec3(0.5f, 0.5f, 3);
  a.camera.target = Vec3(0.5f, 0.4f, 0);
  a.camera.fov = 30;
  a.has_camera = true;
  const auto lost = save_gltf_scene(a, dir / "out.gltf");
  EXPECT_TRUE(lost.empty()) << lost.front();
  Scene r = read(dir / "out.gltf");
  ASSERT_EQ(r.mesh.triangle_count(), a.mesh.triangle_count());
  double area_a = 0, area_r = 0;
  for (uint32_t t = 0; t < a.mesh.triangle_count(); ++t) {
    area_a += a.mesh.area(t);
    area_r += r.mesh.area(t);
  }
  EXPECT_NEAR(area_r, area_a, 1e-4 * area_a);
  std::map<MaterialType, int> types;
  for (uint32_t m : r.mesh.material) {
    const Material& mat = r.materials[m];
    ++types[mat.type];
    if (mat.type == MaterialType::Plastic) {
      EXPECT_TRUE(near(mat.albedo, plastic.albedo));
      EXPECT_NEAR(mat.roughness, plastic.roughness, 1e-6);
      EXPECT_FLOAT_EQ(mat.ior, plastic.ior);
      EXPECT_TRUE(near(mat.specular, Rgb(1)));
    }
    if (mat.type == MaterialType::Conductor) {
      EXPECT_TRUE(near(mat.specular, metal.specular));
      EXPECT_NEAR(mat.roughness, metal.roughness, 1e-6);
    }
    if (mat.is_emissive()) {
      EXPECT_TRUE(near(mat.emission, Rgb(10, 8, 6), 1e-5f));
      EXPECT_TRUE(mat.two_sided_emission);
    }
  }
  EXPECT_EQ(types[MaterialType::Diffuse], 12 + 2);
  EXPECT_EQ(types[MaterialType::Conductor], 2);
  ASSERT_EQ(r.lights.size(), 2u);
  EXPECT_TRUE(near(r.lights[0].radiance, Rgb(1, 2, 3)));
  EXPECT_TRUE(near(r.lights[1].p0, normalize(Vec3(1, 2, 3))));
  EXPECT_TRUE(near(r.camera.position, a.camera.position));
  EXPECT_TRUE(near(normalize(r.camera.target - r.camera.position),
                   normalize(a.camera.target - a.camera.position)));
  EXPECT_NEAR(r.camera.fov, 30, 1e-4);
  EXPECT_EQ(r.width * 3, r.height * 4);
}

TEST(GltfReader, ClearcoatOverADielectricBaseIsACoatedDiffuse) {
  TempDir dir;
  Doc d;
  d.j["extensionsUsed"] = {"KHR_materials_clearcoat", "KHR_materials_ior"};
  d.j["materials"] = json::parse(R"([
    {"pbrMetallicRoughness": {"baseColorFactor": [0.6, 0.3, 0.2, 1], "metallicFactor": 0,
                              "roughnessFactor": 0.9},
     "extensions": {"KHR_materials_clearcoat": {"clearcoatFactor": 1,
                                                "clearcoatRoughnessFactor": 0.4},
                    "KHR_materials_ior": {"ior": 1.33}}},
    {"pbrMetallicRoughness": {"baseColorFactor": [0.6, 0.3, 0.2, 1], "metallicFactor": 0,
                              "roughnessFactor": 0.9}},
    {"pbrMetallicRoughness": {"metallicFactor": 0},
     "extensions": {"KHR_materials_clearcoat": {"clearcoatFactor": 0.5,
                                                "clearcoatTexture": {"index": 0}}}},
    {"pbrMetallicRoughness": {"metallicFactor": 1},
     "extensions": {"KHR_materials_clearcoat": {"clearcoatFactor": 1}}},
    {"pbrMetallicRoughness": {"metallicFactor": 0, "roughnessFactor": 0.5},
     "extensions": {"KHR_materials_clearcoat": {"clearcoatFactor": 0,
                                                "clearcoatRoughnessFactor": 0.7}}}
  ])");
  const int p = d.positions(kTriangle);
  std::vector<int> roots;
  for (int k = 0; k < 5; ++k) roots.push_back(d.node({{"mesh", d.mesh(p, -1, k)}}));
  d.scene(roots);
  Scene s = read(d.write_gltf(dir));
  ASSERT_EQ(s.mesh.triangle_count(), 5u);
  const auto mat = [&](size_t t) { return s.materials[s.mesh.material[t]]; };
  // Base colour as reflectance, the coat's roughness as GGX alpha (0.4^2), IOR 1.5 (the
  // clearcoat's, whatever KHR_materials_ior says of the base), pbrt-v4's default thickness.
  EXPECT_EQ(mat(0).type, MaterialType::CoatedDiffuse);
  EXPECT_TRUE(near(mat(0).albedo, Rgb(0.6f, 0.3f, 0.2f)));
  EXPECT_FLOAT_EQ(mat(0).roughness, 0.16f);
  EXPECT_FLOAT_EQ(mat(0).ior, 1.5f);
  EXPECT_FLOAT_EQ(mat(0).thickness, Material().thickness);
  // Without the extension: as before, rll's plastic with the base's roughness.
  EXPECT_EQ(mat(1).type, MaterialType::Plastic);
  EXPECT_FLOAT_EQ(mat(1).roughness, 0.81f);
  // A partial coat is a full one (a warning); its textures are ignored (a warning).
  EXPECT_EQ(mat(2).type, MaterialType::CoatedDiffuse);
  EXPECT_FLOAT_EQ(mat(2).roughness, 0);  // clearcoatRoughnessFactor's default
  EXPECT_TRUE(has_warning(s, "material 2: clearcoatFactor 0.5 is rendered as a full clearcoat"));
  EXPECT_TRUE(has_warning(s,
                          "material 2: the KHR_materials_clearcoat clearcoatTexture is not "
                          "supported"));
  // Over a metal the coat is dropped (a warning); a zero factor is no coat.
  EXPECT_EQ(mat(3).type, MaterialType::Conductor);
  EXPECT_TRUE(has_warning(s, "material 3: a clearcoat over a metal is not supported"));
  EXPECT_EQ(mat(4).type, MaterialType::Plastic);
  EXPECT_FLOAT_EQ(mat(4).roughness, 0.25f);
  // The extension is one rll reads, and material 0 warns of nothing.
  EXPECT_FALSE(has_warning(s, "KHR_materials_clearcoat is not supported"));
  EXPECT_FALSE(has_warning(s, "material 0"));
  // Factors outside [0, 1] are errors naming the material.
  Doc bad;
  bad.j["materials"] = json::parse(R"([{"extensions": {"KHR_materials_clearcoat":
                                                         {"clearcoatFactor": 1.5}}}])");
  bad.scene({bad.node({{"mesh", bad.mesh(bad.positions(kTriangle), -1, 0)}})});
  expect_mentions(gltf_error(dir, bad), {"bad.gltf", "material 0", "clearcoatFactor"});
}

TEST(GltfWriter, ThinLensAndScreenWindowAreDroppedWithOneWarning) {
  TempDir dir;
  Scene a;
  a.source = "test";
  SceneBuilder b(a);
  b.quad(Vec3(0), Vec3(1, 0, 0), Vec3(0, 1, 0), b.diffuse(Rgb(0.5f)));
  a.camera.position = Vec3(0.5f, 0.5f, 3);
  a.camera.target = Vec3(0.5f, 0.5f, 0);
  a.has_camera = true;
  // A pinhole: nothing is lost (the baseline).
  EXPECT_TRUE(save_gltf_scene(a, dir / "pin.gltf").empty());
  auto lens = a;
  lens.camera.lens_radius = 0.05f;
  lens.camera.focal_distance = 3;
  auto window = a;
  window.camera.screen_window = {-1, 0, -1, 0};
  auto both = lens;
  both.camera.screen_window = window.camera.screen_window;
  for (const Scene* s : {&lens, &window, &both}) {
    const auto lost = save_gltf_scene(*s, dir / "out.gltf");
    ASSERT_EQ(lost.size(), 1u);
    expect_mentions(lost[0], {"thin lens", "screen window", "pinhole"});
    // What is written is the pinhole of the whole image.
    Scene r = read(dir / "out.gltf");
    EXPECT_FALSE(r.camera.has_lens());
    EXPECT_EQ(r.camera.screen_window, Camera().screen_window);
  }
}

TEST(GltfReader, MalformedFilesAreErrors) {
  TempDir dir;
  {
    auto p = dir.write("bad.gltf", "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [");
    expect_mentions(error_of([&] { read(p); }), {"bad.gltf"});
  }
  {
    Doc d;
    d.scene({d.node({{"mesh", d.mesh(d.positions(kTriangle), d.indices({0, 1, 3}))}})});
    expect_mentions(gltf_error(dir, d), {"bad.gltf", "index 3 is out of range"});
  }
  {
    Doc d;
    const int p = d.positions(kTriangle);
    d.j["accessors"][size_t(p)]["count"] = 4;  // one more than the view holds
    d.scene({d.node({{"mesh", d.mesh(p)}})});
    expect_mentions(gltf_error(dir, d), {"bad.gltf", "do not fit"});
  }
  {
    Doc d;
    const int p = d.positions(kTriangle);
    d.j["bufferViews"][0]["byteLength"] = 4000;
    d.scene({d.node({{"mesh", d.mesh(p)}})});
    expect_mentions(gltf_error(dir, d), {"bad.gltf", "outside buffer"});
  }
  {
    Doc d;
    d.positions(kTriangle);
    d.scene({d.node({{"mesh", d.mesh(7)}})});
    expect_mentions(gltf_error(dir, d), {"bad.gltf", "accessor 7 does not exist"});
  }
  {
    Doc d;
    d.scene({d.node({{"mesh", d.mesh(d.positions({0, 0, 0, 1, 0, 0}))}})});
    expect_mentions(gltf_error(dir, d), {"bad.gltf", "not a whole number of triangles"});
  }
  {
    Doc d;
    const int m = d.mesh(d.positions(kTriangle));
    d.node({{"mesh", m}, {"children", {1}}});
    d.node({{"children", {0}}});
    d.scene({0});
    expect_mentions(gltf_error(dir, d), {"bad.gltf", "reached twice"});
  }
  {
    Doc d;
    d.scene({d.node({{"mesh", d.mesh(d.positions(kTriangle))}})});
    d.j["extensionsRequired"] = {"KHR_draco_mesh_compression"};
    d.j["extensionsUsed"] = {"KHR_draco_mesh_compression"};
    expect_mentions(gltf_error(dir, d), {"bad.gltf", "KHR_draco_mesh_compression"});
  }
  {
    Doc d;
    d.scene({d.node({{"mesh", d.mesh(d.positions(kTriangle))}})});
    d.j["buffers"] = json::array({{{"byteLength", d.bin.size()}, {"uri", "missing.bin"}}});
    auto p = dir.write("nobuf.gltf", d.j.dump());
    expect_mentions(error_of([&] { read(p); }), {"nobuf.gltf", "missing.bin"});
  }
  {
    Doc d;
    d.j["images"] = json::array({{{"uri", "missing.png"}}});
    d.j["textures"] = json::array({{{"source", 0}}});
    d.j["materials"] =
        json::array({{{"pbrMetallicRoughness",
                       {{"baseColorTexture", {{"index", 0}}}, {"metallicFactor", 0}}}}});
    d.scene({d.node({{"mesh", d.mesh(d.positions(kTriangle), -1, 0)}})});
    expect_mentions(gltf_error(dir, d), {"bad.gltf", "image 0", "missing.png"});
  }
  {
    auto p =
        dir.write("bad.glb", std::string("glTF\x02\0\0\0\xff\xff\0\0", 12) + std::string(20, 'x'));
    expect_mentions(error_of([&] { read(p); }), {"bad.glb"});
  }
}

TEST(GltfReader, FieldsOfTheWrongTypeAndImpossibleValuesAreErrors) {
  // tinygltf keeps a field's default when its type is wrong ("NaN" read as roughness 1): each is
  // an error naming the field.
  TempDir dir;
  auto with = [&](const std::function<void(Doc&)>& change) {
    Doc d;
    d.j["materials"] = json::array({json::object()});
    d.scene({d.node({{"mesh", d.mesh(d.positions(kTriangle), -1, 0)}})});
    change(d);
    return d;
  };
  struct Case {
    std::function<void(Doc&)> change;
    std::vector<std::string> mentions;
  };
  const Case cases[] = {
      {[](Doc& d) { d.j["materials"][0]["pbrMetallicRoughness"]["roughnessFactor"] = "NaN"; },
       {"materials[0].pbrMetallicRoughness.roughnessFactor", "must be a number", "\"NaN\""}},
      {[](Doc& d) {
         d.j["materials"][0]["emissiveFactor"] = {1, "1", 1};
       },
       {"materials[0].emissiveFactor", "an array of numbers"}},
      {[](Doc& d) { d.j["materials"][0]["extensions"]["KHR_materials_ior"]["ior"] = "1.5"; },
       {"materials[0].extensions.KHR_materials_ior.ior", "must be a number"}},
      {[](Doc& d) {
         d.j["nodes"][0]["translation"] = {0, 0, nullptr};
       },
       {"nodes[0].translation", "an array of numbers"}},
      {[](Doc& d) { d.j["materials"][0]["extensions"]["KHR_materials_ior"]["ior"] = 0.5; },
       {"material 0", "ior must be at least 1, or 0", "0.5"}},
      {[](Doc& d) { d.j["materials"][0]["extensions"]["KHR_materials_ior"]["ior"] = -1; },
       {"material 0", "ior must be at least 1, or 0", "-1"}},
      {[](Doc& d) {
         d.j["materials"][0]["extensions"]["KHR_materials_transmission"]["transmissionFactor"] = 1;
         d.j["materials"][0]["extensions"]["KHR_materials_volume"]["thicknessFactor"] = -0.1;
       },
       {"material 0", "thicknessFactor must be finite and >= 0", "-0.1"}},
      {[](Doc& d) {
         d.j["materials"][0]["extensions"]["KHR_materials_volume"]["thicknessFactor"] = -1;
       },
       {"material 0", "thicknessFactor"}},
  };
  for (const Case& c : cases) {
    Doc d = with(c.change);
    const std::string e = gltf_error(dir, d);
    EXPECT_NE(e.find("bad.gltf"), std::string::npos) << e;
    for (const auto& part : c.mentions) EXPECT_NE(e.find(part), std::string::npos) << e;
  }
  // ior 0 is the extension's own special value (a fully reflective specular layer): read with a
  // warning, as the default 1.5.
  Doc d = with([](Doc& d) { d.j["materials"][0]["extensions"]["KHR_materials_ior"]["ior"] = 0; });
  const Scene s = read(d.write_gltf(dir));
  EXPECT_TRUE(has_warning(s, "ior 0")) << (s.warnings.empty() ? "" : s.warnings[0]);
  ASSERT_EQ(s.materials.size(), 1u);
  EXPECT_EQ(s.materials[0].ior, 1.5f);
}
