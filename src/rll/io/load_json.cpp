// rll's JSON scene format (docs/scene-format.md): camera, film, materials, shapes (OBJ files
// and inline primitives), point and directional lights, sky. Strict: an unknown field, a wrong
// type, a non-finite number or a duplicate key is an error naming the file and the JSON
// pointer of the field.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>

#include "rll/core/error.h"
#include "rll/core/memory_budget.h"
#include "rll/core/paths.h"
#include "rll/io/load.h"
#include "rll/io/text_scan.h"
#include "rll/scene/builder.h"
#include "rll/scene/transform.h"

namespace rll {
namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

// JSON pointer (RFC 6901) of a child field or element.
std::string child(const std::string& ptr, std::string_view key) {
  std::string s = ptr + "/";
  for (char c : key) {
    if (c == '~')
      s += "~0";
    else if (c == '/')
      s += "~1";
    else
      s += c;
  }
  return s;
}
std::string child(const std::string& ptr, size_t index) {
  return ptr + "/" + std::to_string(index);
}
std::string where(const std::string& ptr) {
  return ptr.empty() ? "/" : ptr;
}

// Errors below are thrown without the file name; load_json_scene adds it in front.
const json& check_is_object(const json& v, const std::string& ptr) {
  if (!v.is_object()) fail("{} must be an object (got {})", where(ptr), v.type_name());
  return v;
}

void check_object(const json& v, const std::string& ptr,
                  std::initializer_list<std::string_view> known) {
  check_is_object(v, ptr);
  for (const auto& item : v.items()) {
    if (std::find(known.begin(), known.end(), item.key()) != known.end()) continue;
    std::string list;
    for (auto k : known) list += (list.empty() ? "" : ", ") + std::string(k);
    fail("unknown field \"{}\" in {} (known fields: {})", printable(item.key()), where(ptr), list);
  }
}

const json& check_array(const json& v, const std::string& ptr) {
  if (!v.is_array()) fail("{} must be an array (got {})", ptr, v.type_name());
  return v;
}

float to_number(const json& v, const std::string& ptr) {
  if (!v.is_number()) fail("{} must be a number (got {})", ptr, v.type_name());
  double d = v.get<double>();
  if (!std::isfinite(d) || !std::isfinite(float(d)))
    fail("{} must be a finite number (got {})", ptr, v.dump());
  return float(d);
}

int to_int(const json& v, const std::string& ptr) {
  if (!v.is_number_integer()) fail("{} must be an integer (got {})", ptr, v.dump());
  if (v.is_number_unsigned() ? v.get<uint64_t>() > uint64_t(INT32_MAX)
                             : (v.get<int64_t>() > INT32_MAX || v.get<int64_t>() < INT32_MIN))
    fail("{} is out of range (got {})", ptr, v.dump());
  return int(v.get<int64_t>());
}

bool to_bool(const json& v, const std::string& ptr) {
  if (!v.is_boolean()) fail("{} must be true or false (got {})", ptr, v.type_name());
  return v.get<bool>();
}

std::string to_string(const json& v, const std::string& ptr) {
  if (!v.is_string()) fail("{} must be a string (got {})", ptr, v.type_name());
  return v.get<std::string>();
}

Vec3 to_vec3(const json& v, const std::string& ptr) {
  if (!v.is_array() || v.size() != 3)
    fail("{} must be an array of 3 numbers (got {})", ptr,
         v.is_array() ? fmt::format("{} values", v.size()) : v.type_name());
  return Vec3(to_number(v[0], child(ptr, 0)), to_number(v[1], child(ptr, 1)),
              to_number(v[2], child(ptr, 2)));
}

Vec3 to_direction(const json& v, const std::string& ptr) {
  Vec3 d = to_vec3(v, ptr);
  if (!(length_sq(d) > 0) || !std::isfinite(length_sq(d)))
    fail("{} must be a non-zero vector", ptr);
  return d;
}

// Three non-zero vec3 rows.
std::array<Vec3, 3> to_rows(const json& v, const std::string& ptr) {
  if (!v.is_array() || v.size() != 3) fail("{} must be an array of 3 vec3 rows", ptr);
  return {to_direction(v[0], child(ptr, size_t(0))), to_direction(v[1], child(ptr, size_t(1))),
          to_direction(v[2], child(ptr, size_t(2)))};
}

Rgb to_colour(const json& v, const std::string& ptr) {
  Rgb c = to_vec3(v, ptr);
  for (int i = 0; i < 3; ++i)
    if (c[i] < 0) fail("{} must not be negative (got {})", child(ptr, size_t(i)), c[i]);
  return c;
}

// The field `key` of `obj` converted by `conv`; nullopt when absent.
template <typename T>
std::optional<T> optional_field(const json& obj, const std::string& ptr, const char* key,
                                T (*conv)(const json&, const std::string&)) {
  auto it = obj.find(key);
  if (it == obj.end()) return std::nullopt;
  return conv(*it, child(ptr, key));
}

template <typename T>
T required_field(const json& obj, const std::string& ptr, const char* key,
                 T (*conv)(const json&, const std::string&)) {
  auto it = obj.find(key);
  if (it == obj.end()) fail("{}: missing field \"{}\"", where(ptr), key);
  return conv(*it, child(ptr, key));
}

float positive(float x, const std::string& ptr) {
  if (!(x > 0)) fail("{} must be positive (got {})", ptr, x);
  return x;
}

Affine to_transform(const json& v, const std::string& ptr) {
  check_object(v, ptr, {"translate", "scale", "rotate", "matrix"});
  Affine x;
  if (v.contains("matrix")) {
    if (v.size() > 1) fail("{}: give either \"matrix\" or translate/scale/rotate, not both", ptr);
    const std::string mp = child(ptr, "matrix");
    const json& m = v["matrix"];
    if (!m.is_array() || m.size() != 4) fail("{} must be an array of 4 rows of 4 numbers", mp);
    float r[4][4];
    for (size_t i = 0; i < 4; ++i) {
      if (!m[i].is_array() || m[i].size() != 4)
        fail("{} must be an array of 4 numbers", child(mp, i));
      for (size_t j = 0; j < 4; ++j) r[i][j] = to_number(m[i][j], child(child(mp, i), j));
    }
    if (r[3][0] != 0 || r[3][1] != 0 || r[3][2] != 0 || r[3][3] != 1)
      fail("{} must be [0, 0, 0, 1] (only affine transforms)", child(mp, 3));
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) x.a[i][j] = r[i][j];
      x.t[i] = r[i][3];
    }
  } else {
    // Scale, then rotate, then translate.
    if (auto it = v.find("scale"); it != v.end()) {
      Vec3 s = it->is_number() ? Vec3(to_number(*it, child(ptr, "scale")))
                               : to_vec3(*it, child(ptr, "scale"));
      const float m[3][3] = {{s.x, 0, 0}, {0, s.y, 0}, {0, 0, s.z}};
      x.prepend(m);
    }
    if (auto it = v.find("rotate"); it != v.end()) {
      const std::string rp = child(ptr, "rotate");
      check_object(*it, rp, {"axis", "angle"});
      Vec3 u = normalize(required_field(*it, rp, "axis", to_direction));
      float th = radians(required_field(*it, rp, "angle", to_number));
      float c = std::cos(th), s = std::sin(th), k = 1 - c;
      const float m[3][3] = {{c + u.x * u.x * k, u.x * u.y * k - u.z * s, u.x * u.z * k + u.y * s},
                             {u.y * u.x * k + u.z * s, c + u.y * u.y * k, u.y * u.z * k - u.x * s},
                             {u.z * u.x * k - u.y * s, u.z * u.y * k + u.x * s, c + u.z * u.z * k}};
      x.prepend(m);
    }
    if (auto it = v.find("translate"); it != v.end()) x.t = to_vec3(*it, child(ptr, "translate"));
  }
  const float d = x.det();
  if (!(std::abs(d) > 0) || !std::isfinite(d)) {
    // Say which: a determinant of 0 flattens the shape; one beyond a float (a scale of 1e30 in
    // each axis gives 1e90), or below one, is a scale rll's single precision cannot apply.
    double dd = 0;
    for (int j = 0; j < 3; ++j)
      dd += double(x.a[0][j]) * (double(x.a[1][(j + 1) % 3]) * x.a[2][(j + 2) % 3] -
                                 double(x.a[1][(j + 2) % 3]) * x.a[2][(j + 1) % 3]);
    std::string matrix = "[";
    for (int i = 0; i < 3; ++i)
      matrix += fmt::format("{:g} {:g} {:g} {:g}{}", x.a[i][0], x.a[i][1], x.a[i][2], x.t[i],
                            i < 2 ? "; " : "]");
    if (dd == 0)
      fail("{} is singular: its determinant is 0 (it flattens the shape); matrix {}", ptr, matrix);
    fail(
        "{} scales volumes by {:g} (lengths by about {:g}), {} for rll, which transforms in single "
        "precision; matrix {}",
        ptr, dd, std::cbrt(std::abs(dd)), !(std::abs(dd) < 1) ? "too large" : "too small", matrix);
  }
  return x;
}

