// glTF 2.0 scenes (.gltf, .glb) through tinygltf: meshes under their node transforms,
// metallic-roughness materials mapped to rll's (docs/scene-format.md), base-colour and emissive
// textures, KHR_materials_emissive_strength, KHR_materials_clearcoat, KHR_lights_punctual point, spot
// and directional lights, and the first camera. tinygltf parses the JSON and the buffers; every
// index, count and byte range it leaves unchecked is checked here before it is read.
#include <tiny_gltf.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "rll/core/error.h"
#include "rll/core/memory_budget.h"
#include "rll/core/paths.h"
#include "rll/io/load.h"
#include "rll/io/text_scan.h"
#include "rll/scene/interaction.h"
#include "rll/scene/transform.h"

namespace rll {
namespace fs = std::filesystem;

namespace {

// Extensions whose meaning rll renders (or, for KHR_mesh_quantization, reads).
const std::set<std::string> kSupportedExtensions = {
    "KHR_lights_punctual",        "KHR_materials_emissive_strength",
    "KHR_materials_specular",     "KHR_materials_ior",
    "KHR_materials_transmission", "KHR_materials_volume",
    "KHR_materials_clearcoat",    "KHR_mesh_quantization"};

// tinygltf decodes images with stb_image into 8-bit RGBA, without the sRGB decoding rll needs;
// this keeps the encoded bytes of images given by URI, which rll decodes when a material uses
// them. Images in a buffer view are read by rll itself, which checks the view's range first.
bool keep_image_bytes(tinygltf::Image* image, const int, std::string*, std::string*, int, int,
                      const unsigned char* bytes, int size, void*) {
  if (image->bufferView < 0 && bytes && size > 0) image->image.assign(bytes, bytes + size);
  image->width = image->height = -1;
  return true;
}

// File access refused (the fuzz targets, which must not read files).
bool no_file_exists(const std::string&, void*) {
  return false;
}
std::string same_path(const std::string& p, void*) {
  return p;
}
bool no_file_read(std::vector<unsigned char>*, std::string* err, const std::string& p, void*) {
  if (err) *err += "reading '" + p + "' is turned off\n";
  return false;
}
bool no_file_write(std::string*, const std::string&, const std::vector<unsigned char>&, void*) {
  return false;
}

// tinygltf's own file reader takes the size of whatever it opens: a URI naming a folder ("."
// or "images/") reads as a file of 2^63 bytes and ends in std::bad_alloc. This one reads regular
// files only, within the memory budget, and keeps why a file could not be read (by its path)
// for the message of the image or buffer that named it.
struct FileReads {
  std::map<std::string, std::string> failures;  // path -> why it could not be read
};
bool checked_file_read(std::vector<unsigned char>* out, std::string* err, const std::string& p,
                       void* user) {
  auto& reads = *static_cast<FileReads*>(user);
  auto refuse = [&](const std::string& why) {
    reads.failures[p] = why;
    if (err) *err += why + "\n";
    return false;
  };
  if (const std::string why = unreadable_reason(p); !why.empty())
    return refuse(fmt::format("'{}' {}", printable(p, 256), why));
  std::error_code ec;
  const uintmax_t size = fs::file_size(p, ec);
  if (ec) return refuse(fmt::format("'{}': {}", printable(p, 256), ec.message()));
  if (!(double(size) <= double(memory_budget_bytes())))
    return refuse(fmt::format("'{}' has {}, more than {}", printable(p, 256),
                              format_bytes(double(size)), memory_budget_phrase()));
  std::ifstream f(p, std::ios::binary);
  out->resize(size_t(size));
  if (!f || !f.read(reinterpret_cast<char*>(out->data()), std::streamsize(size)))
    return refuse(fmt::format("'{}': read error", printable(p, 256)));
  return true;
}

std::string one_line(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  for (auto& c : s)
    if (c == '\n') c = ';';
  return s;
}

// The JSON text of a .gltf, or of a .glb's first chunk ("" when there is none).
std::string_view gltf_json_text(std::string_view bytes, bool binary) {
  if (!binary) return bytes;
  if (bytes.size() < 20) return {};
  uint32_t length = 0;
  std::memcpy(&length, bytes.data() + 12, 4);
  return bytes.substr(20, length);
}

// tinygltf names a buffer whose data URI does not decode to its byteLength by the whole URI,
// which can be megabytes of base64: each such line becomes the buffer's sizes and the URI's
// beginning, escaped.
std::string shorten_uri_errors(const std::string& err, std::string_view json_text) {
  static constexpr std::string_view kHead = "Failed to decode 'uri' : ", kTail = " in Buffer";
  nlohmann::json doc = nlohmann::json::parse(json_text, nullptr, false);
  std::string out;
  size_t pos = 0;
  while (pos < err.size()) {
    size_t end = err.find('\n', pos);
    if (end == std::string::npos) end = err.size();
    std::string_view line(err.data() + pos, end - pos);
    pos = end + 1;
    if (line.substr(0, kHead.size()) != kHead || line.size() < kHead.size() + kTail.size() ||
        line.substr(line.size() - kTail.size()) != kTail) {
      out.append(line);
      out += '\n';
      continue;
    }
    const std::string_view uri =
        line.substr(kHead.size(), line.size() - kHead.size() - kTail.size());
    // Base64 decodes to 3 bytes per 4 characters, less one per '=' of padding.
    const size_t comma = uri.find(',');
    std::string decoded = "cannot be decoded";
    if (comma != std::string_view::npos &&
        uri.substr(0, comma).find(";base64") != std::string_view::npos) {
      std::string_view payload = uri.substr(comma + 1);
      if (payload.size() % 4 == 0) {
        size_t pad = 0;
        while (pad < 2 && pad < payload.size() && payload[payload.size() - 1 - pad] == '=') ++pad;
        decoded = fmt::format("decodes to {} bytes", payload.size() / 4 * 3 - pad);
      } else {
        decoded = fmt::format("is not base64 ({} characters, not a multiple of 4)",
                              payload.size());
      }
    }
    std::string buffer = "a buffer";
    if (doc.is_object() && doc.contains("buffers") && doc["buffers"].is_array()) {
      const auto& buffers = doc["buffers"];
      for (size_t i = 0; i < buffers.size(); ++i)
        if (buffers[i].is_object() && buffers[i].contains("uri") && buffers[i]["uri"].is_string() &&
            buffers[i]["uri"].get_ref<const std::string&>() == uri) {
          buffer = fmt::format("buffer {}", i);
          if (buffers[i].contains("byteLength") && buffers[i]["byteLength"].is_number())
            buffer += fmt::format(" (byteLength {})", buffers[i]["byteLength"].dump());
          break;
        }
    }
    out += fmt::format("{}: its data URI '{}' ({} characters) {}", buffer, printable(uri, 40),
                       uri.size(), decoded);
    out += '\n';
  }
  return out;
}

// The JSON type each field rll reads must have. tinygltf keeps the default of a field of the
// wrong type ("roughnessFactor": "NaN" reads as 1) and rll's own reading of extensions did too:
// the document is checked against this table first, and a wrong type is an error naming it.
enum class JsonKind { Number, Numbers, Index, Bool, String };
struct TypedField {
  const char* array;  // a top-level array of objects, as a JSON pointer
  const char* field;  // within each of its objects, as a JSON pointer
  JsonKind kind;
};
constexpr TypedField kTypedFields[] = {
    {"/materials", "/pbrMetallicRoughness/baseColorFactor", JsonKind::Numbers},
    {"/materials", "/pbrMetallicRoughness/metallicFactor", JsonKind::Number},
    {"/materials", "/pbrMetallicRoughness/roughnessFactor", JsonKind::Number},
    {"/materials", "/emissiveFactor", JsonKind::Numbers},
    {"/materials", "/alphaMode", JsonKind::String},
    {"/materials", "/alphaCutoff", JsonKind::Number},
    {"/materials", "/doubleSided", JsonKind::Bool},
    {"/materials", "/extensions/KHR_materials_emissive_strength/emissiveStrength",
     JsonKind::Number},
    {"/materials", "/extensions/KHR_materials_ior/ior", JsonKind::Number},
    {"/materials", "/extensions/KHR_materials_transmission/transmissionFactor", JsonKind::Number},
    {"/materials", "/extensions/KHR_materials_volume/thicknessFactor", JsonKind::Number},
    {"/materials", "/extensions/KHR_materials_volume/attenuationDistance", JsonKind::Number},
    {"/materials", "/extensions/KHR_materials_volume/attenuationColor", JsonKind::Numbers},
    {"/materials", "/extensions/KHR_materials_clearcoat/clearcoatFactor", JsonKind::Number},
    {"/materials", "/extensions/KHR_materials_clearcoat/clearcoatRoughnessFactor",
     JsonKind::Number},
    {"/materials", "/extensions/KHR_materials_specular/specularFactor", JsonKind::Number},
    {"/materials", "/extensions/KHR_materials_specular/specularColorFactor", JsonKind::Numbers},
    {"/nodes", "/matrix", JsonKind::Numbers},
    {"/nodes", "/translation", JsonKind::Numbers},
    {"/nodes", "/rotation", JsonKind::Numbers},
    {"/nodes", "/scale", JsonKind::Numbers},
    {"/nodes", "/mesh", JsonKind::Index},
    {"/nodes", "/camera", JsonKind::Index},
    {"/cameras", "/perspective/yfov", JsonKind::Number},
    {"/cameras", "/perspective/aspectRatio", JsonKind::Number},
    {"/cameras", "/perspective/znear", JsonKind::Number},
    {"/cameras", "/perspective/zfar", JsonKind::Number},
    {"/extensions/KHR_lights_punctual/lights", "/color", JsonKind::Numbers},
    {"/extensions/KHR_lights_punctual/lights", "/intensity", JsonKind::Number},
    {"/extensions/KHR_lights_punctual/lights", "/range", JsonKind::Number},
    {"/extensions/KHR_lights_punctual/lights", "/spot/innerConeAngle", JsonKind::Number},
    {"/extensions/KHR_lights_punctual/lights", "/spot/outerConeAngle", JsonKind::Number},
    {"/accessors", "/count", JsonKind::Index},
    {"/accessors", "/byteOffset", JsonKind::Index},
    {"/accessors", "/bufferView", JsonKind::Index},
    {"/accessors", "/normalized", JsonKind::Bool},
    {"/bufferViews", "/buffer", JsonKind::Index},
    {"/bufferViews", "/byteOffset", JsonKind::Index},
    {"/bufferViews", "/byteLength", JsonKind::Index},
    {"/bufferViews", "/byteStride", JsonKind::Index},
    {"/buffers", "/byteLength", JsonKind::Index},
};

// "materials[0].pbrMetallicRoughness.roughnessFactor" for messages.
std::string field_path(const char* array, size_t index, const char* field) {
  std::string s = fmt::format("{}[{}]{}", array + 1, index, field);
  std::replace(s.begin(), s.end(), '/', '.');
  return s;
}

void check_field_types(std::string_view json_text, const std::string& name) {
  const nlohmann::json doc = nlohmann::json::parse(json_text, nullptr, false);
  if (!doc.is_object()) return;  // tinygltf says what is wrong with it
  for (const TypedField& f : kTypedFields) {
    const nlohmann::json::json_pointer array_ptr(f.array), field_ptr(f.field);
    if (!doc.contains(array_ptr) || !doc.at(array_ptr).is_array()) continue;
    const auto& array = doc.at(array_ptr);
    for (size_t i = 0; i < array.size(); ++i) {
      if (!array[i].is_object() || !array[i].contains(field_ptr)) continue;
      const auto& v = array[i].at(field_ptr);
      bool ok = false;
      const char* wanted = "";
      switch (f.kind) {
        case JsonKind::Number:
          ok = v.is_number(), wanted = "a number";
          break;
        case JsonKind::Numbers:
          ok = v.is_array() &&
               std::all_of(v.begin(), v.end(), [](const auto& x) { return x.is_number(); });
          wanted = "an array of numbers";
          break;
        case JsonKind::Index:
          ok = v.is_number_unsigned(), wanted = "a non-negative integer";
          break;
        case JsonKind::Bool:
          ok = v.is_boolean(), wanted = "true or false";
          break;
        case JsonKind::String:
          ok = v.is_string(), wanted = "a string";
          break;
      }
      if (!ok)
        fail("{}: {} must be {}, not {} {}", name, field_path(f.array, i, f.field), wanted,
             v.type_name(), printable(v.dump(), 40));
    }
  }
}

double number_or(const tinygltf::Value& obj, const char* key, double def) {
  if (!obj.IsObject() || !obj.Has(key)) return def;
  const tinygltf::Value& v = obj.Get(key);
  return v.IsNumber() ? v.GetNumberAsDouble() : def;
}

class GltfReader {
 public:
  // `failures`: the files tinygltf could not read (path -> why), for the messages of the images
  // that named them.
  GltfReader(const tinygltf::Model& model, const std::string& name, Scene& scene,
             const ReadPolicy& policy, const std::map<std::string, std::string>& failures = {})
      : m_model(model), m_name(name), m_scene(scene), m_policy(policy), m_failures(failures) {}

