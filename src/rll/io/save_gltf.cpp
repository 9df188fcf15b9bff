// Writes a scene as glTF 2.0: one mesh of one primitive per material, materials through the
// metallic-roughness model and the extensions rll reads (so that reading back gives the same
// rll materials), KHR_lights_punctual lights and the camera.
#include <fmt/format.h>

#include <algorithm>
#include <cstring>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "rll/core/encode.h"
#include "rll/core/error.h"
#include "rll/core/file_checks.h"
#include "rll/io/save.h"

namespace rll {
namespace fs = std::filesystem;
using json = nlohmann::ordered_json;

namespace {

json vec(const Vec3& v) {
  return json::array({v.x, v.y, v.z});
}

// A node matrix (column-major) whose axes are x, y, z and origin o.
json matrix(const Vec3& x, const Vec3& y, const Vec3& z, const Vec3& o) {
  return json::array({x.x, x.y, x.z, 0, y.x, y.y, y.z, 0, z.x, z.y, z.z, 0, o.x, o.y, o.z, 1});
}

class GltfWriter {
 public:
  GltfWriter(const Scene& scene, const fs::path& path) : m_scene(scene), m_path(path) {}

  std::vector<std::string> write() {
    m_doc["asset"] = {{"version", "2.0"}, {"generator", "rll"}};
    json nodes = json::array();
    json primitives = json::array();
    for (const MaterialMesh& part : split_by_material(m_scene))
      primitives.push_back(primitive(part));
    if (!primitives.empty()) {
      m_doc["meshes"] = json::array({{{"primitives", primitives}}});
      nodes.push_back({{"mesh", 0}});
    }
    if (m_scene.has_camera) nodes.push_back(camera());
    json lights = json::array();
    bool spot_warned = false;
    for (const Light& l : m_scene.lights) {
      if (l.type == LightType::Triangle) continue;
      if (l.has_image()) {
        m_warnings.push_back(
            fmt::format("glTF has no {} light: light {} is not written",
                        l.type == LightType::Goniometric ? "goniometric" : "projection",
                        &l - m_scene.lights.data()));
        continue;
      }
      json light;
      const float scale = std::max(max_component(l.radiance), 1e-30f);
      light["color"] = vec(l.radiance / scale);
      light["intensity"] = max_component(l.radiance);
      json node;
      if (l.type == LightType::Point) {
        light["type"] = "point";
        node["translation"] = vec(l.p0);
      } else if (l.type == LightType::Spot) {
        light["type"] = "spot";
        const SpotAngles a = spot_angles(l);
        double outer = radians(float(a.cone)), inner = radians(float(a.cone - a.delta));
        if (outer > 0.5 * kPi) {
          m_warnings.push_back(fmt::format(
              "a spot light's cone of {} degrees is written as glTF's widest, 90", a.cone));
          outer = 0.5 * kPi;
          inner = std::min(inner, outer);
        }
        if (!(inner < outer)) {
          inner = outer * (1 - 1e-6);  // glTF needs inner < outer: a sharp edge
        }
        if (!spot_warned)
          m_warnings.push_back(
              "spot lights' smoothstep falloff (pbrt-v4's) is written as glTF's cone angles; glTF "
              "viewers ramp between them differently");
        spot_warned = true;
        light["spot"] = {{"innerConeAngle", inner}, {"outerConeAngle", outer}};
        const Frame f(-l.n);  // the light shines along the node's -z
        node["matrix"] = matrix(f.s, f.t, f.n, l.p0);
      } else {
        light["type"] = "directional";
        const Frame f(normalize(l.p0));  // the light shines along the node's -z
        node["matrix"] = matrix(f.s, f.t, f.n, Vec3(0));
      }
      node["extensions"] = {{"KHR_lights_punctual", {{"light", lights.size()}}}};
      lights.push_back(light);
      nodes.push_back(node);
    }
    if (!lights.empty()) {
      m_doc["extensions"] = {{"KHR_lights_punctual", {{"lights", lights}}}};
      m_extensions.insert("KHR_lights_punctual");
    }
    if (m_scene.sky) m_warnings.push_back("glTF has no sky: the sky dome is not written");
    json scene_nodes = json::array();
    for (size_t i = 0; i < nodes.size(); ++i) scene_nodes.push_back(i);
    m_doc["scene"] = 0;
    m_doc["scenes"] = json::array({{{"nodes", scene_nodes}}});
    m_doc["nodes"] = nodes;
    if (!m_materials.empty()) m_doc["materials"] = m_materials;
    if (!m_textures.empty()) {
      m_doc["textures"] = m_textures;
      m_doc["images"] = m_images;
    }
    m_doc["accessors"] = m_accessors;
    m_doc["bufferViews"] = m_views;
    m_doc["buffers"] =
        json::array({{{"byteLength", m_buffer.size()},
                      {"uri", "data:application/octet-stream;base64," + base64(m_buffer)}}});
    if (!m_extensions.empty()) m_doc["extensionsUsed"] = m_extensions;
    write_file_atomic(m_path, m_doc.dump(1) + "\n");
    return m_warnings;
  }