// Builds the scene from a parsed JSON document.
class JsonSceneReader {
 public:
  JsonSceneReader(const fs::path& base_dir, Scene& scene, const ReadPolicy& policy)
      : m_base(base_dir), m_scene(scene), m_policy(policy) {}

  void read(const json& root) {
    check_object(root, "", {"camera", "film", "materials", "shapes", "lights", "sky"});
    if (auto it = root.find("materials"); it != root.end())
      for (const auto& item : check_is_object(*it, "/materials").items()) {
        std::string ptr = child("/materials", item.key());
        if (item.key().empty()) fail("{}: a material name must not be empty", ptr);
        m_named[item.key()] = add_material(item.value(), ptr, item.key());
      }
    if (auto it = root.find("camera"); it != root.end()) read_camera(*it, "/camera");
    if (auto it = root.find("film"); it != root.end()) read_film(*it, "/film");
    if (auto it = root.find("shapes"); it != root.end()) {
      check_array(*it, "/shapes");
      for (size_t i = 0; i < it->size(); ++i) read_shape((*it)[i], child("/shapes", i));
    }
    if (auto it = root.find("lights"); it != root.end()) {
      check_array(*it, "/lights");
      for (size_t i = 0; i < it->size(); ++i) read_light((*it)[i], child("/lights", i));
    }
    if (auto it = root.find("sky"); it != root.end()) read_sky(*it, "/sky");
  }