  void read() {
    for (const auto& e : m_model.extensionsRequired)
      if (!kSupportedExtensions.count(e))
        fail("{}: the file requires extension {}, which rll does not support", m_name, e);
    for (const auto& e : m_model.extensionsUsed)
      if (!kSupportedExtensions.count(e) && e != "KHR_texture_transform")
        warn(fmt::format("{}: extension {} is not supported; ignored", m_name, e));
    std::vector<int> roots;
    if (!m_model.scenes.empty()) {
      int s = m_model.defaultScene;
      if (s < 0) s = 0;
      if (size_t(s) >= m_model.scenes.size())
        fail("{}: the default scene {} does not exist ({} scenes)", m_name, s,
             m_model.scenes.size());
      roots = m_model.scenes[size_t(s)].nodes;
    } else {
      // No scenes: every node without a parent.
      std::vector<bool> child(m_model.nodes.size(), false);
      for (const auto& n : m_model.nodes)
        for (int c : n.children)
          if (c >= 0 && size_t(c) < child.size()) child[size_t(c)] = true;
      for (size_t i = 0; i < child.size(); ++i)
        if (!child[i]) roots.push_back(int(i));
    }
    m_visited.assign(m_model.nodes.size(), false);
    for (int r : roots) visit(r, Affine());
    if (m_scene.mesh.triangles.empty() && m_scene.lights.empty())
      fail("{}: the scene has no triangles and no lights", m_name);
  }

