// Stanford PLY meshes, ASCII and binary (little and big endian): vertex positions, normals and
// uvs, faces as index lists (polygons fan-triangulated). No Debian package reads PLY, so this is
// a small strict reader of its own: every count, type and index is checked, and errors name the
// file and the header or data line (ASCII) or byte offset (binary).
#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstring>
#include <optional>

#include <zlib.h>

#include "rll/core/error.h"
#include "rll/core/memory_budget.h"
#include "rll/io/load.h"
#include "rll/io/text_scan.h"
#include "rll/scene/transform.h"

namespace rll {
namespace fs = std::filesystem;

namespace {

enum class PlyType : uint8_t { Int8, Uint8, Int16, Uint16, Int32, Uint32, Float32, Float64 };
enum class Encoding : uint8_t { Ascii, BinaryLittle, BinaryBig };

struct TypeName {
  const char* name;
  PlyType type;
};
constexpr TypeName kTypes[] = {
    {"char", PlyType::Int8},      {"int8", PlyType::Int8},       {"uchar", PlyType::Uint8},
    {"uint8", PlyType::Uint8},    {"short", PlyType::Int16},     {"int16", PlyType::Int16},
    {"ushort", PlyType::Uint16},  {"uint16", PlyType::Uint16},   {"int", PlyType::Int32},
    {"int32", PlyType::Int32},    {"uint", PlyType::Uint32},     {"uint32", PlyType::Uint32},
    {"float", PlyType::Float32},  {"float32", PlyType::Float32}, {"double", PlyType::Float64},
    {"float64", PlyType::Float64}};

size_t type_size(PlyType t) {
  switch (t) {
    case PlyType::Int8:
    case PlyType::Uint8:
      return 1;
    case PlyType::Int16:
    case PlyType::Uint16:
      return 2;
    case PlyType::Int32:
    case PlyType::Uint32:
    case PlyType::Float32:
      return 4;
    case PlyType::Float64:
      return 8;
  }
  return 0;
}
// The largest list length a count of type `t` can give.
double max_count(PlyType t) {
  switch (t) {
    case PlyType::Int8:
      return 127;
    case PlyType::Uint8:
      return 255;
    case PlyType::Int16:
      return 32767;
    case PlyType::Uint16:
      return 65535;
    case PlyType::Int32:
      return 2147483647.0;
    default:
      return 4294967295.0;
  }
}
bool is_integer(PlyType t) {
  return t != PlyType::Float32 && t != PlyType::Float64;
}

struct Property {
  std::string name;
  PlyType type = PlyType::Float32;
  bool list = false;
  PlyType count_type = PlyType::Uint8;
};

struct Element {
  std::string name;
  size_t count = 0;
  std::vector<Property> properties;
  size_t line = 0;  // header line, for messages
};

// Where the vertex and face data rll uses sit in their elements (-1: absent).
struct Layout {
  int vertex = -1, face = -1;  // element indices
  int xyz[3] = {-1, -1, -1}, normal[3] = {-1, -1, -1}, uv[2] = {-1, -1};
  int indices = -1;  // face property
};

class PlyReader {
 public:
  PlyReader(std::string_view bytes, const std::string& name) : m_data(bytes), m_name(name) {}

  // The most bytes the whole file can take by its header, which `bytes` must hold. The least
  // it takes is checked first: against the memory budget (with the mesh it makes), and, where
  // the file is `compressed_bytes` of gzip data (0: not known), against what those inflate to.
  double declared_bytes(size_t compressed_bytes) {
    read_header();
    const double least = double(m_body) + least_body_bytes();
    if (compressed_bytes > 0 && least > double(compressed_bytes) * kDeflateMaxRatio + 1024)
      fail(
          "{}: its header claims {}, which take at least {:.0f} bytes, but its {} bytes of gzip "
          "data inflate to at most {:.0f} (deflate's limit is {:.0f}:1): a damaged or hostile "
          "file",
          m_name, counts_text(), least, compressed_bytes,
          double(compressed_bytes) * kDeflateMaxRatio + 1024, kDeflateMaxRatio);
    check_memory(least);
    // An ASCII value (with the space after it) is at most this long: "-1.2345678901234567e-308"
    // is 24 characters.
    constexpr double kAsciiValue = 64;
    double total = double(m_body);
    for (const Element& el : m_elements) {
      double entry = m_encoding == Encoding::Ascii ? 2 : 0;  // a line end
      for (const auto& p : el.properties) {
        const double values = p.list ? 1 + max_count(p.count_type) : 1;
        entry += m_encoding == Encoding::Ascii
                     ? values * kAsciiValue
                     : (p.list ? double(type_size(p.count_type)) +
                                     (values - 1) * double(type_size(p.type))
                               : double(type_size(p.type)));
      }
      total += double(el.count) * entry;
    }
    return total;
  }