 private:
  fs::path resolve(const std::string& name) const {
    return (m_base / name).lexically_normal();
  }

  // A file named by the scene, which must exist.
  fs::path referenced_file(const json& v, const std::string& ptr) const {
    std::string name = to_string(v, ptr);
    if (name.empty()) fail("{} must not be empty", ptr);
    if (!m_policy.read_files)
      fail("{}: '{}': reading other files is turned off", ptr, printable(name));
    fs::path p = resolve(name);
    if (const std::string why = unreadable_reason(p); !why.empty())
      fail("{}: '{}' {} ({})", ptr, printable(name), why, printable(p.string(), 256));
    return p;
  }

  uint32_t add_material(const json& v, const std::string& ptr, const std::string& name) {
    check_object(v, ptr,
                 {"type", "albedo", "roughness", "eta", "k", "ior", "specular", "emission",
                  "two_sided", "texture", "roughness_texture", "thickness", "emission_texture"});
    Material m;
    m.name = name;
    std::string type = optional_field(v, ptr, "type", to_string).value_or("diffuse");
    std::vector<std::string_view> applies;
    if (type == "diffuse") {
      m.type = MaterialType::Diffuse;
      applies = {"albedo", "texture"};
    } else if (type == "conductor") {
      m.type = MaterialType::Conductor;
      applies = {"eta", "k", "specular", "roughness", "roughness_texture"};
    } else if (type == "plastic") {
      m.type = MaterialType::Plastic;
      applies = {"albedo", "texture", "specular", "roughness", "roughness_texture", "ior"};
    } else if (type == "dielectric") {
      m.type = MaterialType::Dielectric;
      m.roughness = 0;  // smooth glass unless said otherwise
      applies = {"ior", "roughness", "roughness_texture"};
    } else if (type == "thindielectric") {
      m.type = MaterialType::ThinDielectric;
      m.roughness = 0;  // a smooth pane
      applies = {"ior"};
    } else if (type == "coateddiffuse") {
      m.type = MaterialType::CoatedDiffuse;
      m.roughness = 0;  // a smooth coating unless said otherwise (pbrt-v4's default)
      applies = {"albedo", "texture", "roughness", "roughness_texture", "ior", "thickness"};
    } else {
      fail(
          "{}: unknown material type '{}' (rll knows diffuse, conductor, plastic, dielectric, "
          "thindielectric, coateddiffuse)",
          child(ptr, "type"), printable(type));
    }
    applies.insert(applies.end(), {"type", "emission", "two_sided", "emission_texture"});
    for (const auto& item : v.items())
      if (std::find(applies.begin(), applies.end(), item.key()) == applies.end())
        fail("{}: field \"{}\" does not apply to a {} material", ptr, printable(item.key()), type);
    m.albedo = optional_field(v, ptr, "albedo", to_colour).value_or(m.albedo);
    m.specular = optional_field(v, ptr, "specular", to_colour).value_or(m.specular);
    m.eta = optional_field(v, ptr, "eta", to_colour).value_or(m.eta);
    for (int i = 0; i < 3; ++i) positive(m.eta[i], child(child(ptr, "eta"), size_t(i)));
    m.k = optional_field(v, ptr, "k", to_colour).value_or(m.k);
    m.ior = optional_field(v, ptr, "ior", to_number).value_or(m.ior);
    if (!(m.ior >= 1)) fail("{} must be at least 1 (got {})", child(ptr, "ior"), m.ior);
    m.roughness = optional_field(v, ptr, "roughness", to_number).value_or(m.roughness);
    if (!(m.roughness >= 0))
      fail("{} must not be negative (got {})", child(ptr, "roughness"), m.roughness);
    m.thickness = optional_field(v, ptr, "thickness", to_number).value_or(m.thickness);
    if (!(m.thickness > 0))
      fail("{} must be positive (got {})", child(ptr, "thickness"), m.thickness);
    // With an emission texture, the emission (its factor) defaults to 1.
    m.emission = optional_field(v, ptr, "emission", to_colour)
                     .value_or(v.contains("emission_texture") ? Rgb(1) : m.emission);
    m.two_sided_emission = optional_field(v, ptr, "two_sided", to_bool).value_or(false);
    if (v.contains("texture"))
      m.albedo_texture = texture(v["texture"], child(ptr, "texture"), true);
    if (v.contains("roughness_texture"))
      m.roughness_texture =
          texture(v["roughness_texture"], child(ptr, "roughness_texture"), false);
    if (v.contains("emission_texture"))
      m.emission_texture = texture(v["emission_texture"], child(ptr, "emission_texture"), true);
    m_scene.materials.push_back(m);
    return uint32_t(m_scene.materials.size() - 1);
  }