 private:
  // Appends data to the buffer (4-byte aligned) as a view and an accessor; returns its index.
  int accessor(const void* data, size_t bytes, size_t count, int component, const char* type,
               json extra = json::object()) {
    while (m_buffer.size() % 4) m_buffer.push_back('\0');
    m_views.push_back({{"buffer", 0}, {"byteOffset", m_buffer.size()}, {"byteLength", bytes}});
    m_buffer.append(static_cast<const char*>(data), bytes);
    json a = {{"bufferView", m_views.size() - 1},
              {"componentType", component},
              {"count", count},
              {"type", type}};
    for (auto& [k, v] : extra.items()) a[k] = v;
    m_accessors.push_back(a);
    return int(m_accessors.size() - 1);
  }

  json primitive(const MaterialMesh& part) {
    const Mesh& m = part.mesh;
    json attributes;
    Vec3 lo(kInf), hi(-kInf);
    for (const Vec3& p : m.positions) {
      lo = min(lo, p);
      hi = max(hi, p);
    }
    attributes["POSITION"] =
        accessor(m.positions.data(), m.positions.size() * 12, m.positions.size(), 5126, "VEC3",
                 {{"min", vec(lo)}, {"max", vec(hi)}});
    if (!m.normals.empty()) {
      std::vector<Vec3> n(m.normals.size());
      for (size_t i = 0; i < n.size(); ++i) n[i] = normalize(m.normals[i]);
      attributes["NORMAL"] = accessor(n.data(), n.size() * 12, n.size(), 5126, "VEC3");
    }
    if (!m.uvs.empty()) {
      std::vector<float> uv;
      for (const Vec2& t : m.uvs) uv.insert(uv.end(), {t.x, 1 - t.y});  // glTF's v runs down
      attributes["TEXCOORD_0"] = accessor(uv.data(), uv.size() * 4, m.uvs.size(), 5126, "VEC2");
    }
    const int indices = accessor(m.triangles.data(), m.triangles.size() * 12,
                                 m.triangles.size() * 3, 5125, "SCALAR");
    return {{"attributes", attributes},
            {"indices", indices},
            {"material", material(part.material, hi - lo)}};
  }