  Mesh read() {
    read_header();
    choose_layout();
    for (size_t e = 0; e < m_elements.size(); ++e) {
      if (m_encoding == Encoding::Ascii)
        read_ascii_element(e);
      else
        read_binary_element(e);
    }
    if (m_encoding == Encoding::Ascii) {
      std::string_view line;
      while (m_lines->next(line)) {
        std::string_view rest = line, tok;
        if (next_token(rest, tok))
          fail_line(m_lines->number() + m_header_lines, "data after the last element");
      }
    }
    check_not_empty();
    return std::move(m_mesh);
  }

 private:
  // The fewest bytes the body can take by the header: each entry its fewest (a binary value its
  // size, a list its count; an ASCII value a character and a space or line end).
  double least_body_bytes() const {
    double total = 0;
    for (const Element& el : m_elements) {
      double entry = 0;
      for (const auto& p : el.properties)
        entry +=
            m_encoding == Encoding::Ascii ? 2 : double(type_size(p.list ? p.count_type : p.type));
      if (m_encoding == Encoding::Ascii) entry = std::max(entry, 2.0);
      total += double(el.count) * entry;
    }
    return total;
  }

  // "300000000 vertices (line 3) and 1 face (line 7)": the counts the header claims.
  std::string counts_text() const {
    std::string out;
    for (const Element& el : m_elements)
      if (el.name == "vertex" || el.name == "face")
        out += fmt::format("{}{} {} (line {})", out.empty() ? "" : " and ", el.count,
                           el.count == 1         ? el.name
                           : el.name == "vertex" ? std::string("vertices")
                                                 : el.name + "s",
                           el.line);
    return out.empty() ? "its elements" : out;
  }

  // Checks what the header's counts need in memory, at the least, before anything is allocated
  // for them: `data_bytes` (the file's bytes as read, inflated where compressed) and the mesh
  // made of them, a position per vertex (and a normal and a uv where the vertex has them) and a
  // scene triangle per face (kSceneBytesPerTriangle: with its share of the acceleration
  // structure).
  void check_memory(double data_bytes) const {
    double mesh = 0;
    for (const Element& el : m_elements) {
      if (el.name == "vertex") {
        auto has = [&](const char* n) {
          return std::any_of(el.properties.begin(), el.properties.end(),
                             [&](const Property& p) { return p.name == n; });
        };
        const double per_vertex =
            double(sizeof(Vec3)) + (has("nx") && has("ny") && has("nz") ? sizeof(Vec3) : 0.0) +
            ((has("u") || has("s") || has("texture_u") || has("texture_s")) ? sizeof(Vec2) : 0.0);
        mesh += double(el.count) * per_vertex;
      } else if (el.name == "face") {
        mesh += double(el.count) * kSceneBytesPerTriangle;
      }
    }
    const double bytes = data_bytes + mesh;
    if (!(bytes <= double(memory_budget_bytes())))
      fail(
          "{}: its header claims {}, which need at least {} as a mesh (and {} of file data), "
          "more than {}; is the file damaged, or the mesh too large for this machine?",
          m_name, counts_text(), format_bytes(mesh), format_bytes(data_bytes),
          memory_budget_phrase());
  }

  [[noreturn]] void fail_line(size_t line, const std::string& what) const {
    fail("{}:{}: {}", m_name, line, what);
  }
  [[noreturn]] void fail_at(size_t offset, const std::string& what) const {
    fail("{}: byte {}: {}", m_name, offset, what);
  }

  // --- header ---