  // An image file read once per decoding: colours from sRGB (8-bit files), data such as
  // roughness as it is stored.
  int texture(const json& v, const std::string& ptr, bool srgb) {
    fs::path p = referenced_file(v, ptr);
    auto it = m_textures.find({p, srgb});
    if (it != m_textures.end()) return it->second;
    try {
      m_scene.textures.push_back(read_image(p, srgb));
    } catch (const Error& e) {
      fail("{}: {}", ptr, e.what());
    }
    return m_textures[{p, srgb}] = int(m_scene.textures.size() - 1);
  }

  // A material given by name (from /materials) or inline.
  uint32_t material_ref(const json& v, const std::string& ptr) {
    if (v.is_string()) {
      auto it = m_named.find(v.get<std::string>());
      if (it == m_named.end())
        fail("{}: no material named \"{}\" in /materials", ptr, v.get<std::string>());
      return it->second;
    }
    if (!v.is_object())
      fail("{} must be a material name or a material object (got {})", ptr, v.type_name());
    return add_material(v, ptr, ptr);
  }

  uint32_t shape_material(const json& v, const std::string& ptr) {
    if (auto it = v.find("material"); it != v.end())
      return material_ref(*it, child(ptr, "material"));
    if (!m_default_material) {
      Material m;
      m.name = "default";
      m_scene.materials.push_back(m);
      m_default_material = uint32_t(m_scene.materials.size() - 1);
    }
    return *m_default_material;
  }