  // `extent`: the size of the material's triangles' bounding box (a glass's thickness).
  int material(uint32_t index, const Vec3& extent) {
    if (auto it = m_material_index.find(index); it != m_material_index.end()) return it->second;
    const Material& m = m_scene.materials[index];
    json g;
    g["name"] = m.name;
    json pbr;
    json extensions = json::object();
    auto extend = [&](const char* name, json value) {
      extensions[name] = std::move(value);
      m_extensions.insert(name);
    };
    const bool thin = m.type == MaterialType::ThinDielectric;
    pbr["roughnessFactor"] = thin ? 0.0f : std::sqrt(std::min(1.0f, std::max(0.0f, m.roughness)));
    if (m.roughness > 1 && !thin && m.roughness_texture < 0)
      m_warnings.push_back(
          fmt::format("material '{}': roughness {} is clamped to glTF's 1", m.name, m.roughness));
    if (m.roughness_texture >= 0 && m.type != MaterialType::Diffuse && !thin) {
      // glTF's roughness texture: perceptual roughness (sqrt of alpha) in green, metallic in blue.
      pbr["roughnessFactor"] = 1;
      pbr["metallicRoughnessTexture"] = {
          {"index", roughness_texture(m.roughness_texture, m.type == MaterialType::Conductor)}};
    }
    if (m.type == MaterialType::Conductor) {
      pbr["metallicFactor"] = 1;
      Rgb base = m.specular;
      if (!(m.eta == kTintableEta && m.k == kTintableK)) {
        // glTF's metal is its colour at normal incidence: the Fresnel reflectance of eta, k.
        Rgb f0;
        for (int i = 0; i < 3; ++i)
          f0[i] = (sqr(m.eta[i] - 1) + sqr(m.k[i])) / (sqr(m.eta[i] + 1) + sqr(m.k[i]));
        base = base * f0;
        m_warnings.push_back(fmt::format(
            "material '{}': a conductor's eta and k are written as its reflectance at normal "
            "incidence (glTF's metal colour)",
            m.name));
      }
      pbr["baseColorFactor"] = {base.x, base.y, base.z, 1};
    } else if (m.type == MaterialType::Dielectric || thin) {
      // Clear glass: full transmission; KHR_materials_volume makes it a solid that refracts,
      // its absence a thin wall (glTF's semantics), which is rll's thin dielectric.
      pbr["metallicFactor"] = 0;
      pbr["baseColorFactor"] = {1, 1, 1, 1};
      extend("KHR_materials_transmission", {{"transmissionFactor", 1}});
      extend("KHR_materials_ior", {{"ior", m.ior}});
      if (!thin) {
        float thickness = std::min({extent.x, extent.y, extent.z});
        if (!(thickness > 0)) thickness = std::max({extent.x, extent.y, extent.z, 1e-3f});
        extend("KHR_materials_volume", {{"thicknessFactor", thickness}});
      }
    } else {
      pbr["metallicFactor"] = 0;
      pbr["baseColorFactor"] = {m.albedo.x, m.albedo.y, m.albedo.z, 1};
      if (m.albedo_texture >= 0) pbr["baseColorTexture"] = {{"index", texture(m.albedo_texture)}};
      if (m.type == MaterialType::Diffuse) {
        extend("KHR_materials_specular", {{"specularFactor", 0}});
      } else {
        extend("KHR_materials_specular", {{"specularColorFactor", vec(m.specular)}});
        extend("KHR_materials_ior", {{"ior", m.ior}});
      }
      if (m.type == MaterialType::CoatedDiffuse)
        m_warnings.push_back(fmt::format(
            "material '{}': glTF has no layered coated diffuse; written as a dielectric "
            "specular layer over the base colour (rll reads it back as plastic), without the "
            "coating's thickness",
            m.name));
    }
    g["pbrMetallicRoughness"] = pbr;
    if (m.is_emissive()) {
      // emissiveFactor is at most 1; the strength extension carries the rest (and an emission
      // texture's largest value, its PNG being scaled into [0, 1]).
      float texture_max = 1;
      if (m.emission_texture >= 0)
        g["emissiveTexture"] = {{"index", emissive_texture(m.emission_texture, texture_max)}};
      const float strength = max_component(m.emission) * texture_max;
      g["emissiveFactor"] = vec(m.emission / max_component(m.emission));
      if (strength != 1) {
        extensions["KHR_materials_emissive_strength"] = {{"emissiveStrength", strength}};
        m_extensions.insert("KHR_materials_emissive_strength");
      }
    }
    if (m.two_sided_emission) g["doubleSided"] = true;
    if (!extensions.empty()) g["extensions"] = extensions;
    m_materials.push_back(g);
    return m_material_index[index] = int(m_materials.size() - 1);
  }

  int texture(int index) {
    if (auto it = m_texture_index.find(index); it != m_texture_index.end()) return it->second;
    const std::string file = fmt::format("{}_tex{}.png", m_path.stem().string(), index);
    const Image& img = m_scene.textures[size_t(index)];
    if (std::any_of(img.pixels().begin(), img.pixels().end(),
                    [](const Rgb& c) { return max_component(c) > 1; }))
      m_warnings.push_back(fmt::format("texture {}: values above 1 are clamped in the PNG", index));
    write_image(m_path.parent_path() / file, img);
    m_images.push_back({{"uri", file}});
    m_textures.push_back({{"source", m_images.size() - 1}});
    return m_texture_index[index] = int(m_textures.size() - 1);
  }