  void read_header() {
    // The header is text ending at the line "end_header"; it must be found within the bytes.
    size_t pos = 0, line_no = 0;
    Element* current = nullptr;
    bool have_format = false;
    auto next_line = [&](std::string_view& line) {
      if (pos >= m_data.size()) return false;
      size_t nl = m_data.find('\n', pos);
      size_t end = nl == std::string_view::npos ? m_data.size() : nl;
      line = m_data.substr(pos, end - pos);
      if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
      pos = nl == std::string_view::npos ? m_data.size() : nl + 1;
      ++line_no;
      return true;
    };
    std::string_view line;
    if (!next_line(line) || line != "ply")
      fail("{}: not a PLY file (it must start with 'ply')", m_name);
    for (;;) {
      if (!next_line(line)) fail("{}: the header has no 'end_header' line", m_name);
      std::string_view rest = line, kw, tok;
      if (!next_token(rest, kw)) continue;
      if (kw == "comment" || kw == "obj_info") continue;
      if (kw == "end_header") {
        if (next_token(rest, tok)) fail_line(line_no, "unexpected text after end_header");
        break;
      }
      if (kw == "format") {
        std::string_view enc, version;
        if (!next_token(rest, enc) || !next_token(rest, version) || next_token(rest, tok))
          fail_line(line_no, "expected 'format ascii|binary_little_endian|binary_big_endian 1.0'");
        if (enc == "ascii")
          m_encoding = Encoding::Ascii;
        else if (enc == "binary_little_endian")
          m_encoding = Encoding::BinaryLittle;
        else if (enc == "binary_big_endian")
          m_encoding = Encoding::BinaryBig;
        else
          fail_line(line_no, fmt::format("unknown format '{}'", printable(enc)));
        if (version != "1.0")
          fail_line(line_no, fmt::format("unsupported PLY version '{}'", printable(version)));
        have_format = true;
      } else if (kw == "element") {
        std::string_view name, count;
        long n = 0;
        if (!next_token(rest, name) || !next_token(rest, count) || next_token(rest, tok))
          fail_line(line_no, "expected 'element NAME COUNT'");
        if (!parse_long(count, n) || n < 0)
          fail_line(line_no, fmt::format("element count '{}' is not a non-negative integer",
                                         printable(count)));
        m_elements.push_back({std::string(name), size_t(n), {}, line_no});
        current = &m_elements.back();
      } else if (kw == "property") {
        if (!current) fail_line(line_no, "a property before any element");
        Property p;
        std::string_view type, name;
        if (!next_token(rest, type)) fail_line(line_no, "expected 'property TYPE NAME'");
        if (type == "list") {
          std::string_view count_type;
          if (!next_token(rest, count_type) || !next_token(rest, type))
            fail_line(line_no, "expected 'property list COUNT_TYPE TYPE NAME'");
          p.list = true;
          p.count_type = parse_type(count_type, line_no);
          if (!is_integer(p.count_type))
            fail_line(line_no, fmt::format("a list count must have an integer type, not '{}'",
                                           printable(count_type)));
        }
        p.type = parse_type(type, line_no);
        if (!next_token(rest, name) || next_token(rest, tok))
          fail_line(line_no, "expected 'property TYPE NAME'");
        p.name = std::string(name);
        for (const auto& q : current->properties)
          if (q.name == p.name)
            fail_line(line_no, fmt::format("property '{}' declared twice", printable(p.name)));
        current->properties.push_back(p);
      } else {
        fail_line(line_no, fmt::format("unknown header statement '{}'", printable(kw)));
      }
    }
    if (!have_format) fail("{}: the header has no 'format' line", m_name);
    m_header_lines = line_no;
    m_body = pos;

    if (m_encoding == Encoding::Ascii) m_lines.emplace(m_data.substr(pos));
  }

  PlyType parse_type(std::string_view s, size_t line) const {
    for (const auto& t : kTypes)
      if (s == t.name) return t.type;
    fail_line(line, fmt::format("unknown property type '{}'", printable(s)));
  }