 private:
  void warn(const std::string& message) {
    if (m_warned.insert(message).second) m_scene.warnings.push_back(message);
  }

  const tinygltf::Node& node(int i) const {
    if (i < 0 || size_t(i) >= m_model.nodes.size())
      fail("{}: node {} does not exist ({} nodes)", m_name, i, m_model.nodes.size());
    return m_model.nodes[size_t(i)];
  }

  static Affine local_transform(const tinygltf::Node& n, const std::string& where) {
    Affine x;
    if (!n.matrix.empty()) {
      if (n.matrix.size() != 16) fail("{}: matrix needs 16 values", where);
      // Column-major.
      for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r) x.a[r][c] = to_float(n.matrix[size_t(c * 4 + r)]);
      x.t = Vec3(to_float(n.matrix[12]), to_float(n.matrix[13]), to_float(n.matrix[14]));
      return x;
    }
    if (!n.scale.empty()) {
      if (n.scale.size() != 3) fail("{}: scale needs 3 values", where);
      const float m[3][3] = {
          {to_float(n.scale[0]), 0, 0}, {0, to_float(n.scale[1]), 0}, {0, 0, to_float(n.scale[2])}};
      x.prepend(m);
    }
    if (!n.rotation.empty()) {
      if (n.rotation.size() != 4) fail("{}: rotation needs 4 values (a quaternion)", where);
      double qx = n.rotation[0], qy = n.rotation[1], qz = n.rotation[2], qw = n.rotation[3];
      const double len = std::sqrt(qx * qx + qy * qy + qz * qz + qw * qw);
      if (!(len > 0) || !std::isfinite(len)) fail("{}: rotation is not a unit quaternion", where);
      qx /= len, qy /= len, qz /= len, qw /= len;
      const float m[3][3] = {{float(1 - 2 * (qy * qy + qz * qz)), float(2 * (qx * qy - qz * qw)),
                              float(2 * (qx * qz + qy * qw))},
                             {float(2 * (qx * qy + qz * qw)), float(1 - 2 * (qx * qx + qz * qz)),
                              float(2 * (qy * qz - qx * qw))},
                             {float(2 * (qx * qz - qy * qw)), float(2 * (qy * qz + qx * qw)),
                              float(1 - 2 * (qx * qx + qy * qy))}};
      x.prepend(m);
    }
    if (!n.translation.empty()) {
      if (n.translation.size() != 3) fail("{}: translation needs 3 values", where);
      x.t = Vec3(to_float(n.translation[0]), to_float(n.translation[1]), to_float(n.translation[2]));
    }
    return x;
  }

  static Affine compose(const Affine& parent, const Affine& local) {
    Affine r = local;
    r.prepend(parent.a);
    r.t = parent.apply(local.t);
    return r;
  }

  void visit(int index, const Affine& parent) {
    const tinygltf::Node& n = node(index);
    const std::string where = fmt::format("{}: node {}", m_name, index);
    if (m_visited[size_t(index)])
      fail("{} is reached twice (the node hierarchy must be a tree)", where);
    m_visited[size_t(index)] = true;
    const Affine world = compose(parent, local_transform(n, where));
    for (int i = 0; i < 3; ++i)
      if (!is_finite(Vec3(world.a[i][0], world.a[i][1], world.a[i][2])) || !is_finite(world.t))
        fail("{}: the transform is not finite", where);
    if (n.mesh >= 0) add_mesh(n.mesh, world, where);
    if (n.camera >= 0) add_camera(n.camera, world, where);
    if (auto it = n.extensions.find("KHR_lights_punctual"); it != n.extensions.end())
      add_light(it->second, world, where);
    if (n.skin >= 0 || !n.weights.empty())
      warn(
          fmt::format("{}: skins and morph targets are not supported; the mesh is rendered in its "
                      "rest pose",
                      m_name));
    for (int c : n.children) visit(c, world);
  }

  // --- accessors ---

  static size_t component_size(int type) {
    switch (type) {
      case TINYGLTF_COMPONENT_TYPE_BYTE:
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
        return 1;
      case TINYGLTF_COMPONENT_TYPE_SHORT:
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
        return 2;
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
      case TINYGLTF_COMPONENT_TYPE_FLOAT:
        return 4;
      default:
        return 0;
    }
  }

  static int component_count(int type) {
    switch (type) {
      case TINYGLTF_TYPE_SCALAR:
        return 1;
      case TINYGLTF_TYPE_VEC2:
        return 2;
      case TINYGLTF_TYPE_VEC3:
        return 3;
      case TINYGLTF_TYPE_VEC4:
        return 4;
      default:
        return 0;
    }
  }

