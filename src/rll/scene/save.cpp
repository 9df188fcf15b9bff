#include "rll/scene/save.h"

#include <fmt/format.h>

#include <charconv>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "rll/core/error.h"

namespace rll {
namespace fs = std::filesystem;
using json = nlohmann::json;

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

json material_json(const Material& m, const std::string& texture) {
  json j;
  j["type"] = material_type_name(m.type);
  if (m.type != MaterialType::Conductor) {
    j["albedo"] = vec(m.albedo);
    if (!texture.empty()) j["texture"] = texture;
  }
  if (m.type != MaterialType::Diffuse) {
    j["specular"] = vec(m.specular);
    j["roughness"] = number(m.roughness);
  }
  if (m.type == MaterialType::Conductor) {
    j["eta"] = vec(m.eta);
    j["k"] = vec(m.k);
  }
  if (m.type == MaterialType::Plastic) j["ior"] = number(m.ior);
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
  }
  if (m.is_emissive()) out += fmt::format("Ke {}\n", rgb(m.emission));
  if (!texture.empty()) out += fmt::format("map_Kd {}\n", texture);
  out += "\n";
}

}  // namespace

void save_json_scene(const Scene& scene, const fs::path& json_path) {
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
  for (uint32_t m : used_materials) {
    names.push_back(unique_name(scene.materials[m].name, taken));
    int tex = scene.materials[m].albedo_texture;
    if (tex >= 0 && !texture_files.count(tex))
      texture_files[tex] = fmt::format("{}_tex{}.exr", stem, texture_files.size());
  }
  auto texture_of = [&](const Material& m) {
    return m.albedo_texture >= 0 ? texture_files.at(m.albedo_texture) : std::string();
  };

  json j;
  j["camera"] = {{"position", vec(scene.camera.position)},
                 {"target", vec(scene.camera.target)},
                 {"up", vec(scene.camera.up)},
                 {"fov", number(scene.camera.fov)}};
  j["film"] = {{"width", scene.width}, {"height", scene.height}};
  json lights = json::array();
  for (const Light& l : scene.lights) {
    if (l.type == LightType::Point)
      lights.push_back(
          {{"type", "point"}, {"position", vec(l.p0)}, {"intensity", vec(l.radiance)}});
    else if (l.type == LightType::Directional)
      lights.push_back(
          {{"type", "directional"}, {"direction", vec(l.p0)}, {"irradiance", vec(l.radiance)}});
  }
  if (!lights.empty()) j["lights"] = lights;
  if (scene.sky) {
    const SkyDome& s = *scene.sky;
    j["sky"] = {{"type", "dome"},
                {"triangles", s.triangles},
                {"radiance", vec(s.radiance)},
                {"up", vec(s.up)},
                {"radius_scale", number(s.radius_scale)}};
  }

  if (!used_materials.empty()) {
    for (const auto& [tex, file] : texture_files)
      write_image(dir / file, scene.textures[size_t(tex)]);

    std::string mtl = "# Materials of " + obj_name + ", written by rll; " +
                      json_path.filename().string() + " holds their exact parameters.\n\n";
    json materials = json::object(), material_map = json::object();
    for (size_t i = 0; i < used_materials.size(); ++i) {
      const Material& m = scene.materials[used_materials[i]];
      append_mtl(mtl, names[i], m, texture_of(m));
      materials[names[i]] = material_json(m, texture_of(m));
      material_map[names[i]] = names[i];
    }

    // Vertices in order of first use, so that reading the OBJ back (which numbers vertices in
    // that order) gives the same mesh.
    std::vector<int64_t> remap(mesh.positions.size(), -1);
    std::vector<uint32_t> order;
    order.reserve(mesh.positions.size());
    for (size_t t = 0; t < mesh.triangle_count(); ++t)
      if (written(t))
        for (uint32_t v : mesh.triangles[t])
          if (remap[v] < 0) {
            remap[v] = int64_t(order.size());
            order.push_back(v);
          }
    const bool normals = !mesh.normals.empty(), uvs = !mesh.uvs.empty();
    fmt::memory_buffer obj;
    fmt::format_to(std::back_inserter(obj),
                   "# Written by rll; {} describes the scene.\nmtllib {}\n",
                   json_path.filename().string(), escape_spaces(mtl_name));
    for (uint32_t v : order) {
      const Vec3& p = mesh.positions[v];
      fmt::format_to(std::back_inserter(obj), "v {} {} {}\n", p.x, p.y, p.z);
    }
    if (uvs)
      for (uint32_t v : order)
        fmt::format_to(std::back_inserter(obj), "vt {} {}\n", mesh.uvs[v].x, mesh.uvs[v].y);
    if (normals)
      for (uint32_t v : order) {
        const Vec3& n = mesh.normals[v];
        fmt::format_to(std::back_inserter(obj), "vn {} {} {}\n", n.x, n.y, n.z);
      }
    int64_t current = -1;
    for (size_t t = 0; t < mesh.triangle_count(); ++t) {
      if (!written(t)) continue;
      if (int64_t(mesh.material[t]) != current) {
        current = mesh.material[t];
        fmt::format_to(std::back_inserter(obj), "usemtl {}\n",
                       names[size_t(material_slot[size_t(current)])]);
      }
      obj.push_back('f');
      for (uint32_t v : mesh.triangles[t]) {
        int64_t i = remap[v] + 1;
        if (normals && uvs)
          fmt::format_to(std::back_inserter(obj), " {}/{}/{}", i, i, i);
        else if (normals)
          fmt::format_to(std::back_inserter(obj), " {}//{}", i, i);
        else if (uvs)
          fmt::format_to(std::back_inserter(obj), " {}/{}", i, i);
        else
          fmt::format_to(std::back_inserter(obj), " {}", i);
      }
      obj.push_back('\n');
    }
    write_file_atomic(dir / mtl_name, mtl);
    write_file_atomic(dir / obj_name, fmt::to_string(obj));
    j["materials"] = materials;
    j["shapes"] = json::array({{{"file", obj_name}, {"material_map", material_map}}});
  }
  write_file_atomic(json_path, j.dump(2) + "\n");
}

}  // namespace rll