  void choose_layout() {
    for (size_t e = 0; e < m_elements.size(); ++e) {
      const Element& el = m_elements[e];
      if (el.name == "vertex" && m_layout.vertex < 0) m_layout.vertex = int(e);
      if (el.name == "face" && m_layout.face < 0) m_layout.face = int(e);
    }
    if (m_layout.vertex < 0) fail("{}: the file has no 'vertex' element", m_name);
    if (m_layout.face < 0)
      fail("{}: the file has no 'face' element (rll renders triangles)", m_name);
    const Element& v = m_elements[size_t(m_layout.vertex)];
    auto find = [&](const Element& el, std::initializer_list<const char*> names) {
      for (const char* n : names)
        for (size_t i = 0; i < el.properties.size(); ++i)
          if (el.properties[i].name == n) {
            if (el.properties[i].list)
              fail_line(el.line,
                        fmt::format("property '{}' of '{}' must not be a list", n, el.name));
            return int(i);
          }
      return -1;
    };
    const char* axes[3] = {"x", "y", "z"};
    const char* normals[3] = {"nx", "ny", "nz"};
    for (int k = 0; k < 3; ++k) {
      m_layout.xyz[k] = find(v, {axes[k]});
      if (m_layout.xyz[k] < 0)
        fail_line(v.line, fmt::format("the vertex element has no '{}' property", axes[k]));
      m_layout.normal[k] = find(v, {normals[k]});
    }
    if (m_layout.normal[0] < 0 || m_layout.normal[1] < 0 || m_layout.normal[2] < 0)
      m_layout.normal[0] = m_layout.normal[1] = m_layout.normal[2] = -1;
    m_layout.uv[0] = find(v, {"u", "s", "texture_u", "texture_s"});
    m_layout.uv[1] = find(v, {"v", "t", "texture_v", "texture_t"});
    if (m_layout.uv[0] < 0 || m_layout.uv[1] < 0) m_layout.uv[0] = m_layout.uv[1] = -1;
    const Element& f = m_elements[size_t(m_layout.face)];
    for (const char* n : {"vertex_indices", "vertex_index"})
      for (size_t i = 0; i < f.properties.size() && m_layout.indices < 0; ++i)
        if (f.properties[i].name == n) m_layout.indices = int(i);
    if (m_layout.indices < 0)
      fail_line(f.line, "the face element has no 'vertex_indices' property");
    const Property& ip = f.properties[size_t(m_layout.indices)];
    if (!ip.list) fail_line(f.line, "'vertex_indices' must be a list");
    if (!is_integer(ip.type)) fail_line(f.line, "'vertex_indices' must have an integer type");

    // Each entry takes some bytes at the least (a binary value its size, a list its count, an
    // ASCII entry a line of one character): counts the file cannot hold are caught here, before
    // anything is allocated for them.
    const size_t left = m_data.size() - m_body;
    size_t needed = 0;
    for (const Element& el : m_elements) {
      size_t min_size = m_encoding == Encoding::Ascii ? 2 : 0;
      if (m_encoding != Encoding::Ascii)
        for (const auto& p : el.properties) min_size += type_size(p.list ? p.count_type : p.type);
      if (min_size > 0 && el.count > (left - needed) / min_size) {
        std::string what = fmt::format(
            "the file is truncated: element '{}' has {} entries of at "
            "least {} bytes, more than the {} bytes left",
            el.name, el.count, min_size, left - needed);
        if (m_encoding == Encoding::Ascii) fail_line(el.line, what);
        fail_at(m_body, what);
      }
      needed += el.count * min_size;
    }
    check_memory(double(m_data.size()));
    m_mesh.positions.resize(v.count);
    if (m_layout.normal[0] >= 0) m_mesh.normals.resize(v.count);
    if (m_layout.uv[0] >= 0) m_mesh.uvs.resize(v.count);
    m_values.resize(v.properties.size());
  }

  // --- data ---

