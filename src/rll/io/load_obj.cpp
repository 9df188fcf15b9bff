// Wavefront OBJ + MTL reader. tinyobjloader parses faces, polygons, groups and materials; a
// validating scan of the text before it gives errors with line numbers (tinyobjloader reads
// "nan", "inf" or "abc" as 0 and reports bad indices only at the end of the file) and the
// vertex data, correctly rounded, so that a saved scene reads back bit for bit.
#include <tiny_obj_loader.h>

#include <cmath>
#include <map>
#include <set>
#include <sstream>
#include <streambuf>

#include "rll/core/error.h"
#include "rll/io/load.h"
#include "rll/io/text_scan.h"

namespace rll {
namespace fs = std::filesystem;

namespace {

// What the validating scan of an MTL file notes beside tinyobjloader's reading of it, by
// material name.
struct MtlNotes {
  std::set<std::string> with_kd, with_ke;     // materials with a Kd, a Ke statement
  std::map<std::string, size_t> map_ke_line;  // the line of each material's map_Ke
};

// All MTL files an OBJ names, parsed by tinyobjloader into one list.
struct MtlLibrary {
  std::vector<tinyobj::material_t> materials;
  std::map<std::string, int> by_name;
  std::vector<fs::path> source;  // the MTL file of each material
  std::vector<bool> has_kd;      // whether the material has a Kd statement
  std::vector<bool> has_ke;      // whether the material has a Ke statement
  std::vector<size_t> map_ke_line;  // the line of its map_Ke (0: none)
  std::vector<fs::path> files;   // loaded files, each once
  // Texture statements rll does not read (map_Bump, map_d, ...), each with its first file and
  // line: one warning lists them.
  std::map<std::string, std::string> ignored_maps;
};

// Vertex data read by the scan, in file order (the order tinyobjloader's indices refer to).
struct ObjVertices {
  std::vector<Vec3> positions, normals;
  std::vector<Vec2> uvs;
};

[[noreturn]] void fail_line(const std::string& file, size_t line, const std::string& what) {
  fail("{}:{}: {}", file, line, what);
}

// Reads up to `max` numbers from `rest` into `out`; fails naming the line on any token that is
// not a finite number. Returns how many were read.
int read_numbers(std::string_view rest, float* out, int max, const std::string& file, size_t line,
                 std::string_view what) {
  int n = 0;
  std::string_view tok;
  while (next_token(rest, tok)) {
    if (tok[0] == '#') break;  // a comment after the values
    float v = 0;
    switch (parse_float(tok, v)) {
      case NumberStatus::Ok:
        break;
      case NumberStatus::NonFinite:
        fail_line(file, line, fmt::format("{} '{}' is not a finite number", what, printable(tok)));
      case NumberStatus::Malformed:
        fail_line(file, line, fmt::format("{} '{}' is not a number", what, printable(tok)));
    }
    if (n >= max)
      fail_line(file, line, fmt::format("too many values for {} (at most {})", what, max));
    out[n++] = v;
  }
  return n;
}

// Validates an MTL file's numeric statements and returns its text with one-value colours
// ("Kd 0.5") spelt out as three, which the MTL format allows and tinyobjloader does not read.
// Notes the materials that have a Kd (tinyobjloader makes a missing one 0.6 when there is a
// map_Kd, 0 otherwise) or a Ke, where each map_Ke is, and the texture statements rll ignores.
std::string normalize_mtl(std::string_view text, const std::string& file, MtlNotes& notes,
                          std::map<std::string, std::string>& ignored_maps) {
  static const char* kColours[] = {"Ka", "Kd", "Ks", "Ke", "Tf"};
  static const char* kScalars[] = {"Ns", "Ni", "d",   "Tr",    "Pr",    "Pm",
                                   "Ps", "Pc", "Pcr", "aniso", "anisor"};
  std::string out;
  out.reserve(text.size() + 64);
  TextLines lines(text);
  std::string_view line;
  std::string material;
  while (lines.next(line)) {
    std::string_view rest = line, kw;
    std::string rewritten;
    if (next_token(rest, kw)) {
      if (kw == "newmtl") {
        // tinyobjloader names the material by the rest of the line after one separator.
        size_t at = line.find("newmtl") + 7;
        material = at <= line.size() ? std::string(line.substr(at)) : std::string();
      }
      if (kw == "Kd") notes.with_kd.insert(material);
      if (kw == "Ke") notes.with_ke.insert(material);
      if (kw == "map_Ke") notes.map_ke_line[material] = lines.number();
      // Texture statements other than map_Kd and map_Ke (bump, opacity, specular maps...):
      // tinyobjloader reads them, rll renders without them.
      const bool texture_statement = kw.substr(0, 4) == "map_" || kw == "bump" || kw == "disp" ||
                                     kw == "decal" || kw == "refl" || kw == "norm";
      if (texture_statement && kw != "map_Kd" && kw != "map_Ke")
        ignored_maps.emplace(std::string(kw), fmt::format("{}:{}", file, lines.number()));
      bool colour = std::find(std::begin(kColours), std::end(kColours), kw) != std::end(kColours);
      bool scalar = std::find(std::begin(kScalars), std::end(kScalars), kw) != std::end(kScalars);
      if (colour) {
        std::string_view probe = rest, first;
        if (next_token(probe, first) && (first == "spectral" || first == "xyz"))
          fail_line(file, lines.number(),
                    fmt::format("'{} {}' colours are not supported (use r g b)", kw, first));
        float v[3];
        int n = read_numbers(rest, v, 3, file, lines.number(), kw);
        if (n != 1 && n != 3)
          fail_line(file, lines.number(), fmt::format("{} needs 3 values (r g b) or 1", kw));
        for (int i = 0; i < n; ++i)
          if (v[i] < 0) fail_line(file, lines.number(), fmt::format("{} must not be negative", kw));
        if (n == 1) rewritten = fmt::format("{} {} {} {}", kw, v[0], v[0], v[0]);
      } else if (scalar) {
        float v;
        if (read_numbers(rest, &v, 1, file, lines.number(), kw) != 1)
          fail_line(file, lines.number(), fmt::format("{} needs one value", kw));
        if (kw == "Ns" && v < 0) fail_line(file, lines.number(), "Ns must not be negative");
        // The MTL format: an optical density (Ni) from 0.001 to 10, a dissolve (d) and its
        // complement (Tr) from 0 to 1. Ni in (0, 1] is a relative index rll replaces by 1.5.
        if (kw == "Ni" && !(v > 0))
          fail_line(file, lines.number(),
                    fmt::format("Ni (an index of refraction) must be positive (got {})", v));
        if ((kw == "d" || kw == "Tr") && !(v >= 0 && v <= 1))
          fail_line(file, lines.number(), fmt::format("{} must be in [0, 1] (got {})", kw, v));
      } else if (kw == "illum") {
        std::string_view tok;
        long v;
        if (!next_token(rest, tok) || !parse_long(tok, v))
          fail_line(file, lines.number(), "illum needs an integer");
      }
    }
    if (rewritten.empty())
      out.append(line);
    else
      out += rewritten;
    out += '\n';
  }
  return out;
}

void load_mtl(const fs::path& mtl, const std::string& obj_file, size_t obj_line,
              const std::string& name, MtlLibrary& lib, const ReadPolicy& policy) {
  if (std::find(lib.files.begin(), lib.files.end(), mtl) != lib.files.end()) return;
  std::string bytes;
  if (auto it = policy.memory_files.find(name); it != policy.memory_files.end()) {
    bytes = it->second;
  } else {
    if (!policy.read_files)
      fail_line(
          obj_file, obj_line,
          fmt::format("material library '{}': reading other files is turned off", printable(name)));
    if (const std::string why = unreadable_reason(mtl); !why.empty())
      fail_line(obj_file, obj_line,
                fmt::format("material library '{}' {} ({})", printable(name), why,
                            printable(mtl.string(), 256)));
    bytes = read_text_file(mtl);
  }
  MtlNotes notes;
  std::string text = normalize_mtl(bytes, mtl.string(), notes, lib.ignored_maps);
  std::istringstream in(text);
  std::string warn, err;
  const size_t first = lib.materials.size();
  tinyobj::LoadMtl(&lib.by_name, &lib.materials, &in, &warn, &err);
  if (!err.empty()) fail("{}: {}", mtl.string(), err);
  lib.source.resize(lib.materials.size(), mtl);
  for (size_t i = first; i < lib.materials.size(); ++i) {
    const std::string& name = lib.materials[i].name;
    lib.has_kd.push_back(notes.with_kd.count(name) > 0);
    lib.has_ke.push_back(notes.with_ke.count(name) > 0);
    const auto line = notes.map_ke_line.find(name);
    lib.map_ke_line.push_back(line == notes.map_ke_line.end() ? 0 : line->second);
  }
  lib.files.push_back(mtl);
}

// Highest 1-based index a face used, and where: positive indices may refer to vertices defined
// later in the file, so they are checked against the final counts.
struct IndexUse {
  long max = 0;
  size_t line = 0;
};

// Checks one face index: 0 is never valid, a negative one counts back from the vertices read so
// far, a positive one is checked at the end.
void check_index(long idx, size_t count, IndexUse& use, const std::string& file, size_t line,
                 const char* what) {
  if (idx == 0) fail_line(file, line, fmt::format("{} index 0 (OBJ indices start at 1)", what));
  if (idx < 0) {
    if (size_t(-idx) > count)
      fail_line(file, line,
                fmt::format("{} index {} reaches before the first {} ({} so far)", what, idx, what,
                            count));
  } else if (idx > use.max) {
    use.max = idx;
    use.line = line;
  }
}

// The validating scan: vertices, normals and uvs into `v`, face indices and material names
// checked, the MTL files read into `lib`.
void scan_obj(std::string_view text, const std::string& file, const fs::path& base_dir,
              ObjVertices& v, MtlLibrary& lib, const ReadPolicy& policy) {
  IndexUse use_v, use_vt, use_vn;
  TextLines lines(text);
  std::string_view line;
  while (lines.next(line)) {
    std::string_view rest = line, kw;
    if (!next_token(rest, kw) || kw[0] == '#') continue;
    const size_t ln = lines.number();
    if (kw == "v") {
      float c[7];  // x y z, then w or r g b
      if (read_numbers(rest, c, 7, file, ln, "vertex coordinate") < 3)
        fail_line(file, ln, "a vertex needs 3 coordinates");
      v.positions.push_back({c[0], c[1], c[2]});
    } else if (kw == "vn") {
      float c[3];
      if (read_numbers(rest, c, 3, file, ln, "normal coordinate") != 3)
        fail_line(file, ln, "a normal needs 3 coordinates");
      v.normals.push_back({c[0], c[1], c[2]});
    } else if (kw == "vt") {
      float c[3] = {0, 0, 0};
      if (read_numbers(rest, c, 3, file, ln, "texture coordinate") < 1)
        fail_line(file, ln, "a texture coordinate needs at least 1 value");
      v.uvs.push_back({c[0], c[1]});
    } else if (kw == "f") {
      std::string_view tok;
      int corners = 0;
      while (next_token(rest, tok)) {
        ++corners;
        std::string_view parts[3];
        int np = 0;
        for (size_t b = 0;; ++np) {
          size_t e = tok.find('/', b);
          if (np == 3)
            fail_line(file, ln, fmt::format("malformed face vertex '{}'", printable(tok)));
          parts[np] = tok.substr(b, e == std::string_view::npos ? std::string_view::npos : e - b);
          if (e == std::string_view::npos) {
            ++np;
            break;
          }
          b = e + 1;
        }
        long idx;
        if (!parse_long(parts[0], idx))
          fail_line(file, ln, fmt::format("malformed face vertex '{}'", printable(tok)));
        check_index(idx, v.positions.size(), use_v, file, ln, "vertex");
        // "3/" (a slash and nothing after it): tinyobjloader reads the next vertex's number,
        // across the space, as its texture coordinate.
        if (np == 2 && parts[1].empty())
          fail_line(file, ln, fmt::format("malformed face vertex '{}'", printable(tok)));
        if (np >= 2 && !parts[1].empty()) {
          if (!parse_long(parts[1], idx))
            fail_line(file, ln, fmt::format("malformed face vertex '{}'", printable(tok)));
          check_index(idx, v.uvs.size(), use_vt, file, ln, "texture coordinate");
        }
        if (np == 3) {
          if (!parse_long(parts[2], idx))
            fail_line(file, ln, fmt::format("malformed face vertex '{}'", printable(tok)));
          check_index(idx, v.normals.size(), use_vn, file, ln, "normal");
        }
      }
      if (corners < 3)
        fail_line(file, ln, fmt::format("a face needs at least 3 vertices (got {})", corners));
      if (corners > 255)
        fail_line(file, ln, fmt::format("a face with {} vertices (at most 255)", corners));
    } else if (kw == "mtllib") {
      // Names separated by spaces; a backslash escapes a space inside one (as tinyobjloader reads
      // them).
      std::string name;
      auto flush = [&] {
        if (!name.empty()) load_mtl(base_dir / name, file, ln, name, lib, policy);
        name.clear();
      };
      std::string_view names = rest;
      while (!names.empty() && (names[0] == ' ' || names[0] == '\t')) names.remove_prefix(1);
      for (size_t i = 0; i < names.size(); ++i) {
        if (names[i] == '\\' && i + 1 < names.size() && names[i + 1] == ' ')
          name += names[++i];
        else if (names[i] == ' ' || names[i] == '\t')
          flush();
        else
          name += names[i];
      }
      flush();
    } else if (kw == "usemtl") {
      std::string_view name;
      if (!next_token(rest, name)) fail_line(file, ln, "usemtl needs a material name");
      if (!lib.by_name.count(std::string(name))) {
        std::string libs;
        for (const auto& f : lib.files) libs += (libs.empty() ? "" : ", ") + f.filename().string();
        fail_line(file, ln,
                  libs.empty()
                      ? fmt::format("usemtl '{}' but no mtllib was read before it", printable(name))
                      : fmt::format("usemtl '{}': no such material in {}", printable(name), libs));
      }
    }
  }
  auto check_max = [&](const IndexUse& use, size_t count, const char* what) {
    if (size_t(use.max) > count)
      fail_line(file, use.line,
                fmt::format("{} index {} is out of range (the file has {})", what, use.max, count));
  };
  check_max(use_v, v.positions.size(), "vertex");
  check_max(use_vt, v.uvs.size(), "texture coordinate");
  check_max(use_vn, v.normals.size(), "normal");
}

// Hands tinyobjloader the MTL files the scan already read, all of them at the first mtllib.
class PreloadedMaterials : public tinyobj::MaterialReader {
 public:
  explicit PreloadedMaterials(const MtlLibrary& lib) : m_lib(lib) {}
  bool operator()(const std::string&, std::vector<tinyobj::material_t>* materials,
                  std::map<std::string, int>* by_name, std::string*, std::string*) override {
    if (!m_done) {
      *materials = m_lib.materials;
      *by_name = m_lib.by_name;
      m_done = true;
    }
    return true;
  }