  // SceneBuilder gives quads (and boxes) uvs over [0, 1]^2 only when the mesh already has uvs;
  // a texture needs them, where otherwise each triangle would show its own barycentric patch.
  // The quads' vertices from v0 on come in fours: p, p+e1, p+e1+e2, p+e2.
  void quad_uvs(uint32_t material, size_t v0) {
    Mesh& mesh = m_scene.mesh;
    const Material& m = m_scene.materials[material];
    if (m.albedo_texture < 0 && m.roughness_texture < 0 && m.emission_texture < 0) return;
    mesh.uvs.resize(mesh.positions.size(), Vec2{});
    static const Vec2 kCorners[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    for (size_t i = v0; i < mesh.positions.size(); ++i) mesh.uvs[i] = kCorners[(i - v0) % 4];
  }

  void read_camera(const json& v, const std::string& ptr) {
    check_object(
        v, ptr,
        {"position", "target", "up", "fov", "lens_radius", "focal_distance", "screen_window"});
    Camera& c = m_scene.camera;
    c.position = required_field(v, ptr, "position", to_vec3);
    c.target = required_field(v, ptr, "target", to_vec3);
    c.up = optional_field(v, ptr, "up", to_direction).value_or(Vec3(0, 1, 0));
    c.fov = optional_field(v, ptr, "fov", to_number).value_or(45.0f);
    if (!(c.fov > 0 && c.fov < 180))
      fail("{} must be in (0, 180) degrees (got {})", child(ptr, "fov"), c.fov);
    if (!(length_sq(c.target - c.position) > 0)) fail("{}: position and target must differ", ptr);
    c.lens_radius = optional_field(v, ptr, "lens_radius", to_number).value_or(0.0f);
    if (!(c.lens_radius >= 0))
      fail("{} must not be negative (got {})", child(ptr, "lens_radius"), c.lens_radius);
    c.focal_distance = positive(
        optional_field(v, ptr, "focal_distance", to_number).value_or(Camera().focal_distance),
        child(ptr, "focal_distance"));
    if (auto it = v.find("screen_window"); it != v.end()) {
      const std::string sp = child(ptr, "screen_window");
      if (!it->is_array() || it->size() != 4)
        fail("{} must be an array of 4 numbers [xmin, xmax, ymin, ymax] (got {})", sp,
             it->is_array() ? fmt::format("{} values", it->size()) : it->type_name());
      for (size_t i = 0; i < 4; ++i) c.screen_window[i] = to_number((*it)[i], child(sp, i));
      const auto& w = c.screen_window;
      if (!(w[0] < w[1]) || !(w[2] < w[3]))
        fail("{} needs xmin < xmax and ymin < ymax (got [{}, {}, {}, {}])", sp, w[0], w[1], w[2],
             w[3]);
    }
    m_scene.has_camera = true;
  }

  void read_film(const json& v, const std::string& ptr) {
    check_object(v, ptr, {"width", "height"});
    for (const char* key : {"width", "height"}) {
      auto value = optional_field(v, ptr, key, to_int);
      if (!value) continue;
      if (*value <= 0) fail("{} must be a positive integer (got {})", child(ptr, key), *value);
      (std::string_view(key) == "width" ? m_scene.width : m_scene.height) = *value;
    }
  }

  void read_shape(const json& v, const std::string& ptr) {
    if (!v.is_object()) fail("{} must be an object (got {})", ptr, v.type_name());
    const size_t t0 = m_scene.mesh.triangle_count(), v0 = m_scene.mesh.positions.size();
    if (v.contains("file")) {
      if (v.contains("type")) fail("{}: give either \"file\" or \"type\", not both", ptr);
      read_mesh_file(v, ptr);
    } else {
      std::string type = required_field(v, ptr, "type", to_string);
      SceneBuilder b(m_scene);
      if (type == "quad") {
        check_object(v, ptr, {"type", "origin", "edge1", "edge2", "material", "transform"});
        Vec3 o = required_field(v, ptr, "origin", to_vec3),
             e1 = required_field(v, ptr, "edge1", to_vec3),
             e2 = required_field(v, ptr, "edge2", to_vec3);
        if (!(length_sq(cross(e1, e2)) > 0))
          fail("{}: edge1 and edge2 must be non-zero and not parallel", ptr);
        uint32_t m = shape_material(v, ptr);
        b.quad(o, e1, e2, m);
        quad_uvs(m, v0);
      } else if (type == "triangle") {
        check_object(v, ptr, {"type", "vertices", "material", "transform"});
        const std::string vp = child(ptr, "vertices");
        auto it = v.find("vertices");
        if (it == v.end()) fail("{}: missing field \"vertices\"", ptr);
        if (!it->is_array() || it->size() != 3) fail("{} must be an array of 3 points", vp);
        Vec3 p[3];
        for (size_t i = 0; i < 3; ++i) p[i] = to_vec3((*it)[i], child(vp, i));
        if (!(length_sq(cross(p[1] - p[0], p[2] - p[0])) > 0))
          fail("{}: the triangle is degenerate", vp);
        b.triangle(p[0], p[1], p[2], shape_material(v, ptr));
      } else if (type == "box") {
        check_object(v, ptr, {"type", "min", "max", "inward", "skip", "material", "transform"});
        Vec3 lo = required_field(v, ptr, "min", to_vec3),
             hi = required_field(v, ptr, "max", to_vec3);
        if (!(lo.x < hi.x && lo.y < hi.y && lo.z < hi.z))
          fail("{}: min must be below max on every axis", ptr);
        unsigned skip = 0;
        if (auto it = v.find("skip"); it != v.end()) {
          const std::string sp = child(ptr, "skip");
          check_array(*it, sp);
          static const char* kFaces[] = {"-x", "+x", "-y", "+y", "-z", "+z"};
          for (size_t i = 0; i < it->size(); ++i) {
            std::string f = to_string((*it)[i], child(sp, i));
            auto k = std::find(std::begin(kFaces), std::end(kFaces), f);
            if (k == std::end(kFaces))
              fail("{}: unknown face '{}' (faces: -x +x -y +y -z +z)", child(sp, i), printable(f));
            skip |= 1u << (k - std::begin(kFaces));
          }
        }
        uint32_t m = shape_material(v, ptr);
        b.box(lo, hi, m, optional_field(v, ptr, "inward", to_bool).value_or(false), skip);
        quad_uvs(m, v0);
      } else if (type == "sphere") {
        check_object(
            v, ptr,
            {"type", "center", "radius", "subdivisions", "inward", "material", "transform"});
        Vec3 c = required_field(v, ptr, "center", to_vec3);
        float r = positive(required_field(v, ptr, "radius", to_number), child(ptr, "radius"));
        int sub = optional_field(v, ptr, "subdivisions", to_int).value_or(3);
        if (sub < 0 || sub > 8)
          fail("{} must be in [0, 8] (got {})", child(ptr, "subdivisions"), sub);
        // A sphere of 8 subdivisions is a million triangles from a few bytes of JSON.
        if (const std::string why = triangle_budget_problem(
                double(m_scene.mesh.triangle_count()) + 20 * std::pow(4.0, sub), m_policy);
            !why.empty())
          fail("{}: {}", ptr, why);
        b.sphere(c, r, sub, shape_material(v, ptr),
                 optional_field(v, ptr, "inward", to_bool).value_or(false));
      } else {
        fail(
            "{}: unknown shape type '{}' (rll knows quad, triangle, box, sphere, or {{\"file\": "
            "...}})",
            child(ptr, "type"), printable(type));
      }
    }
    if (auto it = v.find("transform"); it != v.end())
      transform_mesh(m_scene.mesh, to_transform(*it, child(ptr, "transform")), t0, v0);
  }

  void read_mesh_file(const json& v, const std::string& ptr) {
    check_object(v, ptr, {"file", "material", "material_map", "transform"});
    const fs::path file = referenced_file(v["file"], child(ptr, "file"));
    if (lower_extension(file) != ".obj")
      fail("{}: '{}': rll reads meshes from .obj files", child(ptr, "file"), file.string());
    const size_t t0 = m_scene.mesh.triangle_count(), m0 = m_scene.materials.size();
    try {
      load_obj(file, m_scene);
    } catch (const Error& e) {
      fail("{}: {}", ptr, e.what());
    }
    const size_t t1 = m_scene.mesh.triangle_count(), m1 = m_scene.materials.size();
    if (v.contains("material") && v.contains("material_map"))
      fail("{}: give either \"material\" or \"material_map\", not both", ptr);
    if (auto it = v.find("material"); it != v.end()) {
      uint32_t m = material_ref(*it, child(ptr, "material"));
      std::fill(m_scene.mesh.material.begin() + t0, m_scene.mesh.material.begin() + t1, m);
    }
    if (auto it = v.find("material_map"); it != v.end()) {
      const std::string mp = child(ptr, "material_map");
      check_is_object(*it, mp);
      std::map<uint32_t, uint32_t> replace;
      for (const auto& item : it->items()) {
        size_t k = m0;
        while (k < m1 && m_scene.materials[k].name != item.key()) ++k;
        if (k == m1)
          fail("{}: {} has no material named \"{}\"", mp, file.filename().string(), item.key());
        replace[uint32_t(k)] = material_ref(item.value(), child(mp, item.key()));
      }
      for (size_t t = t0; t < t1; ++t) {
        auto r = replace.find(m_scene.mesh.material[t]);
        if (r != replace.end()) m_scene.mesh.material[t] = r->second;
      }
    }
  }

  void read_light(const json& v, const std::string& ptr) {
    const size_t before = m_scene.lights.size();
    read_light_fields(v, ptr);
    for (size_t i = before; i < m_scene.lights.size(); ++i)
      if (const std::string why = light_parameter_problem(m_scene.lights[i]); !why.empty())
        fail(
            "{}: the {} light: {}; a light's parameters must be finite and its emission not "
            "negative",
            ptr, light_type_name(m_scene.lights[i].type), why);
  }

  void read_light_fields(const json& v, const std::string& ptr) {
    if (!v.is_object()) fail("{} must be an object (got {})", ptr, v.type_name());
    std::string type = required_field(v, ptr, "type", to_string);
    if (type == "directional") {
      check_object(v, ptr, {"type", "direction", "irradiance"});
      Vec3 d = required_field(v, ptr, "direction",
                              to_direction);  // normalized by make_directional_light
      m_scene.lights.push_back(
          make_directional_light(d, required_field(v, ptr, "irradiance", to_colour)));
    } else if (type == "point") {
      check_object(v, ptr, {"type", "position", "intensity"});
      m_scene.lights.push_back(make_point_light(required_field(v, ptr, "position", to_vec3),
                                                required_field(v, ptr, "intensity", to_colour)));
    } else if (type == "spot") {
      check_object(v, ptr, {"type", "position", "direction", "intensity", "cone_angle",
                            "cone_delta_angle"});
      // pbrt-v4's spot: full intensity within cone_angle - cone_delta_angle of the direction,
      // a smoothstep falloff (in the cosine) to nothing at cone_angle.
      const float cone = required_field(v, ptr, "cone_angle", to_number);
      const float delta = optional_field(v, ptr, "cone_delta_angle", to_number).value_or(0.0f);
      if (!(cone > 0 && cone <= 180))
        fail("{}: must be in (0, 180] degrees (got {})", child(ptr, "cone_angle"), cone);
      if (!(delta >= 0 && delta <= cone))
        fail("{}: must be in [0, cone_angle = {}] degrees (got {})", child(ptr, "cone_delta_angle"),
             cone, delta);
      m_scene.lights.push_back(make_spot_light(
          required_field(v, ptr, "position", to_vec3),
          required_field(v, ptr, "direction", to_direction),
          required_field(v, ptr, "intensity", to_colour), std::cos(radians(cone - delta)),
          std::cos(radians(cone))));
    } else if (type == "goniometric" || type == "projection") {
      check_object(v, ptr, {"type", "position", "scale", "image", "to_light"});
      const bool gonio = type == "goniometric";
      const std::string file = required_field(v, ptr, "image", to_string);
      Image image;
      try {
        image = read_image(referenced_file(v["image"], child(ptr, "image")));
      } catch (const Error& e) {
        fail("{}: {}", child(ptr, "image"), e.what());
      }
      if (gonio) {
        if (image.width() != image.height())
          fail("{}: '{}' is {}x{}: a goniometric image must be square (equal-area)",
               child(ptr, "image"), printable(file), image.width(), image.height());
        for (Rgb& c : image.pixels()) c = Rgb((c.x + c.y + c.z) / 3);
      }
      if (const std::string bad = bad_emission_texel(image); !bad.empty())
        fail("{}: '{}' has a negative or non-finite pixel, which no light can emit: {}",
             child(ptr, "image"), printable(file), bad);
      const std::array<Vec3, 3> to_light = required_field(v, ptr, "to_light", to_rows);
      Light l = make_image_light(gonio ? LightType::Goniometric : LightType::Projection,
                                 required_field(v, ptr, "position", to_vec3), to_light.data(),
                                 optional_field(v, ptr, "scale", to_colour).value_or(Rgb(1)),
                                 uint32_t(m_scene.textures.size()), 0);
      l.area = image_light_power_factor(l, image);
      m_scene.textures.push_back(std::move(image));
      m_scene.lights.push_back(l);
    } else {
      fail("{}: unknown light type '{}' (rll knows directional, point, spot, goniometric, "
           "projection)",
           child(ptr, "type"), printable(type));
    }
  }

  void read_sky(const json& v, const std::string& ptr) {
    check_object(v, ptr,
                 {"type", "triangles", "radiance", "up", "radius_scale", "full_sphere", "image",
                  "mapping", "transform"});
    std::string type = required_field(v, ptr, "type", to_string);
    if (type != "dome")
      fail("{}: unknown sky type '{}' (rll knows dome)", child(ptr, "type"), printable(type));
    SkyDome sky;
    sky.full_sphere = optional_field(v, ptr, "full_sphere", to_bool).value_or(false);
    sky.triangles = optional_field(v, ptr, "triangles", to_int).value_or(sky.triangles);
    if (sky.triangles < 4 || sky.triangles > (1 << 22))
      fail("{} must be in [4, {}] (got {})", child(ptr, "triangles"), 1 << 22, sky.triangles);
    if (sky.full_sphere && (sky.triangles < 8 || sky.triangles % 2 != 0))
      fail("{} must be even and at least 8 for a full sphere (got {})", child(ptr, "triangles"),
           sky.triangles);
    // 4 M dome triangles from a few bytes of JSON: counted as every other geometry is (with a
    // map, each triangle also gets a material of its own, held to the memory budget below).
    if (const std::string why = triangle_budget_problem(
            double(m_scene.mesh.triangle_count()) + sky.triangles, m_policy);
        !why.empty())
      fail("{}: {}", child(ptr, "triangles"), why);
    sky.radiance = optional_field(v, ptr, "radiance", to_colour).value_or(sky.radiance);
    sky.up = normalize(optional_field(v, ptr, "up", to_direction).value_or(sky.up));
    sky.radius_scale = optional_field(v, ptr, "radius_scale", to_number).value_or(sky.radius_scale);
    if (!(sky.radius_scale > 2))
      fail("{} must be greater than 2 (got {})", child(ptr, "radius_scale"), sky.radius_scale);
    if (v.contains("image")) {
      check_memory_budget(double(sky.triangles) * double(sizeof(Material)),
                          fmt::format("{} (a material for each of the sky's {} triangles)",
                                      child(ptr, "triangles"), sky.triangles));
      auto map = std::make_shared<EnvironmentMap>();
      const fs::path file = referenced_file(v["image"], child(ptr, "image"));
      try {
        map->image = read_image(file, /*srgb=*/true);
      } catch (const Error& e) {
        fail("{}: {}", child(ptr, "image"), e.what());
      }
      // As every light's image: the sky emits its map.
      if (const std::string bad = bad_emission_texel(map->image); !bad.empty())
        fail("{}: '{}' has a negative or non-finite pixel, which no light can emit: {}",
             child(ptr, "image"), printable(file.string()), bad);
      std::string mapping = optional_field(v, ptr, "mapping", to_string).value_or("equal-area");
      if (mapping == "equirect")
        map->mapping = EnvironmentMap::Mapping::Equirect;
      else if (mapping != "equal-area")
        fail("{}: unknown mapping '{}' (rll knows equal-area, equirect)", child(ptr, "mapping"),
             mapping);
      if (auto it = v.find("transform"); it != v.end()) {
        // The map's frame in the world; directions are looked up through its inverse.
        Affine x = to_transform(*it, child(ptr, "transform"));
        x.t = Vec3(0);
        const Affine inv = inverse(x);
        std::copy(&inv.a[0][0], &inv.a[0][0] + 9, &map->world_to_map[0][0]);
      }
      sky.map = std::move(map);
    } else {
      for (const char* key : {"mapping", "transform"})
        if (v.contains(key)) fail("{}: \"{}\" needs an \"image\"", ptr, key);
    }
    m_scene.sky = sky;
  }

  fs::path m_base;
  Scene& m_scene;
  ReadPolicy m_policy;
  std::map<std::string, uint32_t> m_named;
  std::map<std::pair<fs::path, bool>, int> m_textures;  // (file, sRGB) -> Scene::textures
  std::optional<uint32_t> m_default_material;
};

// nlohmann keeps the last of two equal keys silently; this parser callback makes it an error,
// tracking the JSON pointer of the object being parsed.
class DuplicateKeyCheck {
 public:
  bool operator()(int, json::parse_event_t event, json& parsed) {
    switch (event) {
      case json::parse_event_t::object_start:
      case json::parse_event_t::array_start:
        m_stack.push_back({event == json::parse_event_t::array_start, 0, {}, {}});
        break;
      case json::parse_event_t::key: {
        Frame& f = m_stack.back();
        f.key = parsed.get<std::string>();
        if (!f.keys.insert(f.key).second)
          fail("duplicate field \"{}\" in {}", printable(f.key), where(pointer()));
        break;
      }
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        m_stack.pop_back();
        if (!m_stack.empty() && m_stack.back().array) ++m_stack.back().index;
        break;
      case json::parse_event_t::value:
        if (!m_stack.empty() && m_stack.back().array) ++m_stack.back().index;
        break;
    }
    return true;
  }

