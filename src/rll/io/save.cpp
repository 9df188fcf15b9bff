#include "rll/io/save.h"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <charconv>
#include <cstring>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "rll/core/error.h"
#include "rll/core/file_checks.h"
#include "rll/scene/transform.h"

namespace rll {
namespace fs = std::filesystem;
// Ordered, so that the file reads camera, film, materials, shapes, lights, sky, and "type" first.
using json = nlohmann::ordered_json;

namespace {

// A float as the shortest decimal that reads back to it, so that the JSON says 0.73 rather than
// 0.7300000190734863 (the value nlohmann would print for the float widened to a double).
json number(float f) {
  std::string s = fmt::format("{}", f);
  double d = 0;
  std::from_chars(s.data(), s.data() + s.size(), d);
  return d;
}
json vec(const Vec3& v) {
  return json::array({number(v.x), number(v.y), number(v.z)});
}

// A material name that OBJ/MTL statements can carry (one token) and that is unique.
std::string unique_name(const std::string& name, std::set<std::string>& taken) {
  std::string base;
  for (char c : name) base += (std::isspace(static_cast<unsigned char>(c)) || c == '#') ? '_' : c;
  if (base.empty()) base = "material";
  std::string n = base;
  for (int k = 2; !taken.insert(n).second; ++k) n = fmt::format("{}_{}", base, k);
  return n;
}

// A file name as an mtllib statement reads it: spaces escaped with a backslash.
std::string escape_spaces(const std::string& s) {
  std::string e;
  for (char c : s) e += c == ' ' ? std::string("\\ ") : std::string(1, c);
  return e;
}

// Every field that applies to the material's type (docs/scene-format.md), so that reading the
// JSON back gives the same material whatever the type's defaults.
json material_json(const Material& m, const std::string& texture,
                   const std::string& roughness_texture) {
  const MaterialType t = m.type;
  json j;
  j["type"] = material_type_name(t);
  if (t == MaterialType::Diffuse || t == MaterialType::Plastic ||
      t == MaterialType::CoatedDiffuse) {
    j["albedo"] = vec(m.albedo);
    if (!texture.empty()) j["texture"] = texture;
  }
  if (t == MaterialType::Conductor || t == MaterialType::Plastic) j["specular"] = vec(m.specular);
  if (t != MaterialType::Diffuse && t != MaterialType::ThinDielectric) {
    j["roughness"] = number(m.roughness);
    if (!roughness_texture.empty()) j["roughness_texture"] = roughness_texture;
  }
  if (t == MaterialType::Conductor) {
    j["eta"] = vec(m.eta);
    j["k"] = vec(m.k);
  }
  if (t != MaterialType::Diffuse && t != MaterialType::Conductor) j["ior"] = number(m.ior);
  if (t == MaterialType::CoatedDiffuse) j["thickness"] = number(m.thickness);
  if (m.is_emissive()) j["emission"] = vec(m.emission);
  if (m.two_sided_emission) j["two_sided"] = true;
  return j;
}

// The MTL statements closest to a material, for programs other than rll (which reads the JSON).
void append_mtl(std::string& out, const std::string& name, const Material& m,
                const std::string& texture) {
  auto rgb = [](const Rgb& c) { return fmt::format("{} {} {}", c.x, c.y, c.z); };
  out += fmt::format("newmtl {}\n", name);
  float alpha = std::max(m.roughness, 1e-3f);
  float ns = std::max(0.0f, 2 / (alpha * alpha) - 2);
  switch (m.type) {
    case MaterialType::Diffuse:
      out += fmt::format("Kd {}\nKs 0 0 0\nillum 1\n", rgb(m.albedo));
      break;
    case MaterialType::Conductor:
      out += fmt::format("Kd 0 0 0\nKs {}\nNs {}\nillum 3\n", rgb(m.specular), ns);
      break;
    case MaterialType::Plastic:
      out += fmt::format("Kd {}\nKs {}\nNs {}\nNi {}\nillum 2\n", rgb(m.albedo), rgb(m.specular),
                         ns, m.ior);
      break;
    case MaterialType::CoatedDiffuse:
      out += fmt::format("Kd {}\nKs 1 1 1\nNs {}\nNi {}\nillum 2\n", rgb(m.albedo), ns, m.ior);
      break;
    case MaterialType::Dielectric:
    case MaterialType::ThinDielectric:  // glass: refraction and Fresnel reflection
      out += fmt::format("Kd 0 0 0\nKs 1 1 1\nNs {}\nNi {}\nTf 1 1 1\nillum 7\n", ns, m.ior);
      break;
  }
  if (m.is_emissive()) out += fmt::format("Ke {}\n", rgb(m.emission));
  if (!texture.empty()) out += fmt::format("map_Kd {}\n", texture);
  out += "\n";
}

// JSON as a person would write it: one field a line, arrays of numbers on one line.
void write_pretty(std::string& out, const json& j, int indent) {
  const std::string pad(size_t(indent) + 2, ' ');
  if (j.is_array() &&
      std::all_of(j.begin(), j.end(), [](const json& e) { return e.is_primitive(); })) {
    out += '[';
    for (size_t i = 0; i < j.size(); ++i) out += (i ? ", " : "") + j[i].dump();
    out += ']';
  } else if (j.is_structured() && !j.empty()) {
    out += j.is_object() ? "{\n" : "[\n";
    bool first = true;
    for (const auto& item : j.items()) {
      out += first ? "" : ",\n";
      first = false;
      out += pad;
      if (j.is_object()) out += json(item.key()).dump() + ": ";
      write_pretty(out, item.value(), indent + 2);
    }
    out += "\n" + std::string(size_t(indent), ' ') + (j.is_object() ? "}" : "]");
  } else {
    out += j.dump();
  }
}

// Writes the files of save_json_scene (inside its WriteBatch, which puts them in place together).
void write_json_scene(const Scene& scene, const fs::path& json_path) {
  if (json_path.extension() != ".json")
    fail("{}: a scene is saved as a .json file", json_path.string());
  const fs::path dir = json_path.parent_path();
  const std::string stem = json_path.stem().string();
  const std::string obj_name = stem + ".obj", mtl_name = stem + ".mtl";
  const Mesh& mesh = scene.mesh;
  const size_t sky_begin = scene.sky_first_triangle, sky_end = sky_begin + scene.sky_triangle_count;
  auto written = [&](size_t t) { return t < sky_begin || t >= sky_end; };

  // Materials and textures that the written triangles use, in order of first use.
  std::vector<int> material_slot(scene.materials.size(), -1);
  std::vector<uint32_t> used_materials;
  for (size_t t = 0; t < mesh.triangle_count(); ++t)
    if (written(t) && material_slot[mesh.material[t]] < 0) {
      material_slot[mesh.material[t]] = int(used_materials.size());
      used_materials.push_back(mesh.material[t]);
    }
  std::set<std::string> taken;
  std::vector<std::string> names;
  std::map<int, std::string> texture_files;
  auto add_texture = [&](int tex) {
    if (tex >= 0 && !texture_files.count(tex))
      texture_files[tex] = fmt::format("{}_tex{}.exr", stem, texture_files.size());
  };
  for (uint32_t m : used_materials) {
    names.push_back(unique_name(scene.materials[m].name, taken));
    add_texture(scene.materials[m].albedo_texture);
    const MaterialType t = scene.materials[m].type;
    if (t != MaterialType::Diffuse && t != MaterialType::ThinDielectric)  // where it applies
      add_texture(scene.materials[m].roughness_texture);
    if (scene.materials[m].is_emissive()) add_texture(scene.materials[m].emission_texture);
  }
  auto texture_of = [&](int tex) { return tex >= 0 ? texture_files.at(tex) : std::string(); };

  json j;
  if (scene.has_camera) {  // otherwise the reader fits one to the scene, as it was here
    const Camera& c = scene.camera;
    j["camera"] = {{"position", vec(c.position)},
                   {"target", vec(c.target)},
                   {"up", vec(c.up)},
                   {"fov", number(c.fov)}};
    // The thin lens and the screen window where they differ from the reader's defaults.
    if (c.lens_radius != 0) j["camera"]["lens_radius"] = number(c.lens_radius);
    if (c.focal_distance != Camera().focal_distance)
      j["camera"]["focal_distance"] = number(c.focal_distance);
    if (c.screen_window != Camera().screen_window)
      j["camera"]["screen_window"] =
          json::array({number(c.screen_window[0]), number(c.screen_window[1]),
                       number(c.screen_window[2]), number(c.screen_window[3])});
  }
  j["film"] = {{"width", scene.width}, {"height", scene.height}};
  json lights = json::array();
  for (const Light& l : scene.lights) {
    if (l.type == LightType::Point)
      lights.push_back(
          {{"type", "point"}, {"position", vec(l.p0)}, {"intensity", vec(l.radiance)}});
    else if (l.type == LightType::Directional)
      lights.push_back(
          {{"type", "directional"}, {"direction", vec(l.p0)}, {"irradiance", vec(l.radiance)}});
    else if (l.has_image()) {
      const std::string file = fmt::format("{}_light{}.exr", stem, &l - scene.lights.data());
      write_image(dir / file, scene.textures.at(l.triangle));
      lights.push_back({{"type", l.type == LightType::Goniometric ? "goniometric" : "projection"},
                        {"position", vec(l.p0)},
                        {"scale", vec(l.radiance)},
                        {"image", file},
                        {"to_light", json::array({vec(l.p1), vec(l.p2), vec(l.n)})}});
    } else if (l.type == LightType::Spot) {
      const SpotAngles a = spot_angles(l);
      lights.push_back({{"type", "spot"},
                        {"position", vec(l.p0)},
                        {"direction", vec(l.n)},
                        {"intensity", vec(l.radiance)},
                        {"cone_angle", a.cone},
                        {"cone_delta_angle", a.delta}});
    }
  }
  if (!lights.empty()) j["lights"] = lights;
  if (scene.sky) {
    const SkyDome& s = *scene.sky;
    j["sky"] = {{"type", "dome"},
                {"triangles", s.triangles},
                {"radiance", vec(s.radiance)},
                {"up", vec(s.up)},
                {"radius_scale", number(s.radius_scale)}};
    if (s.full_sphere) j["sky"]["full_sphere"] = true;
    if (s.map) {
      const std::string file = stem + "_sky.exr";
      write_image(dir / file, s.map->image);
      j["sky"]["image"] = file;
      j["sky"]["mapping"] =
          s.map->mapping == EnvironmentMap::Mapping::Equirect ? "equirect" : "equal-area";
      Affine to_map;
      std::copy(&s.map->world_to_map[0][0], &s.map->world_to_map[0][0] + 9, &to_map.a[0][0]);
      const Affine to_world = inverse(to_map);
      json rows = json::array();
      for (int i = 0; i < 3; ++i)
        rows.push_back(json::array(
            {number(to_world.a[i][0]), number(to_world.a[i][1]), number(to_world.a[i][2]), 0}));
      rows.push_back(json::array({0, 0, 0, 1}));
      j["sky"]["transform"] = {{"matrix", rows}};
    }
  }

  if (!used_materials.empty()) {
    for (const auto& [tex, file] : texture_files)
      write_image(dir / file, scene.textures[size_t(tex)]);

    std::string mtl = "# Materials of " + obj_name + ", written by rll; " +
                      json_path.filename().string() + " holds their exact parameters.\n\n";
    json materials = json::object(), material_map = json::object();
    for (size_t i = 0; i < used_materials.size(); ++i) {
      const Material& m = scene.materials[used_materials[i]];
      append_mtl(mtl, names[i], m, texture_of(m.albedo_texture));
      const bool rough = texture_files.count(m.roughness_texture) > 0;
      materials[names[i]] = material_json(m, texture_of(m.albedo_texture),
                                          rough ? texture_of(m.roughness_texture) : "");
      if (m.is_emissive() && m.emission_texture >= 0)
        materials[names[i]]["emission_texture"] = texture_of(m.emission_texture);
      material_map[names[i]] = names[i];
    }

    // The vertices the written triangles use, in the mesh's order: the OBJ reader numbers
    // vertices in the order of the file's positions, so the mesh reads back numbered the same.
    std::vector<bool> used(mesh.positions.size(), false);
    for (size_t t = 0; t < mesh.triangle_count(); ++t)
      if (written(t))
        for (uint32_t v : mesh.triangles[t]) used[v] = true;
    std::vector<int64_t> remap(mesh.positions.size(), -1);
    std::vector<uint32_t> order;
    for (size_t v = 0; v < used.size(); ++v)
      if (used[v]) {
        remap[v] = int64_t(order.size());
        order.push_back(uint32_t(v));
      }
    // A zero normal means "none" and a zero uv is the default: those are left out (other
    // programs read "vn 0 0 0" as a broken normal), and read back as zero all the same.
    const bool normals = !mesh.normals.empty(), uvs = !mesh.uvs.empty();
    std::vector<int64_t> uv_index(order.size(), 0), normal_index(order.size(), 0);
    fmt::memory_buffer obj;
    auto out = std::back_inserter(obj);
    fmt::format_to(out, "# Written by rll; {} describes the scene.\nmtllib {}\n",
                   json_path.filename().string(), escape_spaces(mtl_name));
    for (uint32_t v : order) {
      const Vec3& p = mesh.positions[v];
      fmt::format_to(out, "v {} {} {}\n", p.x, p.y, p.z);
    }
    int64_t count = 0;
    if (uvs) {
      for (size_t i = 0; i < order.size(); ++i) {
        const Vec2& t = mesh.uvs[order[i]];
        if (t.x == 0 && t.y == 0) continue;
        fmt::format_to(out, "vt {} {}\n", t.x, t.y);
        uv_index[i] = ++count;
      }
      // Keep the mesh's uvs (all zero) rather than none, which would read back as barycentrics.
      if (count == 0) fmt::format_to(out, "vt 0 0\n");
    }
    count = 0;
    if (normals)
      for (size_t i = 0; i < order.size(); ++i) {
        const Vec3& n = mesh.normals[order[i]];
        if (n == Vec3(0)) continue;
        fmt::format_to(out, "vn {} {} {}\n", n.x, n.y, n.z);
        normal_index[i] = ++count;
      }
    int64_t current = -1;
    for (size_t t = 0; t < mesh.triangle_count(); ++t) {
      if (!written(t)) continue;
      if (int64_t(mesh.material[t]) != current) {
        current = mesh.material[t];
        fmt::format_to(out, "usemtl {}\n", names[size_t(material_slot[size_t(current)])]);
      }
      obj.push_back('f');
      for (uint32_t v : mesh.triangles[t]) {
        const size_t i = size_t(remap[v]);
        fmt::format_to(out, " {}", i + 1);
        if (uv_index[i] > 0) fmt::format_to(out, "/{}", uv_index[i]);
        if (normal_index[i] > 0)
          fmt::format_to(out, "{}/{}", uv_index[i] > 0 ? "" : "/", normal_index[i]);
      }
      obj.push_back('\n');
    }
    write_file_atomic(dir / mtl_name, mtl);
    write_file_atomic(dir / obj_name, fmt::to_string(obj));
    j["materials"] = materials;
    j["shapes"] = json::array({{{"file", obj_name}, {"material_map", material_map}}});
  }
  std::string text;
  write_pretty(text, j, 0);
  write_file_atomic(json_path, text + "\n");
}

}  // namespace

void save_json_scene(const Scene& scene, const fs::path& json_path) {
  // The JSON, its OBJ, MTL and images replace an earlier conversion's together or not at all: a
  // full disk halfway must not leave a new .mtl beside an old .obj.
  WriteBatch batch;
  write_json_scene(scene, json_path);
  batch.commit();
}

std::string ply_bytes(const Mesh& mesh, PlyEncoding encoding) {
  const bool normals = !mesh.normals.empty(), uvs = !mesh.uvs.empty();
  const char* format = encoding == PlyEncoding::Ascii                ? "ascii"
                       : encoding == PlyEncoding::BinaryLittleEndian ? "binary_little_endian"
                                                                     : "binary_big_endian";
  std::string out = fmt::format("ply\nformat {} 1.0\ncomment written by rll\nelement vertex {}\n",
                                format, mesh.positions.size());
  out += "property float x\nproperty float y\nproperty float z\n";
  if (normals) out += "property float nx\nproperty float ny\nproperty float nz\n";
  if (uvs) out += "property float u\nproperty float v\n";
  out += fmt::format("element face {}\nproperty list uchar int vertex_indices\nend_header\n",
                     mesh.triangles.size());
  if (encoding == PlyEncoding::Ascii) {
    fmt::memory_buffer b;
    auto it = std::back_inserter(b);
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
      const Vec3& p = mesh.positions[i];
      fmt::format_to(it, "{} {} {}", p.x, p.y, p.z);
      if (normals) fmt::format_to(it, " {} {} {}", mesh.normals[i].x, mesh.normals[i].y, mesh.normals[i].z);
      if (uvs) fmt::format_to(it, " {} {}", mesh.uvs[i].x, mesh.uvs[i].y);
      b.push_back('\n');
    }
    for (const auto& t : mesh.triangles) fmt::format_to(it, "3 {} {} {}\n", t[0], t[1], t[2]);
    out.append(b.data(), b.size());
    return out;
  }
  const bool swap = (encoding == PlyEncoding::BinaryBigEndian) == (std::endian::native == std::endian::little);
  auto put = [&](auto v) {
    char bytes[sizeof(v)];
    std::memcpy(bytes, &v, sizeof(v));
    if (swap) std::reverse(bytes, bytes + sizeof(v));
    out.append(bytes, sizeof(v));
  };
  out.reserve(out.size() + mesh.positions.size() * 32 + mesh.triangles.size() * 13);
  for (size_t i = 0; i < mesh.positions.size(); ++i) {
    for (int k = 0; k < 3; ++k) put(mesh.positions[i][k]);
    if (normals)
      for (int k = 0; k < 3; ++k) put(mesh.normals[i][k]);
    if (uvs) {
      put(mesh.uvs[i].x);
      put(mesh.uvs[i].y);
    }
  }
  for (const auto& t : mesh.triangles) {
    put(uint8_t(3));
    for (uint32_t v : t) put(int32_t(v));
  }
  return out;
}