  // The byte range [begin, begin + size) of a buffer view, checked against its buffer.
  std::pair<const unsigned char*, size_t> view_bytes(int view, const std::string& what) const {
    if (view < 0 || size_t(view) >= m_model.bufferViews.size())
      fail("{}: buffer view {} does not exist ({} views)", what, view, m_model.bufferViews.size());
    const auto& bv = m_model.bufferViews[size_t(view)];
    if (bv.buffer < 0 || size_t(bv.buffer) >= m_model.buffers.size())
      fail("{}: buffer {} does not exist ({} buffers)", what, bv.buffer, m_model.buffers.size());
    const auto& buf = m_model.buffers[size_t(bv.buffer)];
    if (bv.byteOffset > buf.data.size() || bv.byteLength > buf.data.size() - bv.byteOffset)
      fail("{}: buffer view {} (bytes {} to {}) lies outside buffer {} of {} bytes{}", what, view,
           bv.byteOffset, uint64_t(bv.byteOffset) + bv.byteLength, bv.buffer, buf.data.size(),
           buf.data.empty() ? " (its file may be missing)" : "");
    return {buf.data.data() + bv.byteOffset, bv.byteLength};
  }

  // Reads an accessor as `components` floats per element; integer components are converted
  // (normalized ones to [0, 1] or [-1, 1], as the specification says).
  std::vector<float> read_floats(int index, int components, const std::string& what) const {
    const auto& a = accessor(index, what);
    const std::string where = fmt::format("{} (accessor {})", what, index);
    if (component_count(a.type) != components)
      fail("{}: expected {} components per element", where, components);
    const size_t cs = component_size(a.componentType);
    // The claimed count is checked against the buffer (or, for an accessor of zeros, the memory
    // budget) before anything is allocated for it.
    const auto [data, stride] = element_range(a, where, cs * size_t(components));
    std::vector<float> out(a.count * size_t(components), 0.0f);
    if (!data) return out;  // all zeros, as the specification says
    for (size_t i = 0; i < a.count; ++i)
      for (int c = 0; c < components; ++c) {
        const unsigned char* p = data + i * stride + size_t(c) * cs;
        out[i * size_t(components) + size_t(c)] = component(p, a.componentType, a.normalized);
      }
    for (float v : out)
      if (!std::isfinite(v)) fail("{}: a value is not finite", where);
    return out;
  }