  // Stores the scalar values of one vertex (in m_values) into the mesh.
  void store_vertex(size_t i, size_t line, size_t offset) {
    Vec3 p(to_float(m_values[size_t(m_layout.xyz[0])]), to_float(m_values[size_t(m_layout.xyz[1])]),
           to_float(m_values[size_t(m_layout.xyz[2])]));
    if (!is_finite(p)) {
      std::string what =
          fmt::format("vertex {} has a non-finite position ({}, {}, {})", i, p.x, p.y, p.z);
      if (m_encoding == Encoding::Ascii) fail_line(line, what);
      fail_at(offset, what);
    }
    m_mesh.positions[i] = p;
    if (m_layout.normal[0] >= 0) {
      Vec3 n(to_float(m_values[size_t(m_layout.normal[0])]),
             to_float(m_values[size_t(m_layout.normal[1])]),
             to_float(m_values[size_t(m_layout.normal[2])]));
      m_mesh.normals[i] = is_finite(n) ? n : Vec3(0);  // an unusable normal: "none"
    }
    if (m_layout.uv[0] >= 0) {
      Vec2 uv{to_float(m_values[size_t(m_layout.uv[0])]),
              to_float(m_values[size_t(m_layout.uv[1])])};
      if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) {
        std::string what = fmt::format("vertex {} has a non-finite texture coordinate", i);
        if (m_encoding == Encoding::Ascii) fail_line(line, what);
        fail_at(offset, what);
      }
      m_mesh.uvs[i] = uv;
    }
  }

  // Fan-triangulates one face from m_face. Its indices are checked against the vertex count of
  // the header (the positions are sized from it), so faces may come before the vertices.
  void store_face(size_t face, size_t where) {
    const size_t n = m_face.size();
    if (n < 3)
      where_fail(where, fmt::format("face {} has {} vertices (at least 3 are needed)", face, n));
    for (int64_t idx : m_face)
      if (idx < 0 || uint64_t(idx) >= m_mesh.positions.size())
        where_fail(where, fmt::format("face {}: vertex index {} is out of range (the file has {} "
                                      "vertices)",
                                      face, idx, m_mesh.positions.size()));
    for (size_t k = 1; k + 1 < n; ++k)
      m_mesh.triangles.push_back(
          {uint32_t(m_face[0]), uint32_t(m_face[k]), uint32_t(m_face[k + 1])});
  }
  void where_fail(size_t where, const std::string& what) const {
    if (m_encoding == Encoding::Ascii) fail_line(where, what);
    fail_at(where, what);
  }

  void check_not_empty() const {
    if (m_mesh.triangles.empty()) fail("{}: the file has no faces", m_name);
  }

  void read_ascii_element(size_t e) {
    const Element& el = m_elements[e];
    const bool is_vertex = int(e) == m_layout.vertex, is_face = int(e) == m_layout.face;
    if (is_face) m_mesh.triangles.reserve(el.count);
    std::string_view line;
    for (size_t i = 0; i < el.count; ++i) {
      // One element a line; blank lines are skipped.
      std::string_view rest, tok;
      do {
        if (!m_lines->next(line))
          fail("{}: the file ends after {} of {} '{}' entries", m_name, i, el.count, el.name);
        rest = line;
      } while (!next_token(rest, tok));
      const size_t ln = m_lines->number() + m_header_lines;
      rest = line;
      if (is_face) m_face.clear();
      for (size_t p = 0; p < el.properties.size(); ++p) {
        const Property& prop = el.properties[p];
        if (prop.list) {
          double count = ascii_value(rest, prop.count_type, ln, el, prop);
          if (count < 0 || count > double(line.size()))
            fail_line(ln, fmt::format("list '{}' has a bad length {}", prop.name, count));
          for (size_t k = 0; k < size_t(count); ++k) {
            double v = ascii_value(rest, prop.type, ln, el, prop);
            if (is_face && int(p) == m_layout.indices) m_face.push_back(int64_t(v));
          }
        } else {
          double v = ascii_value(rest, prop.type, ln, el, prop);
          if (is_vertex) m_values[p] = v;
        }
      }
      if (next_token(rest, tok))
        fail_line(ln, fmt::format("too many values for one '{}' (it has {} properties)", el.name,
                                  el.properties.size()));
      if (is_vertex) store_vertex(i, ln, 0);
      if (is_face) store_face(i, ln);
    }
  }