std::vector<MaterialMesh> split_by_material(const Scene& scene) {
  const Mesh& mesh = scene.mesh;
  const size_t sky_begin = scene.sky_first_triangle, sky_end = sky_begin + scene.sky_triangle_count;
  std::map<uint32_t, size_t> slot;
  std::vector<MaterialMesh> out;
  std::vector<int64_t> remap(mesh.positions.size(), -1);
  std::vector<std::vector<uint32_t>> triangles;
  for (size_t t = 0; t < mesh.triangle_count(); ++t) {
    if (t >= sky_begin && t < sky_end) continue;
    auto [it, added] = slot.emplace(mesh.material[t], out.size());
    if (added) {
      out.push_back({mesh.material[t], {}});
      triangles.emplace_back();
    }
    triangles[it->second].push_back(uint32_t(t));
  }
  for (size_t i = 0; i < out.size(); ++i) {
    Mesh& m = out[i].mesh;
    std::vector<uint32_t> used;
    for (uint32_t t : triangles[i]) {
      std::array<uint32_t, 3> tri;
      for (int k = 0; k < 3; ++k) {
        const uint32_t v = mesh.triangles[t][size_t(k)];
        if (remap[v] < 0) {
          remap[v] = int64_t(m.positions.size());
          used.push_back(v);
          m.positions.push_back(mesh.positions[v]);
          if (!mesh.normals.empty()) m.normals.push_back(mesh.normals[v]);
          if (!mesh.uvs.empty()) m.uvs.push_back(mesh.uvs[v]);
        }
        tri[size_t(k)] = uint32_t(remap[v]);
      }
      m.triangles.push_back(tri);
    }
    for (uint32_t v : used) remap[v] = -1;
    // A zero normal means "none" in rll; other formats have no such value, so a mesh with any
    // is written without normals.
    if (std::any_of(m.normals.begin(), m.normals.end(), [](const Vec3& n) { return n == Vec3(0); }))
      m.normals.clear();
  }
  return out;
}

}  // namespace rll