  // An emission texture as an sRGB PNG divided by its largest value (`largest`, >= 1), which the
  // material's emissive strength carries, so that values above 1 survive to 8 bits.
  int emissive_texture(int index, float& largest) {
    const Image& img = m_scene.textures[size_t(index)];
    largest = 1;
    for (const Rgb& c : img.pixels()) largest = std::max(largest, max_component(c));
    if (largest == 1) return texture(index);
    const auto key = std::make_pair(index, true);
    if (auto it = m_emissive_index.find(key); it != m_emissive_index.end()) return it->second;
    const std::string file = fmt::format("{}_emission{}.png", m_path.stem().string(), index);
    Image scaled = img;
    for (Rgb& c : scaled.pixels()) c = c / largest;
    m_warnings.push_back(fmt::format(
        "texture {}: an emission texture with values up to {} is written as an 8-bit PNG scaled "
        "by 1/{} (the emissive strength carries the factor)",
        index, largest, largest));
    write_image(m_path.parent_path() / file, scaled);
    m_images.push_back({{"uri", file}});
    m_textures.push_back({{"source", m_images.size() - 1}});
    return m_emissive_index[key] = int(m_textures.size() - 1);
  }

  // A roughness texture as glTF's metallic-roughness PNG: green = sqrt(alpha), blue = metallic,
  // stored linearly (write_image encodes PNGs as sRGB, so each value is given as the linear
  // value of its sRGB code).
  int roughness_texture(int index, bool metal) {
    const auto key = std::make_pair(index, metal);
    if (auto it = m_roughness_index.find(key); it != m_roughness_index.end()) return it->second;
    const std::string file =
        fmt::format("{}_rough{}{}.png", m_path.stem().string(), index, metal ? "_metal" : "");
    auto code = [](float v) {
      const float c = std::round(std::clamp(v, 0.0f, 1.0f) * 255) / 255;
      return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
    };
    const Image& alpha = m_scene.textures[size_t(index)];
    Image img(alpha.width(), alpha.height());
    bool clamped = false;
    for (size_t i = 0; i < img.pixel_count(); ++i) {
      clamped = clamped || alpha[i].x > 1;
      img[i] = Rgb(0, code(std::sqrt(std::max(0.0f, alpha[i].x))), code(metal ? 1 : 0));
    }
    if (clamped)
      m_warnings.push_back(
          fmt::format("texture {}: roughness above 1 is clamped to glTF's 1", index));
    write_image(m_path.parent_path() / file, img);
    m_images.push_back({{"uri", file}});
    m_textures.push_back({{"source", m_images.size() - 1}});
    return m_roughness_index[key] = int(m_textures.size() - 1);
  }

  json camera() {
    const Camera& c = m_scene.camera;
    if (c.has_lens() || c.screen_window != Camera().screen_window)
      m_warnings.push_back(
          "glTF's camera has no thin lens and no screen window: the camera is written as a "
          "pinhole seeing the whole image (lens radius, focal distance and screen window are "
          "dropped)");
    const Vec3 f = normalize(c.target - c.position), r = normalize(cross(f, c.up)), u = cross(r, f);
    m_doc["cameras"] =
        json::array({{{"type", "perspective"},
                      {"perspective",
                       {{"yfov", radians(c.fov)},
                        {"aspectRatio", float(m_scene.width) / float(m_scene.height)},
                        {"znear", 1e-3}}}}});
    return {{"camera", 0}, {"matrix", matrix(r, u, -f, c.position)}};
  }

  const Scene& m_scene;
  fs::path m_path;
  json m_doc;
  std::string m_buffer;
  json m_views = json::array(), m_accessors = json::array(), m_materials = json::array(),
       m_textures = json::array(), m_images = json::array();
  std::map<uint32_t, int> m_material_index;
  std::map<int, int> m_texture_index;
  std::map<std::pair<int, bool>, int> m_roughness_index;
  std::map<std::pair<int, bool>, int> m_emissive_index;
  std::set<std::string> m_extensions;
  std::vector<std::string> m_warnings;
};

}  // namespace

std::vector<std::string> save_gltf_scene(const Scene& scene, const fs::path& path) {
  if (path.extension() != ".gltf") fail("{}: a glTF scene is saved as a .gltf file", path.string());
  // The .gltf and its textures replace an earlier conversion's together or not at all.
  WriteBatch batch;
  std::vector<std::string> warnings = GltfWriter(scene, path).write();
  batch.commit();
  return warnings;
}

}  // namespace rll