 private:
  const MtlLibrary& m_lib;
  bool m_done = false;
};

// Lets tinyobjloader read the text already in memory without a copy.
struct ViewBuffer : std::streambuf {
  explicit ViewBuffer(const std::string& s) {
    char* p = const_cast<char*>(s.data());
    setg(p, p, p + s.size());
  }
};

Rgb rgb(const tinyobj::real_t* c) {
  return Rgb(float(c[0]), float(c[1]), float(c[2]));
}

// What an MTL material says beside tinyobjloader's reading of it.
struct MtlMaterialNotes {
  bool has_kd = false, has_ke = false;
  size_t map_ke_line = 0;  // 0: no map_Ke
};

// The MTL -> Material mapping documented in docs/scene-format.md. `has_uvs`: whether the OBJ has
// texture coordinates, which an emission texture needs.
Material convert_material(const tinyobj::material_t& t, const MtlMaterialNotes& notes,
                          const fs::path& mtl, Scene& scene, std::map<fs::path, int>& textures,
                          const ReadPolicy& policy, bool has_uvs) {
  Material m;
  m.name = t.name;
  Rgb kd = notes.has_kd ? rgb(t.diffuse) : Rgb(0), ks = rgb(t.specular);
  m.emission = rgb(t.emission);
  // A texture of the material (map_Kd, map_Ke), read once per file as sRGB.
  auto texture = [&](const std::string& texname) {
    fs::path tex = mtl.parent_path() / texname;
    if (!fs::exists(tex) && texname.find('\\') != std::string::npos) {
      std::string unix_name = texname;
      std::replace(unix_name.begin(), unix_name.end(), '\\', '/');
      tex = mtl.parent_path() / unix_name;
    }
    tex = tex.lexically_normal();
    auto it = textures.find(tex);
    if (it == textures.end()) {
      if (!policy.read_files)
        fail("{}: material '{}': texture '{}': reading other files is turned off", mtl.string(),
             printable(t.name), printable(texname));
      if (const std::string why = unreadable_reason(tex); !why.empty())
        fail("{}: material '{}': texture '{}' {} ({})", mtl.string(), printable(t.name),
             printable(texname), why, printable(tex.string(), 256));
      try {
        scene.textures.push_back(read_image(tex));
      } catch (const Error& e) {
        fail("{}: material '{}': {}", mtl.string(), t.name, e.what());
      }
      it = textures.emplace(tex, int(scene.textures.size() - 1)).first;
    }
    return it->second;
  };
  if (!t.diffuse_texname.empty()) {
    m.albedo_texture = texture(t.diffuse_texname);
    if (is_black(kd))
      kd = Rgb(1);  // the texture multiplies Kd; a missing or black Kd must not hide it
  }
  if (!t.emissive_texname.empty()) {
    // map_Ke multiplies Ke as map_Kd multiplies Kd: an absent Ke counts as 1, a black one
    // leaves the material dark (said, since the file names a texture it then does not show).
    const std::string at = fmt::format("{}:{}", mtl.string(), notes.map_ke_line);
    const int tex = texture(t.emissive_texname);
    if (!notes.has_ke) m.emission = Rgb(1);
    if (is_black(m.emission)) {
      scene.warnings.push_back(fmt::format(
          "{}: material '{}': map_Ke '{}' has no effect: its Ke is 0 and the texture multiplies "
          "it (give Ke 1 1 1 for the texture's own colours)",
          at, printable(t.name), printable(t.emissive_texname)));
    } else if (!has_uvs) {
      // Without texture coordinates, the emission cannot vary over the surface: the texture's
      // mean colour stands for it, as for a glTF primitive without TEXCOORD_0.
      const Image& img = scene.textures[size_t(tex)];
      Rgb mean(0);
      for (const Rgb& c : img.pixels()) mean += c;
      m.emission = m.emission * (mean / float(std::max<size_t>(1, img.pixel_count())));
      scene.warnings.push_back(fmt::format(
          "{}: material '{}': map_Ke '{}': the OBJ has no texture coordinates (vt), so the "
          "material emits Ke times the texture's mean colour",
          at, printable(t.name), printable(t.emissive_texname)));
    } else {
      m.emission_texture = tex;
    }
  }
  float alpha = std::sqrt(2.0f / (float(t.shininess) + 2.0f));
  if (t.illum == 3 || (is_black(kd) && !is_black(ks))) {
    m.type = MaterialType::Conductor;
    m.specular = ks;
    m.eta = kTintableEta;
    m.k = kTintableK;
    m.roughness = alpha;
  } else if (!is_black(ks)) {
    m.type = MaterialType::Plastic;
    m.albedo = kd;
    m.specular = ks;
    m.roughness = alpha;
    m.ior = t.ior > 1 ? float(t.ior) : 1.5f;
  } else {
    m.albedo = kd;
  }
  return m;
}

// OBJ indexes positions, normals and uvs separately; the mesh has one index per vertex. Each
// distinct (position, normal, uv) triple becomes one vertex, found through a short chain of the
// variants of its position (almost always one or two), so no hashing is needed. Vertices are
// numbered in the file's order of positions (variants of one position in order of first use),
// so that a file written from a mesh reads back with the same numbering. Local material ids:
// the MTL materials in order, `default_material` for faces without usemtl.
// The scan checked the indices as rll reads them; the mesh is built from tinyobjloader's, which
// read some face vertices differently (a fuzzed file made it index a texture coordinate past the
// last), so each is checked again against the arrays it indexes before it is used.
Mesh build_mesh(const ObjVertices& v, const std::vector<tinyobj::shape_t>& shapes,
                uint32_t default_material, bool& uses_default, const std::string& file) {
  std::vector<int32_t> first_variant(v.positions.size(), -1), next_variant;
  std::vector<uint32_t> variant_count(v.positions.size(), 0), variant_rank;
  std::vector<int32_t> variant_position;
  std::vector<std::array<int32_t, 2>> variant_key;  // (normal, uv)
  auto variant = [&](const tinyobj::index_t& idx) {
    auto outside = [](int i, size_t count, int lowest) {
      return i < lowest || (i >= 0 && size_t(i) >= count);
    };
    if (outside(idx.vertex_index, v.positions.size(), 0) ||
        outside(idx.texcoord_index, v.uvs.size(), -1) ||
        outside(idx.normal_index, v.normals.size(), -1))
      fail(
          "{}: tinyobjloader reads a face vertex as position {}, texture coordinate {}, normal {} "
          "(counted from 1; 0 for none), beyond the {} positions, {} texture coordinates and {} "
          "normals of the file: a malformed face vertex",
          file, idx.vertex_index + 1, idx.texcoord_index + 1, idx.normal_index + 1,
          v.positions.size(), v.uvs.size(), v.normals.size());
    const size_t p = size_t(idx.vertex_index);
    int32_t k = first_variant[p];
    for (; k >= 0; k = next_variant[size_t(k)])
      if (variant_key[size_t(k)][0] == idx.normal_index &&
          variant_key[size_t(k)][1] == idx.texcoord_index)
        return uint32_t(k);
    k = int32_t(variant_key.size());
    variant_key.push_back({idx.normal_index, idx.texcoord_index});
    variant_position.push_back(int32_t(p));
    variant_rank.push_back(variant_count[p]++);
    next_variant.push_back(first_variant[p]);
    first_variant[p] = k;
    return uint32_t(k);
  };

  Mesh mesh;
  size_t triangle_total = 0;
  for (const auto& s : shapes) triangle_total += s.mesh.num_face_vertices.size();
  mesh.triangles.reserve(triangle_total);
  mesh.material.reserve(triangle_total);
  for (const auto& s : shapes) {
    size_t offset = 0;
    for (size_t f = 0; f < s.mesh.num_face_vertices.size(); ++f) {
      const size_t n = s.mesh.num_face_vertices[f];
      if (n == 3) {  // always, since tinyobjloader triangulates
        const auto* idx = &s.mesh.indices[offset];
        mesh.triangles.push_back({variant(idx[0]), variant(idx[1]), variant(idx[2])});
        int mat = s.mesh.material_ids[f];
        if (mat < 0) uses_default = true;
        mesh.material.push_back(mat < 0 ? default_material : uint32_t(mat));
      }
      offset += n;
    }
  }

  // Final vertex id = (variants of all earlier positions) + rank among its position's variants.
  std::vector<uint32_t> start(v.positions.size() + 1, 0);
  for (size_t p = 0; p < v.positions.size(); ++p) start[p + 1] = start[p] + variant_count[p];
  const size_t nv = variant_key.size();
  std::vector<uint32_t> final_id(nv);
  mesh.positions.resize(nv);
  if (!v.normals.empty()) mesh.normals.resize(nv);
  if (!v.uvs.empty()) mesh.uvs.resize(nv);
  for (size_t k = 0; k < nv; ++k) {
    const uint32_t id = start[size_t(variant_position[k])] + variant_rank[k];
    final_id[k] = id;
    mesh.positions[id] = v.positions[size_t(variant_position[k])];
    const auto [n, t] = variant_key[k];
    if (!v.normals.empty()) mesh.normals[id] = n >= 0 ? v.normals[size_t(n)] : Vec3(0);
    if (!v.uvs.empty()) mesh.uvs[id] = t >= 0 ? v.uvs[size_t(t)] : Vec2{};
  }
  for (auto& tri : mesh.triangles)
    for (auto& i : tri) i = final_id[i];
  return mesh;
}

}  // namespace

void load_obj(const fs::path& path, Scene& scene) {
  const std::string file = path.string();
  if (!fs::exists(path)) fail("{}: file not found", file);
  parse_obj(read_text_file(path), file, path.parent_path(), scene);
}

void parse_obj(std::string_view text_view, const std::string& file, const fs::path& base_dir,
               Scene& scene, const ReadPolicy& policy) {
  const std::string text(text_view);  // tinyobjloader reads it through a stream
  ObjVertices v;
  MtlLibrary lib;
  scan_obj(text, file, base_dir, v, lib, policy);

  tinyobj::attrib_t attrib;
  std::vector<tinyobj::shape_t> shapes;
  std::vector<tinyobj::material_t> materials;
  std::string warn, err;
  ViewBuffer buffer(text);
  std::istream in(&buffer);
  PreloadedMaterials reader(lib);
  bool ok = tinyobj::LoadObj(&attrib, &shapes, &materials, &warn, &err, &in, &reader, true, false);
  if (!ok || !err.empty()) {
    while (!err.empty() && err.back() == '\n') err.pop_back();
    fail("{}: {}", file, err.empty() ? "cannot parse the file" : err);
  }
  if (attrib.vertices.size() != 3 * v.positions.size() ||
      attrib.normals.size() != 3 * v.normals.size() || attrib.texcoords.size() != 2 * v.uvs.size())
    fail("{}: tinyobjloader read {} vertices where rll counted {}", file,
         attrib.vertices.size() / 3, v.positions.size());

  const uint32_t default_material = uint32_t(lib.materials.size());
  bool uses_default = false;
  Mesh mesh = build_mesh(v, shapes, default_material, uses_default, file);
  mesh.light.assign(mesh.triangles.size(), -1);
  if (mesh.triangles.empty()) fail("{}: the file has no faces", file);
  if (const std::string why = triangle_budget_problem(
          double(scene.mesh.triangle_count() + mesh.triangles.size()), policy);
      !why.empty())
    fail("{}: {}", file, why);

  const uint32_t material_offset = uint32_t(scene.materials.size());
  std::map<fs::path, int> textures;
  for (size_t i = 0; i < lib.materials.size(); ++i)
    scene.materials.push_back(
        convert_material(lib.materials[i], {lib.has_kd[i], lib.has_ke[i], lib.map_ke_line[i]},
                         lib.source[i], scene, textures, policy, !v.uvs.empty()));
  if (!lib.ignored_maps.empty()) {
    std::string list;
    for (const auto& [statement, at] : lib.ignored_maps)
      list += fmt::format("{}{} ({})", list.empty() ? "" : ", ", printable(statement), at);
    scene.warnings.push_back(fmt::format(
        "{}: texture statements rll does not read are ignored: {} (rll reads map_Kd and map_Ke)",
        file, list));
  }
  if (uses_default) {
    Material m;
    m.name = "default";
    scene.materials.push_back(m);
  }
  scene.mesh.append(mesh, material_offset);
}

}  // namespace rll