  double ascii_value(std::string_view& rest, PlyType type, size_t line, const Element& el,
                     const Property& prop) const {
    std::string_view tok;
    if (!next_token(rest, tok))
      fail_line(line,
                fmt::format("too few values for one '{}' (missing '{}')", el.name, prop.name));
    if (is_integer(type)) {
      long v = 0;
      if (!parse_long(tok, v))
        fail_line(line, fmt::format("'{}' of '{}' must be an integer (got '{}')", prop.name,
                                    el.name, printable(tok)));
      if (!in_range(double(v), type))
        fail_line(line, fmt::format("'{}' value {} is out of range for its type", prop.name, v));
      return double(v);
    }
    float v = 0;
    switch (parse_float(tok, v)) {
      case NumberStatus::Ok:
        return v;
      case NumberStatus::NonFinite: {
        // Positions are checked when stored; other properties (an unused colour) may be inf.
        // The value as written, for the message: "nan", or an infinity ("inf", "-Infinity" and
        // "1e39" alike, which hold an 'n' and no "nan").
        std::string lower(tok);
        for (char& c : lower) c = char(std::tolower(static_cast<unsigned char>(c)));
        if (lower.find("nan") != std::string::npos) return std::nan("");
        return tok[0] == '-' ? -HUGE_VAL : HUGE_VAL;
      }
      case NumberStatus::Malformed:
        break;
    }
    fail_line(line, fmt::format("'{}' of '{}' is not a number (got '{}')", prop.name, el.name,
                                printable(tok)));
  }

  static bool in_range(double v, PlyType t) {
    switch (t) {
      case PlyType::Int8:
        return v >= -128 && v <= 127;
      case PlyType::Uint8:
        return v >= 0 && v <= 255;
      case PlyType::Int16:
        return v >= -32768 && v <= 32767;
      case PlyType::Uint16:
        return v >= 0 && v <= 65535;
      case PlyType::Int32:
        return v >= -2147483648.0 && v <= 2147483647.0;
      case PlyType::Uint32:
        return v >= 0 && v <= 4294967295.0;
      default:
        return true;
    }
  }

  template <typename T>
  T load(const char* p) const {
    T v;
    std::memcpy(&v, p, sizeof(T));
    const bool swap =
        (m_encoding == Encoding::BinaryBig) == (std::endian::native == std::endian::little);
    if (swap && sizeof(T) > 1) {
      unsigned char b[sizeof(T)];
      std::memcpy(b, &v, sizeof(T));
      std::reverse(b, b + sizeof(T));
      std::memcpy(&v, b, sizeof(T));
    }
    return v;
  }

  double binary_value(const char* p, PlyType t) const {
    switch (t) {
      case PlyType::Int8:
        return double(load<int8_t>(p));
      case PlyType::Uint8:
        return double(load<uint8_t>(p));
      case PlyType::Int16:
        return double(load<int16_t>(p));
      case PlyType::Uint16:
        return double(load<uint16_t>(p));
      case PlyType::Int32:
        return double(load<int32_t>(p));
      case PlyType::Uint32:
        return double(load<uint32_t>(p));
      case PlyType::Float32:
        return double(load<float>(p));
      case PlyType::Float64:
        return load<double>(p);
    }
    return 0;
  }