 private:
  struct Frame {
    bool array;
    size_t index;
    std::string key;
    std::set<std::string> keys;
  };
  // Pointer of the innermost object (without its current key).
  std::string pointer() const {
    std::string p;
    for (size_t i = 1; i < m_stack.size(); ++i) {
      const Frame& parent = m_stack[i - 1];
      p = parent.array ? child(p, parent.index) : child(p, parent.key);
    }
    return p;
  }
  std::vector<Frame> m_stack;
};

}  // namespace

void load_json_scene(const fs::path& path, Scene& scene) {
  const std::string file = path.string();
  if (!fs::exists(path)) fail("{}: file not found", file);
  parse_json_scene(read_text_file(path), file, path.parent_path(), scene);
}

void parse_json_scene(std::string_view text, const std::string& file, const fs::path& base_dir,
                      Scene& scene, const ReadPolicy& policy) {
  json root;
  try {
    root = json::parse(text, DuplicateKeyCheck(), true, /*ignore_comments=*/true);
  } catch (const json::parse_error& e) {
    // e.byte counts from 1 and points one past the character that failed.
    size_t at = std::min(text.size(), e.byte > 0 ? size_t(e.byte - 1) : size_t(0));
    size_t line = 1 + size_t(std::count(text.begin(), text.begin() + long(at), '\n'));
    size_t newline = at == 0 ? std::string::npos : text.rfind('\n', at - 1);
    size_t column = at - (newline == std::string::npos ? 0 : newline + 1) + 1;
    std::string what = e.what();
    // nlohmann's message starts "[json.exception.parse_error.101] parse error at ...: ".
    if (size_t k = what.find("]"); k != std::string::npos) {
      size_t c = what.find(": ", k);
      if (c != std::string::npos) what = what.substr(c + 2);
    }
    fail("{}:{}:{}: invalid JSON: {}", file, line, column, what);
  } catch (const json::exception& e) {
    // A number too large for a double: nlohmann gives no position for it.
    std::string what = e.what();
    if (size_t k = what.find("] "); k != std::string::npos) what = what.substr(k + 2);
    fail("{}: invalid JSON: {}", file, what);
  } catch (const Error& e) {
    fail("{}: {}", file, e.what());
  }
  try {
    JsonSceneReader(base_dir, scene, policy).read(root);
  } catch (const Error& e) {
    fail("{}: {}", file, e.what());
  }
}

}  // namespace rll