  std::vector<uint32_t> read_indices(int index, const std::string& what) const {
    const auto& a = accessor(index, what);
    const std::string where = fmt::format("{} (accessor {})", what, index);
    if (a.type != TINYGLTF_TYPE_SCALAR) fail("{}: indices must be scalars", where);
    if (a.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
        a.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
        a.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
      fail("{}: indices must be unsigned integers", where);
    const size_t cs = component_size(a.componentType);
    const auto [data, stride] = element_range(a, where, cs);
    std::vector<uint32_t> out(a.count, 0);
    if (!data) return out;
    for (size_t i = 0; i < a.count; ++i) {
      const unsigned char* p = data + i * stride;
      if (cs == 1)
        out[i] = p[0];
      else if (cs == 2)
        out[i] = uint32_t(load<uint16_t>(p));
      else
        out[i] = load<uint32_t>(p);
    }
    return out;
  }

  const tinygltf::Accessor& accessor(int index, const std::string& what) const {
    if (index < 0 || size_t(index) >= m_model.accessors.size())
      fail("{}: accessor {} does not exist ({} accessors)", what, index, m_model.accessors.size());
    const auto& a = m_model.accessors[size_t(index)];
    if (a.sparse.isSparse) fail("{}: sparse accessors are not supported", what);
    if (component_size(a.componentType) == 0)
      fail("{}: accessor {} has an unknown component type {}", what, index, a.componentType);
    return a;
  }

  // The first element and the stride of an accessor, its whole range checked; null for an
  // accessor without a buffer view (all zeros), whose count is checked against the memory
  // budget instead (as 4-byte values, as it is read).
  std::pair<const unsigned char*, size_t> element_range(const tinygltf::Accessor& a,
                                                        const std::string& where,
                                                        size_t element) const {
    if (a.bufferView < 0) {
      check_memory_budget(double(a.count) * double(element / component_size(a.componentType)) * 4,
                          fmt::format("{}: count {} without a buffer view", where, a.count));
      return {nullptr, element};
    }
    const auto [bytes, size] = view_bytes(a.bufferView, where);
    const auto& bv = m_model.bufferViews[size_t(a.bufferView)];
    size_t stride = element;
    if (bv.byteStride != 0) {
      if (bv.byteStride < element || bv.byteStride > 252 || bv.byteStride % 4 != 0)
        fail("{}: byte stride {} is invalid for elements of {} bytes", where, bv.byteStride,
             element);
      stride = bv.byteStride;
    }
    if (a.count == 0) return {bytes, stride};
    // The last element ends at offset + (count - 1) * stride + element, all within the view.
    if (a.byteOffset > size || (a.count - 1) > (size - a.byteOffset) / stride ||
        (a.count - 1) * stride + element > size - a.byteOffset)
      fail("{}: {} elements from byte {} do not fit the buffer view's {} bytes", where, a.count,
           a.byteOffset, size);
    return {bytes + a.byteOffset, stride};
  }

  template <typename T>
  static T load(const unsigned char* p) {
    T v;
    std::memcpy(&v, p, sizeof(T));
    return v;
  }

  static float component(const unsigned char* p, int type, bool normalized) {
    switch (type) {
      case TINYGLTF_COMPONENT_TYPE_FLOAT:
        return load<float>(p);
      case TINYGLTF_COMPONENT_TYPE_BYTE: {
        const float v = float(load<int8_t>(p));
        return normalized ? std::max(v / 127.0f, -1.0f) : v;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
        return normalized ? p[0] / 255.0f : float(p[0]);
      case TINYGLTF_COMPONENT_TYPE_SHORT: {
        const float v = float(load<int16_t>(p));
        return normalized ? std::max(v / 32767.0f, -1.0f) : v;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        const float v = float(load<uint16_t>(p));
        return normalized ? v / 65535.0f : v;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
        return float(load<uint32_t>(p));
    }
    return 0;
  }

  // --- meshes ---

  void add_mesh(int index, const Affine& world, const std::string& where) {
    if (size_t(index) >= m_model.meshes.size())
      fail("{}: mesh {} does not exist ({} meshes)", where, index, m_model.meshes.size());
    const auto& gm = m_model.meshes[size_t(index)];
    for (size_t k = 0; k < gm.primitives.size(); ++k) {
      const auto& prim = gm.primitives[k];
      const std::string pw = fmt::format("{}: mesh {} primitive {}", m_name, index, k);
      const int mode = prim.mode < 0 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
      if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
          mode != TINYGLTF_MODE_TRIANGLE_FAN) {
        warn(fmt::format("{}: points and lines are not rendered; skipped", pw));
        continue;
      }
      auto pos = prim.attributes.find("POSITION");
      if (pos == prim.attributes.end()) {
        warn(fmt::format("{}: no POSITION; skipped", pw));
        continue;
      }
      Mesh mesh;
      std::vector<float> p = read_floats(pos->second, 3, pw + " POSITION");
      const size_t nv = p.size() / 3;
      mesh.positions.resize(nv);
      for (size_t i = 0; i < nv; ++i)
        mesh.positions[i] = Vec3(p[3 * i], p[3 * i + 1], p[3 * i + 2]);
      if (auto it = prim.attributes.find("NORMAL"); it != prim.attributes.end()) {
        std::vector<float> n = read_floats(it->second, 3, pw + " NORMAL");
        if (n.size() != p.size()) fail("{}: {} normals for {} positions", pw, n.size() / 3, nv);
        mesh.normals.resize(nv);
        for (size_t i = 0; i < nv; ++i)
          mesh.normals[i] = Vec3(n[3 * i], n[3 * i + 1], n[3 * i + 2]);
      }
      if (auto it = prim.attributes.find("TEXCOORD_0"); it != prim.attributes.end()) {
        std::vector<float> t = read_floats(it->second, 2, pw + " TEXCOORD_0");
        if (t.size() / 2 != nv) fail("{}: {} uvs for {} positions", pw, t.size() / 2, nv);
        mesh.uvs.resize(nv);
        // glTF's v runs down the image, rll's up.
        for (size_t i = 0; i < nv; ++i) mesh.uvs[i] = Vec2{t[2 * i], 1 - t[2 * i + 1]};
      }
      std::vector<uint32_t> idx;
      if (prim.indices >= 0) {
        idx = read_indices(prim.indices, pw + " indices");
        for (uint32_t i : idx)
          if (i >= nv) fail("{}: index {} is out of range ({} vertices)", pw, i, nv);
      } else {
        idx.resize(nv);
        for (size_t i = 0; i < nv; ++i) idx[i] = uint32_t(i);
      }
      if (mode == TINYGLTF_MODE_TRIANGLES) {
        if (idx.size() % 3 != 0)
          fail("{}: {} indices is not a whole number of triangles", pw, idx.size());
        for (size_t i = 0; i + 2 < idx.size(); i += 3)
          mesh.triangles.push_back({idx[i], idx[i + 1], idx[i + 2]});
      } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
        for (size_t i = 0; i + 2 < idx.size(); ++i)
          mesh.triangles.push_back(i % 2 == 0
                                       ? std::array<uint32_t, 3>{idx[i], idx[i + 1], idx[i + 2]}
                                       : std::array<uint32_t, 3>{idx[i + 1], idx[i], idx[i + 2]});
      } else {
        for (size_t i = 1; i + 1 < idx.size(); ++i)
          mesh.triangles.push_back({idx[i], idx[i + 1], idx[0]});
      }
      // A mesh that many nodes share is built once per node: its copies count.
      if (const std::string why = triangle_budget_problem(
              double(m_scene.mesh.triangle_count() + mesh.triangle_count()), m_policy);
          !why.empty())
        fail("{}: {}", pw, why);
      transform_mesh(mesh, world, 0, 0);
      assign_materials(prim.material, mesh, pw);
      mesh.light.assign(mesh.triangle_count(), -1);
      m_scene.mesh.append(mesh, 0);
    }
  }

  // --- materials ---

  struct Converted {
    uint32_t material = 0;
    int emissive_texture = -1;  // the material's emission texture (Scene::textures), or -1
  };

  void assign_materials(int index, Mesh& mesh, const std::string& where) {
    const Converted& c = material(index, where);
    mesh.material.assign(mesh.triangle_count(), c.material);
    if (c.emissive_texture < 0 || !mesh.uvs.empty()) return;
    // An emissive texture needs TEXCOORD_0: without, the primitive emits the factor times the
    // texture's mean (one material per glTF material).
    auto it = m_untextured_emitters.find(c.material);
    if (it == m_untextured_emitters.end()) {
      const Image& tex = m_scene.textures[size_t(c.emissive_texture)];
      Rgb mean(0);
      for (const auto& px : tex.pixels()) mean += px;
      mean = mean / float(std::max<size_t>(1, tex.pixel_count()));
      Material m = m_scene.materials[c.material];
      m.emission = m.emission * mean;
      m.emission_texture = -1;
      m_scene.materials.push_back(m);
      it = m_untextured_emitters.emplace(c.material, uint32_t(m_scene.materials.size() - 1)).first;
    }
    warn(fmt::format("{}: an emissive texture without TEXCOORD_0 emits its mean colour", where));
    mesh.material.assign(mesh.triangle_count(), it->second);
  }

  const Converted& material(int index, const std::string& where) {
    auto it = m_materials.find(index);
    if (it != m_materials.end()) return it->second;
    tinygltf::Material gm;  // the specification's default material when there is none
    if (index >= 0) {
      if (size_t(index) >= m_model.materials.size())
        fail("{}: material {} does not exist ({} materials)", where, index,
             m_model.materials.size());
      gm = m_model.materials[size_t(index)];
    }
    const std::string mw = fmt::format("{}: material {}", m_name, index);
    Material m;
    m.name = gm.name.empty() ? fmt::format("gltf material {}", index) : gm.name;
    const auto& pbr = gm.pbrMetallicRoughness;
    Rgb base(1);
    if (!pbr.baseColorFactor.empty()) {
      if (pbr.baseColorFactor.size() != 4) fail("{}: baseColorFactor needs 4 values", mw);
      base = Rgb(to_float(pbr.baseColorFactor[0]), to_float(pbr.baseColorFactor[1]),
                 to_float(pbr.baseColorFactor[2]));
    }
    if (!is_finite(base) || min_component(base) < 0)
      fail("{}: baseColorFactor must be finite and >= 0", mw);
    const float metallic = to_float(pbr.metallicFactor), rough = to_float(pbr.roughnessFactor);
    if (!(metallic >= 0 && metallic <= 1) || !(rough >= 0 && rough <= 1))
      fail("{}: metallicFactor and roughnessFactor must be in [0, 1]", mw);
    m.roughness = rough * rough;  // glTF's perceptual roughness to GGX alpha
    int base_texture = -1;
    if (pbr.baseColorTexture.index >= 0) {
      base_texture = texture(pbr.baseColorTexture.index, mw + " baseColorTexture");
      if (pbr.baseColorTexture.texCoord != 0)
        warn(fmt::format("{}: only TEXCOORD_0 is read; the base colour texture uses it", mw));
    }
    const tinygltf::Value* transmission = extension(gm, "KHR_materials_transmission");
    const float transmit =
        transmission ? to_float(number_or(*transmission, "transmissionFactor", 0)) : 0.0f;
    if (!(transmit >= 0 && transmit <= 1))
      fail("{}: KHR_materials_transmission transmissionFactor must be in [0, 1]", mw);
    float ior = 1.5f;
    if (const tinygltf::Value* e = extension(gm, "KHR_materials_ior")) {
      // The extension allows ior >= 1, and 0, which makes the specular layer reflect fully
      // (its F0 = ((ior - 1) / (ior + 1))^2 = 1): rll has no such layer, and warns.
      ior = to_float(number_or(*e, "ior", 1.5));
      if (!std::isfinite(ior) || !(ior >= 1 || ior == 0))
        fail("{}: KHR_materials_ior ior must be at least 1, or 0 (got {})", mw, ior);
      if (ior == 0) {
        warn(
            fmt::format("{}: KHR_materials_ior ior 0 (a fully reflective specular layer) is not "
                        "supported; rendered with ior 1.5",
                        mw));
        ior = 1.5f;
      }
    }
    if (const tinygltf::Value* volume = extension(gm, "KHR_materials_volume")) {
      const double thickness = number_or(*volume, "thicknessFactor", 0);
      if (!(thickness >= 0) || !std::isfinite(thickness))
        fail("{}: KHR_materials_volume thicknessFactor must be finite and >= 0 (got {})", mw,
             thickness);
    }
    // A clearcoat (glTF gives it IOR 1.5) over a dielectric base is pbrt-v4's coated diffuse.
    const tinygltf::Value* clearcoat = extension(gm, "KHR_materials_clearcoat");
    const float coat = clearcoat ? to_float(number_or(*clearcoat, "clearcoatFactor", 0)) : 0.0f;
    const float coat_rough =
        clearcoat ? to_float(number_or(*clearcoat, "clearcoatRoughnessFactor", 0)) : 0.0f;
    if (!(coat >= 0 && coat <= 1) || !(coat_rough >= 0 && coat_rough <= 1))
      fail(
          "{}: KHR_materials_clearcoat clearcoatFactor and clearcoatRoughnessFactor must be in "
          "[0, 1]",
          mw);
    if (coat > 0 && (metallic >= 0.5f || transmit >= 0.5f))
      warn(fmt::format("{}: a clearcoat over a {} is not supported; the clearcoat is ignored", mw,
                       metallic >= 0.5f ? "metal" : "transmissive material"));
    if (metallic < 0.5f && transmit > 0 && transmit < 0.5f)
      warn(
          fmt::format("{}: a transmissionFactor below 0.5 ({}) is ignored: the material is "
                      "rendered opaque",
                      mw, transmit));
    if (metallic >= 0.5f) {
      m.type = MaterialType::Conductor;
      m.specular = base;
      m.eta = kTintableEta;
      m.k = kTintableK;
      if (base_texture >= 0)
        warn(fmt::format("{}: a metal's base colour texture is not supported; its factor is used",
                         mw));
    } else if (transmit >= 0.5f) {
      // Glass. glTF's transmission without KHR_materials_volume is thin-walled (a pane: light
      // goes straight through); with a volume (thicknessFactor > 0) it refracts.
      const tinygltf::Value* volume = extension(gm, "KHR_materials_volume");
      const bool solid = volume && number_or(*volume, "thicknessFactor", 0) > 0;
      m.type = solid ? MaterialType::Dielectric : MaterialType::ThinDielectric;
      m.ior = ior;
      if (!solid) m.roughness = 0;
      if (transmit < 1)
        warn(fmt::format("{}: transmissionFactor {} is rendered as fully transmissive glass", mw,
                         transmit));
      if (transmission->Has("transmissionTexture"))
        warn(fmt::format("{}: the transmissionTexture is not supported; ignored", mw));
      if (!solid && rough > 0)
        warn(
            fmt::format("{}: thin-walled transmission is rendered smooth (roughnessFactor {} "
                        "ignored)",
                        mw, rough));
      if (!(base == Rgb(1)) || base_texture >= 0)
        warn(
            fmt::format("{}: glass is rendered clear: its base colour (and texture) does not "
                        "tint the transmitted light",
                        mw));
      if (volume && (volume->Has("attenuationDistance") || volume->Has("attenuationColor")))
        warn(fmt::format("{}: KHR_materials_volume attenuation is not supported; the glass is "
                         "rendered without absorption",
                         mw));
    } else if (coat > 0) {
      // The coating's roughness replaces the base's, whose own lobe the coated diffuse does not
      // have (its base is Lambertian).
      m.type = MaterialType::CoatedDiffuse;
      m.albedo = base;
      m.albedo_texture = base_texture;
      m.roughness = coat_rough * coat_rough;  // perceptual roughness to GGX alpha
      m.ior = 1.5f;
      m.specular = Rgb(1);
      if (coat < 1)
        warn(fmt::format("{}: clearcoatFactor {} is rendered as a full clearcoat", mw, coat));
      for (const char* t :
           {"clearcoatTexture", "clearcoatRoughnessTexture", "clearcoatNormalTexture"})
        if (clearcoat->Has(t))
          warn(fmt::format("{}: the KHR_materials_clearcoat {} is not supported; ignored", mw, t));
      if (extension(gm, "KHR_materials_specular"))
        warn(
            fmt::format("{}: KHR_materials_specular is ignored under a clearcoat (the coated "
                        "base is Lambertian)",
                        mw));
    } else {
      m.albedo = base;
      m.albedo_texture = base_texture;
      const tinygltf::Value* spec = extension(gm, "KHR_materials_specular");
      const float specular = spec ? to_float(number_or(*spec, "specularFactor", 1)) : 1.0f;
      Rgb spec_colour(1);
      if (spec && spec->Has("specularColorFactor")) {
        const auto& v = spec->Get("specularColorFactor");
        if (v.IsArray() && v.ArrayLen() == 3)
          for (int i = 0; i < 3; ++i)
            spec_colour[i] = to_float(v.Get(i).IsNumber() ? v.Get(i).GetNumberAsDouble() : 1);
      }
      if (specular == 0) {
        m.type = MaterialType::Diffuse;  // glTF without its specular layer is Lambertian
      } else {
        m.type = MaterialType::Plastic;
        m.specular = spec_colour * specular;
        m.ior = ior;
        if (!is_finite(m.specular) || min_component(m.specular) < 0)
          fail("{}: KHR_materials_specular values must be finite and >= 0", mw);
      }
    }
    Converted c;
    Rgb emission(0);
    if (gm.emissiveFactor.size() == 3)
      emission = Rgb(to_float(gm.emissiveFactor[0]), to_float(gm.emissiveFactor[1]),
                     to_float(gm.emissiveFactor[2]));
    if (const tinygltf::Value* strength = extension(gm, "KHR_materials_emissive_strength"))
      emission = emission * to_float(number_or(*strength, "emissiveStrength", 1));
    if (!is_finite(emission) || min_component(emission) < 0)
      fail("{}: the emission must be finite and >= 0", mw);
    m.two_sided_emission = gm.doubleSided;
    m.emission = emission;
    if (gm.emissiveTexture.index >= 0 && !is_black(emission)) {
      c.emissive_texture = m.emission_texture =
          texture(gm.emissiveTexture.index, mw + " emissiveTexture");
      if (gm.emissiveTexture.texCoord != 0)
        warn(fmt::format("{}: only TEXCOORD_0 is read; the emissive texture uses it", mw));
    }
    if (gm.alphaMode != "OPAQUE" && !gm.alphaMode.empty())
      warn(fmt::format("{}: alphaMode {} is not supported; rendered opaque", mw, gm.alphaMode));
    if (pbr.metallicRoughnessTexture.index >= 0) {
      if (m.type == MaterialType::ThinDielectric || m.type == MaterialType::Diffuse ||
          m.type == MaterialType::CoatedDiffuse) {
        warn(
            fmt::format("{}: the metallic-roughness texture has no use on a {} material; "
                        "ignored",
                        mw, material_type_name(m.type)));
      } else {
        m.roughness_texture = roughness_texture(pbr.metallicRoughnessTexture.index, rough,
                                                mw + " metallicRoughnessTexture");
        if (pbr.metallicRoughnessTexture.texCoord != 0)
          warn(fmt::format("{}: only TEXCOORD_0 is read; the roughness texture uses it", mw));
        // The blue channel (metallic) cannot turn parts of a material into metal or back.
        const Image& mr = m_scene.textures[size_t(
            texture(pbr.metallicRoughnessTexture.index, mw + " metallicRoughnessTexture", false))];
        if (std::any_of(mr.pixels().begin(), mr.pixels().end(), [&](const Rgb& c) {
              return (c.z * metallic >= 0.5f) != (metallic >= 0.5f);
            }))
          warn(
              fmt::format("{}: the metallic channel (blue) of the metallic-roughness texture "
                          "is not supported; metallicFactor decides the material",
                          mw));
      }
    }
    if (gm.normalTexture.index >= 0 || gm.occlusionTexture.index >= 0)
      warn(fmt::format("{}: normal and occlusion textures are not supported; ignored", m_name));
    m_scene.materials.push_back(m);
    c.material = uint32_t(m_scene.materials.size() - 1);
    return m_materials[index] = c;
  }

  static const tinygltf::Value* extension(const tinygltf::Material& m, const char* name) {
    auto it = m.extensions.find(name);
    return it == m.extensions.end() || !it->second.IsObject() ? nullptr : &it->second;
  }

  // A texture's image, decoded (colours from sRGB, data as stored) into Scene::textures once.
  int texture(int index, const std::string& where, bool srgb = true) {
    if (index < 0 || size_t(index) >= m_model.textures.size())
      fail("{}: texture {} does not exist ({} textures)", where, index, m_model.textures.size());
    const int source = m_model.textures[size_t(index)].source;
    if (source < 0 || size_t(source) >= m_model.images.size())
      fail("{}: texture {} has no image (source {})", where, index, source);
    if (auto it = m_images.find({source, srgb}); it != m_images.end()) return it->second;
    const auto& img = m_model.images[size_t(source)];
    const std::string iw = fmt::format("{}: image {}", m_name, source);
    Image decoded;
    if (img.bufferView >= 0) {
      const auto [bytes, size] = view_bytes(img.bufferView, iw);
      decoded = decode_image(bytes, size, srgb, iw);
    } else {
      if (img.image.empty()) {
        // Why, where the file reader said: the failure at the path that ends in the URI.
        for (const auto& [path, why] : m_failures)
          if (!img.uri.empty() && path.size() >= img.uri.size() &&
              path.compare(path.size() - img.uri.size(), img.uri.size(), img.uri) == 0)
            fail("{} ('{}') could not be read: {}", iw, printable(img.uri, 256), why);
        fail("{} ('{}') could not be read{}", iw, printable(img.uri, 256),
             m_policy.read_files ? " (missing file?)" : " (reading files is turned off)");
      }
      decoded = decode_image(img.image.data(), img.image.size(), srgb, iw);
    }
    if (decoded.width() <= 0 || decoded.height() <= 0) fail("{}: empty image", iw);
    m_scene.textures.push_back(std::move(decoded));
    return m_images[{source, srgb}] = int(m_scene.textures.size() - 1);
  }

  // rll's roughness texture (GGX alpha in the first channel) from a metallic-roughness texture:
  // alpha = (green channel x roughnessFactor)^2, glTF's roughness being perceptual.
  int roughness_texture(int index, float factor, const std::string& where) {
    const int data = texture(index, where, false);
    auto key = std::make_pair(data, factor);
    if (auto it = m_roughness.find(key); it != m_roughness.end()) return it->second;
    Image alpha = m_scene.textures[size_t(data)];
    for (size_t i = 0; i < alpha.pixel_count(); ++i) alpha[i] = Rgb(sqr(alpha[i].y * factor));
    m_scene.textures.push_back(std::move(alpha));
    return m_roughness[key] = int(m_scene.textures.size() - 1);
  }

  // --- camera and lights ---

  void add_camera(int index, const Affine& world, const std::string& where) {
    if (size_t(index) >= m_model.cameras.size())
      fail("{}: camera {} does not exist ({} cameras)", where, index, m_model.cameras.size());
    if (m_scene.has_camera) return;  // the first camera only
    const auto& c = m_model.cameras[size_t(index)];
    if (c.type != "perspective") {
      warn(fmt::format("{}: a {} camera is not supported; skipped", where, c.type));
      return;
    }
    const double fov = c.perspective.yfov * 180 / 3.14159265358979323846;
    if (!(fov > 0 && fov < 180)) fail("{}: camera yfov must be in (0, pi) radians", where);
    Camera& cam = m_scene.camera;
    cam.position = world.t;
    cam.target = world.t + normalize(world.apply_vector(Vec3(0, 0, -1)));
    cam.up = normalize(world.apply_vector(Vec3(0, 1, 0)));
    cam.fov = to_float(fov);
    if (!is_finite(cam.target) || !is_finite(cam.up) ||
        !(length_sq(cross(cam.target - cam.position, cam.up)) > 0))
      fail("{}: the camera transform is degenerate", where);
    const double aspect = c.perspective.aspectRatio;
    if (aspect > 0) {
      if (!(aspect >= 1e-3 && aspect <= 1e3))
        fail("{}: camera aspectRatio {} is out of range", where, aspect);
      m_scene.width = 640;
      m_scene.height = std::max(1, int(std::lround(640 / aspect)));
    }
    m_scene.has_camera = true;
  }

  void add_light(const tinygltf::Value& ext, const Affine& world, const std::string& where) {
    if (!ext.IsObject() || !ext.Has("light") || !ext.Get("light").IsInt())
      fail("{}: KHR_lights_punctual needs an integer \"light\"", where);
    const int index = ext.Get("light").GetNumberAsInt();
    if (index < 0 || size_t(index) >= m_model.lights.size())
      fail("{}: light {} does not exist ({} lights)", where, index, m_model.lights.size());
    const auto& l = m_model.lights[size_t(index)];
    Rgb colour(1);
    if (!l.color.empty()) {
      if (l.color.size() != 3) fail("{}: light {} colour needs 3 values", where, index);
      colour = Rgb(to_float(l.color[0]), to_float(l.color[1]), to_float(l.color[2]));
    }
    const Rgb value = colour * to_float(l.intensity);
    if (!is_finite(value) || min_component(value) < 0)
      fail("{}: light {} colour and intensity must be finite and >= 0", where, index);
    if (l.type == "point") {
      m_scene.lights.push_back(make_point_light(world.t, value));
    } else if (l.type == "directional") {
      const Vec3 towards = world.apply_vector(Vec3(0, 0, 1));  // the light shines along -z
      if (!(length_sq(towards) > 0) || !is_finite(towards))
        fail("{}: the directional light's transform is degenerate", where);
      m_scene.lights.push_back(make_directional_light(normalize(towards), value));
    } else if (l.type == "spot") {
      const double inner = l.spot.innerConeAngle, outer = l.spot.outerConeAngle;
      if (!(inner >= 0 && inner < outer && outer <= 0.5 * kPi + 1e-6))
        fail("{}: spot light {} needs 0 <= innerConeAngle < outerConeAngle <= pi/2 (got {} and {})",
             where, index, inner, outer);
      const Vec3 axis = world.apply_vector(Vec3(0, 0, -1));  // the light shines along -z
      if (!(length_sq(axis) > 0) || !is_finite(axis))
        fail("{}: the spot light's transform is degenerate", where);
      m_scene.lights.push_back(make_spot_light(world.t, axis, value, float(std::cos(inner)),
                                               float(std::cos(outer))));
      warn(fmt::format("{}: spot lights' falloff between their inner and outer cones is pbrt-v4's "
                       "smoothstep in rll (glTF suggests a squared linear ramp)",
                       m_name));
    } else {
      warn(fmt::format("{}: a {} light is not supported; skipped", where, l.type));
    }
  }

  const tinygltf::Model& m_model;
  std::string m_name;
  Scene& m_scene;
  ReadPolicy m_policy;
  std::vector<bool> m_visited;
  std::map<int, Converted> m_materials;
  std::map<std::pair<int, bool>, int> m_images;  // (image, sRGB) -> Scene::textures
  std::map<std::pair<int, float>, int> m_roughness;  // (linear image, factor) -> alpha texture
  // A material with an emission texture -> its variant for primitives without TEXCOORD_0.
  std::map<uint32_t, uint32_t> m_untextured_emitters;
  std::set<std::string> m_warned;
  std::map<std::string, std::string> m_failures;
};

}  // namespace

void parse_gltf(std::string_view bytes, const std::string& name, const fs::path& base_dir,
                Scene& scene, const ReadPolicy& policy) {
  if (bytes.size() >= (size_t(1) << 31)) fail("{}: the file is too large (2 GiB at most)", name);
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(keep_image_bytes, nullptr);
  FileReads reads;
  if (!policy.read_files)
    loader.SetFsCallbacks({no_file_exists, same_path, no_file_read, no_file_write, nullptr});
  else
    loader.SetFsCallbacks({&tinygltf::FileExists, &tinygltf::ExpandFilePath, checked_file_read,
                           no_file_write, &reads});
  tinygltf::Model model;
  std::string err, warn;
  if (bytes.empty()) fail("{}: empty file", name);
  const bool binary = bytes.size() >= 4 && bytes.substr(0, 4) == "glTF";
  const std::string ext = lower_extension(name);
  if (ext == ".glb" || binary) {
    if (bytes.size() < 12)
      fail("{}: not a GLB: {} bytes are too short for its 12-byte header", name, bytes.size());
    if (!binary) fail("{}: not a GLB: it does not begin with 'glTF'", name);
  }
  check_field_types(gltf_json_text(bytes, binary), name);
  bool ok = false;
  const std::string dir = base_dir.string();
  try {
    if (binary)
      ok = loader.LoadBinaryFromMemory(&model, &err, &warn,
                                       reinterpret_cast<const unsigned char*>(bytes.data()),
                                       unsigned(bytes.size()), dir);
    else
      ok = loader.LoadASCIIFromString(&model, &err, &warn, bytes.data(), unsigned(bytes.size()),
                                      dir);
  } catch (const std::exception& e) {
    // tinygltf reports errors in `err`; its JSON library may still throw on odd input.
    fail("{}: {}", name, e.what());
  }
  if (!ok || !err.empty())
    fail("{}: {}", name,
         err.empty() ? "cannot parse the file"
                     : one_line(shorten_uri_errors(err, gltf_json_text(bytes, binary))));
  if (!warn.empty()) scene.warnings.push_back(fmt::format("{}: {}", name, one_line(warn)));
  GltfReader(model, name, scene, policy, reads.failures).read();
}

void load_gltf(const fs::path& path, Scene& scene) {
  const std::string file = path.string();
  if (!fs::exists(path)) fail("{}: file not found", file);
  parse_gltf(read_text_file(path), file, path.parent_path(), scene);
}

}  // namespace rll