  void read_binary_element(size_t e) {
    const Element& el = m_elements[e];
    const bool is_vertex = int(e) == m_layout.vertex, is_face = int(e) == m_layout.face;
    // The fewest bytes one entry can take (a list at least its count); the element must fit.
    size_t min_size = 0;
    bool fixed = true;
    for (const auto& p : el.properties) {
      min_size += type_size(p.list ? p.count_type : p.type);
      fixed = fixed && !p.list;
    }
    if (is_face) m_mesh.triangles.reserve(el.count);
    const char* data = m_data.data();
    if (fixed) {
      // Every entry the same size: one check covers all of them. (The header's check does not:
      // lists in earlier elements may have taken more than their least.)
      if (min_size > 0 && el.count > (m_data.size() - m_body) / min_size)
        fail_at(m_body, fmt::format("the file is truncated: element '{}' needs {} bytes, {} are "
                                    "left",
                                    el.name, el.count * min_size, m_data.size() - m_body));
      std::vector<size_t> offsets;
      size_t o = 0;
      for (const auto& p : el.properties) {
        offsets.push_back(o);
        o += type_size(p.type);
      }
      if (!is_vertex) {
        m_body += el.count * min_size;
        return;
      }
      for (size_t i = 0; i < el.count; ++i) {
        const char* base = data + m_body;
        for (size_t p = 0; p < el.properties.size(); ++p)
          m_values[p] = binary_value(base + offsets[p], el.properties[p].type);
        store_vertex(i, 0, m_body);
        m_body += min_size;
      }
      return;
    }
    for (size_t i = 0; i < el.count; ++i) {
      const size_t start = m_body;
      if (is_face) m_face.clear();
      for (size_t p = 0; p < el.properties.size(); ++p) {
        const Property& prop = el.properties[p];
        if (prop.list) {
          const size_t cs = type_size(prop.count_type);
          need(cs, el, i);
          double count = binary_value(data + m_body, prop.count_type);
          m_body += cs;
          if (count < 0)
            fail_at(m_body - cs, fmt::format("list '{}' has a negative length", prop.name));
          const size_t vs = type_size(prop.type);
          if (count > double((m_data.size() - m_body) / vs)) need(size_t(count) * vs, el, i);
          const size_t n = size_t(count);
          if (is_face && int(p) == m_layout.indices) {
            m_face.resize(n);
            for (size_t k = 0; k < n; ++k) {
              double v = binary_value(data + m_body + k * vs, prop.type);
              m_face[k] = int64_t(v);
            }
          }
          m_body += n * vs;
        } else {
          const size_t vs = type_size(prop.type);
          need(vs, el, i);
          if (is_vertex) m_values[p] = binary_value(data + m_body, prop.type);
          m_body += vs;
        }
      }
      if (is_vertex) store_vertex(i, 0, start);
      if (is_face) store_face(i, start);
    }
  }

  void need(size_t bytes, const Element& el, size_t i) const {
    if (bytes > m_data.size() - m_body)
      fail_at(m_body,
              fmt::format("the file is truncated in '{}' entry {} of {}", el.name, i, el.count));
  }

  std::string_view m_data;
  std::string m_name;
  Encoding m_encoding = Encoding::Ascii;
  std::vector<Element> m_elements;
  Layout m_layout;
  size_t m_body = 0, m_header_lines = 0;
  std::optional<TextLines> m_lines;
  std::vector<double> m_values;
  std::vector<int64_t> m_face;
  Mesh m_mesh;
};

}  // namespace

Mesh parse_ply(std::string_view bytes, const std::string& name) {
  return PlyReader(bytes, name).read();
}

size_t ply_declared_bytes(std::string_view head, const std::string& name, size_t compressed_bytes) {
  // A header longer than this is not one: say so rather than inflate on to find its end.
  constexpr size_t kMaxHeader = size_t(1) << 20;
  // The header is whole once a line of "end_header" (and spaces) has ended.
  bool whole = false;
  for (size_t at = head.find("\nend_header"); at != std::string_view::npos && !whole;
       at = head.find("\nend_header", at + 1)) {
    const size_t nl = head.find('\n', at + 1);
    if (nl == std::string_view::npos) break;
    std::string_view rest = head.substr(at + 11, nl - at - 11), tok;
    if (!rest.empty() && rest.back() == '\r') rest.remove_suffix(1);
    whole = !next_token(rest, tok);
  }
  if (!whole) {
    if (head.size() > kMaxHeader)
      fail("{}: no 'end_header' line in the first {} bytes", name, kMaxHeader);
    return 0;
  }
  const double bytes = PlyReader(head, name).declared_bytes(compressed_bytes);
  return bytes >= double(SIZE_MAX) ? SIZE_MAX : size_t(bytes);
}

std::string gzip(std::string_view bytes, int level) {
  z_stream z{};
  // 16 + MAX_WBITS: a gzip header and trailer around the deflate stream.
  if (deflateInit2(&z, level, Z_DEFLATED, 16 + MAX_WBITS, 8, Z_DEFAULT_STRATEGY) != Z_OK)
    fail("gzip: cannot start zlib");
  std::string out(deflateBound(&z, uLong(bytes.size())) + 64, '\0');
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(bytes.data()));
  z.avail_in = uInt(bytes.size());
  z.next_out = reinterpret_cast<Bytef*>(out.data());
  z.avail_out = uInt(out.size());
  const int rc = deflate(&z, Z_FINISH);
  out.resize(z.total_out);
  deflateEnd(&z);
  if (rc != Z_STREAM_END) fail("gzip: compression failed");
  return out;
}

bool is_gzip(std::string_view bytes) {
  return bytes.size() >= 2 && uint8_t(bytes[0]) == 0x1f && uint8_t(bytes[1]) == 0x8b;
}

std::string gunzip(std::string_view bytes, const std::string& name, size_t max_bytes,
                   const std::function<size_t(std::string_view head)>& declared) {
  const bool budget = max_bytes == 0;
  if (budget) max_bytes = memory_budget_bytes();
  // What the beginning of the output declares, once known, lowers the limit.
  bool by_header = false, header_known = !declared;
  z_stream z{};
  // 16 + MAX_WBITS: a gzip header and trailer around the deflate stream.
  if (inflateInit2(&z, 16 + MAX_WBITS) != Z_OK) fail("{}: cannot start zlib", name);
  std::string out;
  char buf[1 << 16];
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(bytes.data()));
  size_t left = bytes.size();
  int rc = Z_OK;
  try {
    for (;;) {
      if (z.avail_in == 0 && left > 0) {
        const uInt n = uInt(std::min<size_t>(left, 1u << 30));
        z.avail_in = n;
        left -= n;
      }
      z.next_out = reinterpret_cast<Bytef*>(buf);
      z.avail_out = sizeof buf;
      rc = inflate(&z, Z_NO_FLUSH);
      out.append(buf, sizeof buf - z.avail_out);
      if (!header_known) {
        if (const size_t d = declared(out)) {
          header_known = true;
          if (d < max_bytes) max_bytes = d, by_header = true;
        }
      }
      if (out.size() > max_bytes) {
        if (by_header)
          fail(
              "{}: decompresses to more than {} bytes, the most its header declares (its "
              "element counts times their largest entries)",
              name, max_bytes);
        if (budget)
          fail("{}: decompresses to more than {}, more than {}", name,
               format_bytes(double(max_bytes)), memory_budget_phrase());
        fail("{}: decompresses to more than {} bytes", name, max_bytes);
      }
      if (rc == Z_STREAM_END) {
        // Concatenated gzip members are one file (RFC 1952); anything else after the end is not.
        if (z.avail_in == 0 && left == 0) break;
        if (z.avail_in == 0) {
          const uInt n = uInt(std::min<size_t>(left, 1u << 30));
          z.avail_in = n;
          left -= n;
        }
        if (z.avail_in < 2 || z.next_in[0] != 0x1f || z.next_in[1] != 0x8b)
          fail("{}: data after the end of the gzip stream", name);
        inflateReset(&z);
        continue;
      }
      if (rc == Z_BUF_ERROR && z.avail_in == 0 && left == 0)
        fail(
            "{}: the gzip data is truncated (it ends after {} compressed bytes, inside the "
            "stream)",
            name, bytes.size());
      if (rc != Z_OK && rc != Z_BUF_ERROR)
        fail("{}: corrupt gzip data ({})", name, z.msg ? z.msg : "zlib error");
    }
  } catch (...) {
    inflateEnd(&z);
    throw;
  }
  inflateEnd(&z);
  return out;
}

Mesh read_ply_file(const fs::path& path) {
  const std::string file = path.string();
  std::string bytes = read_text_file(path);
  if (is_gzip(bytes))
    bytes = gunzip(bytes, file, 0, [&, compressed = bytes.size()](std::string_view head) {
      return ply_declared_bytes(head, file, compressed);
    });
  return parse_ply(bytes, file);
}

void load_ply(const fs::path& path, Scene& scene) {
  const std::string file = path.string();
  if (!fs::exists(path)) fail("{}: file not found", file);
  Mesh mesh = read_ply_file(path);
  Material m;
  m.name = "default";
  const uint32_t material = uint32_t(scene.materials.size());
  scene.materials.push_back(m);
  mesh.material.assign(mesh.triangles.size(), 0);
  mesh.light.assign(mesh.triangles.size(), -1);
  scene.mesh.append(mesh, material);
}

}  // namespace rll
