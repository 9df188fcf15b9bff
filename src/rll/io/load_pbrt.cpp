// pbrt-v4 scene files, the subset in docs/scene-format.md: transforms, attributes, object
// instances, includes, the perspective camera, film size, triangle/PLY/bilinear meshes and
// tessellated spheres and disks, the materials that map onto rll's, image textures, diffuse
// area lights, distant/point lights and infinite lights (a dome of triangles). pbrt has no
// parser library: this one is hand-written, with line tracking through included files. A
// syntax error is an error naming the file and line; a directive rll does not render is
// skipped with one warning naming it and the line.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <deque>
#include <map>
#include <optional>
#include <set>
#include <tuple>

#include "rll/core/error.h"
#include "rll/io/load.h"
#include "rll/io/text_scan.h"
#include "rll/scene/transform.h"

namespace rll {
namespace fs = std::filesystem;

namespace {

// Tessellation of pbrt's analytic shapes (documented in docs/scene-format.md).
constexpr int kSphereSegments = 48, kSphereRings = 24;  // a full sphere: 2208 triangles
constexpr int kDiskSegments = 64;
constexpr int kBilinearGrid = 8;  // a non-planar bilinear patch: 8 x 8 quads
constexpr int kInfiniteLightTriangles = 2048;
constexpr int kMaxIncludeDepth = 32;

// --- 4x4 matrices in double, as pbrt composes its transforms ---

struct Mat4 {
  double m[4][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}};
};

Mat4 operator*(const Mat4& a, const Mat4& b) {
  Mat4 r;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      double s = 0;
      for (int k = 0; k < 4; ++k) s += a.m[i][k] * b.m[k][j];
      r.m[i][j] = s;
    }
  return r;
}

// Inverse by Gauss-Jordan elimination with partial pivoting; nullopt when singular.
std::optional<Mat4> inverse(const Mat4& a) {
  double w[4][8];
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      w[i][j] = a.m[i][j];
      w[i][j + 4] = i == j ? 1 : 0;
    }
  for (int c = 0; c < 4; ++c) {
    int p = c;
    for (int r = c + 1; r < 4; ++r)
      if (std::abs(w[r][c]) > std::abs(w[p][c])) p = r;
    if (!(std::abs(w[p][c]) > 1e-300)) return std::nullopt;
    if (p != c)
      for (int j = 0; j < 8; ++j) std::swap(w[p][j], w[c][j]);
    const double d = 1 / w[c][c];
    for (int j = 0; j < 8; ++j) w[c][j] *= d;
    for (int r = 0; r < 4; ++r) {
      if (r == c || w[r][c] == 0) continue;
      const double f = w[r][c];
      for (int j = 0; j < 8; ++j) w[r][j] -= f * w[c][j];
    }
  }
  Mat4 r;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) r.m[i][j] = w[i][j + 4];
  return r;
}

Vec3 apply_point(const Mat4& t, const Vec3& p) {
  double v[3];
  for (int i = 0; i < 3; ++i)
    v[i] = t.m[i][0] * p.x + t.m[i][1] * p.y + t.m[i][2] * p.z + t.m[i][3];
  const double w = t.m[3][0] * p.x + t.m[3][1] * p.y + t.m[3][2] * p.z + t.m[3][3];
  return Vec3(to_float(v[0] / w), to_float(v[1] / w), to_float(v[2] / w));
}

Vec3 apply_vector(const Mat4& t, const Vec3& d) {
  return Vec3(to_float(t.m[0][0] * d.x + t.m[0][1] * d.y + t.m[0][2] * d.z),
              to_float(t.m[1][0] * d.x + t.m[1][1] * d.y + t.m[1][2] * d.z),
              to_float(t.m[2][0] * d.x + t.m[2][1] * d.y + t.m[2][2] * d.z));
}

Affine to_affine(const Mat4& t) {
  Affine x;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) x.a[i][j] = to_float(t.m[i][j]);
    x.t[i] = to_float(t.m[i][3]);
  }
  return x;
}

Mat4 translate(double x, double y, double z) {
  Mat4 r;
  r.m[0][3] = x;
  r.m[1][3] = y;
  r.m[2][3] = z;
  return r;
}

Mat4 scale(double x, double y, double z) {
  Mat4 r;
  r.m[0][0] = x;
  r.m[1][1] = y;
  r.m[2][2] = z;
  return r;
}

// Rotation by `deg` degrees about `axis` (pbrt's Rotate).
Mat4 rotate(double deg, double ax, double ay, double az) {
  const double len = std::sqrt(ax * ax + ay * ay + az * az);
  ax /= len;
  ay /= len;
  az /= len;
  const double th = deg * (3.14159265358979323846 / 180), c = std::cos(th), s = std::sin(th),
               k = 1 - c;
  Mat4 r;
  r.m[0][0] = ax * ax * k + c;
  r.m[0][1] = ax * ay * k - az * s;
  r.m[0][2] = ax * az * k + ay * s;
  r.m[1][0] = ay * ax * k + az * s;
  r.m[1][1] = ay * ay * k + c;
  r.m[1][2] = ay * az * k - ax * s;
  r.m[2][0] = az * ax * k - ay * s;
  r.m[2][1] = az * ay * k + ax * s;
  r.m[2][2] = az * az * k + c;
  return r;
}

// --- spectra as RGB ---

// Complex indices of refraction of pbrt's named metal spectra, reduced to RGB.
struct NamedMetal {
  const char* name;
  Rgb eta, k;
};
constexpr NamedMetal kMetals[] = {
    {"Cu", {0.200438f, 0.924033f, 1.10221f}, {3.91295f, 2.45285f, 2.14219f}},
    {"Au", {0.143119f, 0.374957f, 1.44248f}, {3.98316f, 2.38572f, 1.60322f}},
    {"Ag", {0.155265f, 0.116723f, 0.138342f}, {4.82835f, 3.12225f, 2.14696f}},
    {"Al", {1.65746f, 0.880369f, 0.521229f}, {9.22387f, 6.26952f, 4.837f}},
    {"CuZn", {0.444f, 0.527f, 1.094f}, {3.695f, 2.765f, 1.829f}},
};

// The colour of a blackbody at `kelvin`, in linear sRGB with luminance 1 (pbrt-v4 normalizes
// a blackbody emitter to one nit before `scale`). The CIE 1931 matching functions are the
// multi-lobe Gaussian fit of Wyman, Sloan and Shirley (2013).
Rgb blackbody_rgb(double kelvin) {
  auto g = [](double l, double mu, double s1, double s2) {
    const double t = (l - mu) / (l < mu ? s1 : s2);
    return std::exp(-0.5 * t * t);
  };
  double X = 0, Y = 0, Z = 0;
  for (double l = 360; l <= 830; l += 1) {
    const double lm = l * 1e-9, c = 299792458.0, h = 6.62606957e-34, kb = 1.3806488e-23;
    const double le =
        2 * h * c * c / (std::pow(lm, 5) * (std::exp(h * c / (lm * kb * kelvin)) - 1));
    X += le * (1.056 * g(l, 599.8, 37.9, 31.0) + 0.362 * g(l, 442.0, 16.0, 26.7) -
               0.065 * g(l, 501.1, 20.4, 26.2));
    Y += le * (0.821 * g(l, 568.8, 46.9, 40.5) + 0.286 * g(l, 530.9, 16.3, 31.1));
    Z += le * (1.217 * g(l, 437.0, 11.8, 36.0) + 0.681 * g(l, 459.0, 26.0, 13.8));
  }
  X /= Y;
  Z /= Y;
  Y = 1;
  Rgb c(to_float(3.2406 * X - 1.5372 * Y - 0.4986 * Z),
        to_float(-0.9689 * X + 1.8758 * Y + 0.0415 * Z),
        to_float(0.0557 * X - 0.2040 * Y + 1.0570 * Z));
  return max(c, Rgb(0));
}

// --- tokens ---

struct Token {
  std::string_view text;  // without the quotes of a string
  size_t line = 0;
  uint32_t file = 0;  // index into the parser's file names
  bool quoted = false;
};

// Splits one file's text into tokens: quoted strings, [ and ], and runs of other characters;
// '#' starts a comment to the end of the line.
class Tokenizer {
 public:
  // `included_from` comes before the file in messages: "a.pbrt:3: Include: ".
  Tokenizer(std::string_view text, uint32_t file, const std::string& name,
            const std::string& included_from)
      : m_text(text), m_file(file), m_name(name), m_included_from(included_from) {}

  bool next(Token& t) {
    const size_t n = m_text.size();
    for (;;) {
      while (m_pos < n && is_space(m_text[m_pos])) {
        if (m_text[m_pos] == '\n') ++m_line;
        ++m_pos;
      }
      if (m_pos >= n) return false;
      if (m_text[m_pos] != '#') break;
      while (m_pos < n && m_text[m_pos] != '\n') ++m_pos;
    }
    t.line = m_line;
    t.file = m_file;
    t.quoted = false;
    const char c = m_text[m_pos];
    if (c == '"') {
      const size_t start = ++m_pos;
      while (m_pos < n && m_text[m_pos] != '"') {
        if (m_text[m_pos] == '\n')
          fail("{}{}:{}: a string runs past the end of the line", m_included_from, m_name,
               t.line);
        if (m_text[m_pos] == '\\') ++m_pos;  // an escaped character, whatever it is
        ++m_pos;
      }
      if (m_pos >= n)
        fail("{}{}:{}: a string is not closed", m_included_from, m_name, t.line);
      t.text = m_text.substr(start, m_pos - start);
      t.quoted = true;
      ++m_pos;
      return true;
    }
    if (c == '[' || c == ']') {
      t.text = m_text.substr(m_pos++, 1);
      return true;
    }
    const size_t start = m_pos;
    while (m_pos < n && !is_space(m_text[m_pos]) && m_text[m_pos] != '"' && m_text[m_pos] != '[' &&
           m_text[m_pos] != ']' && m_text[m_pos] != '#')
      ++m_pos;
    t.text = m_text.substr(start, m_pos - start);
    return true;
  }

 private:
  static bool is_space(char c) {
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v';
  }
  std::string_view m_text;
  size_t m_pos = 0, m_line = 1;
  uint32_t m_file;
  std::string m_name, m_included_from;
};

std::string unescape(std::string_view s) {
  std::string r;
  r.reserve(s.size());
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] != '\\' || i + 1 == s.size()) {
      r += s[i];
      continue;
    }
    switch (char e = s[++i]) {
      case 'n':
        r += '\n';
        break;
      case 't':
        r += '\t';
        break;
      case 'r':
        r += '\r';
        break;
      case 'b':
        r += '\b';
        break;
      case 'f':
        r += '\f';
        break;
      default:
        r += e;
        break;
    }
  }
  return r;
}

// --- parameter lists ---

struct Param {
  std::string type, name;
  std::vector<double> numbers;
  std::vector<std::string> strings;  // string, texture, bool and named-spectrum values
  size_t line = 0;
  mutable bool used = false;
};

constexpr const char* kParamTypes[] = {
    "integer", "float", "point2", "vector2",  "point3",    "vector3", "normal3", "normal", "point",
    "vector",  "rgb",   "color",  "spectrum", "blackbody", "bool",    "string",  "texture"};

bool is_numeric_type(const std::string& t) {
  return t != "bool" && t != "string" && t != "texture";
}

const std::set<std::string_view>& pbrt_directives() {
  static const std::set<std::string_view> names = {"Accelerator",
                                                   "ActiveTransform",
                                                   "AreaLightSource",
                                                   "Attribute",
                                                   "AttributeBegin",
                                                   "AttributeEnd",
                                                   "Camera",
                                                   "ColorSpace",
                                                   "ConcatTransform",
                                                   "CoordinateSystem",
                                                   "CoordSysTransform",
                                                   "Film",
                                                   "Identity",
                                                   "Import",
                                                   "Include",
                                                   "Integrator",
                                                   "LightSource",
                                                   "LookAt",
                                                   "MakeNamedMaterial",
                                                   "MakeNamedMedium",
                                                   "Material",
                                                   "MediumInterface",
                                                   "NamedMaterial",
                                                   "ObjectBegin",
                                                   "ObjectEnd",
                                                   "ObjectInstance",
                                                   "Option",
                                                   "PixelFilter",
                                                   "ReverseOrientation",
                                                   "Rotate",
                                                   "Sampler",
                                                   "Scale",
                                                   "Shape",
                                                   "Texture",
                                                   "Transform",
                                                   "TransformBegin",
                                                   "TransformEnd",
                                                   "TransformTimes",
                                                   "Translate",
                                                   "WorldBegin",
                                                   "WorldEnd"};
  return names;
}

struct GraphicsState {
  Mat4 ctm;           // object to world (before WorldBegin: world to camera)
  int material = -1;  // index into the scene's materials; -1: pbrt's default diffuse
  bool reverse_orientation = false;
  bool emissive = false;  // an AreaLightSource is active
  Rgb emission;
  bool two_sided = false;
};

struct ImageTexture {
  int index = -1;  // into Scene::textures
  float scale = 1;
};

// One ObjectBegin/End block: its triangles, in the world space of their definition.
struct ObjectMesh {
  Mesh mesh;
};

class PbrtReader {
 public:
  PbrtReader(const fs::path& base_dir, Scene& scene, const ReadPolicy& policy)
      : m_base(base_dir), m_scene(scene), m_policy(policy) {}

  void read(std::string_view text, const std::string& name) {
    std::string key;
    if (m_policy.read_files) {
      std::error_code ec;
      fs::path canon = fs::weakly_canonical(name, ec);
      key = ec ? name : canon.string();
    }
    push_file(text, name, key, "");
    m_scene.width = 1280;  // pbrt's default film
    m_scene.height = 720;
    while (auto t = take()) directive(*t);
    if (!m_stack.empty())
      fail("{}: {} AttributeBegin without AttributeEnd (the first at line {})", name,
           m_stack.size(), m_stack.front().line);
    if (m_object) fail("{}: ObjectBegin \"{}\" without ObjectEnd", name, m_object_name);
    finish();
  }

 private:
  // --- token stream across included files ---

  void push_file(std::string_view text, const std::string& name, const std::string& key,
                 const std::string& included_from) {
    if (m_tokenizers.size() >= size_t(kMaxIncludeDepth))
      fail("{}: includes nested more than {} deep", name, kMaxIncludeDepth);
    m_names.push_back(name);
    m_included_from.push_back(included_from);
    m_begun.push_back(false);
    m_tokenizers.emplace_back(text, uint32_t(m_names.size() - 1), name, included_from);
    m_open.push_back(key);
  }

  std::optional<Token> take() {
    if (m_peeked) {
      auto t = m_peeked;
      m_peeked.reset();
      return t;
    }
    Token t;
    while (!m_tokenizers.empty()) {
      if (m_tokenizers.back().next(t)) return t;
      m_tokenizers.pop_back();
      m_open.pop_back();
    }
    return std::nullopt;
  }

  const Token* peek() {
    if (!m_peeked) m_peeked = take();
    return m_peeked ? &*m_peeked : nullptr;
  }

  std::string where(const Token& t) const { return where(t.file, t.line); }
  std::string where(size_t file, size_t line) const {
    return fmt::format("{}{}:{}", m_included_from[file], m_names[file], line);
  }

  [[noreturn]] void syntax(const Token& t, const std::string& what) const {
    fail("{}: {}", where(t), what);
  }

  void warn(const std::string& key, const std::string& message) {
    auto it = m_warning_index.find(key);
    if (it != m_warning_index.end()) {
      ++m_warnings[it->second].second;
      return;
    }
    m_warning_index[key] = m_warnings.size();
    m_warnings.push_back({message, 1});
  }

  bool is_directive(const Token& t) const {
    return !t.quoted && !t.text.empty() && std::isalpha(static_cast<unsigned char>(t.text[0])) &&
           t.text != "true" && t.text != "false";
  }

  double number(const Token& t) const {
    if (t.quoted) syntax(t, fmt::format("expected a number, got \"{}\"", printable(t.text)));
    float f = 0;
    switch (parse_float(t.text, f)) {
      case NumberStatus::Ok:
        return f;
      case NumberStatus::NonFinite:
        syntax(t, fmt::format("'{}' is not a finite number", printable(t.text)));
      case NumberStatus::Malformed:
        break;
    }
    syntax(t, fmt::format("expected a number, got '{}'", printable(t.text)));
  }

  Token expect_token(const Token& after, const char* what) {
    auto t = take();
    if (!t) fail("{}: the file ends where {} was expected", where(after), what);
    return *t;
  }

  double expect_number(const Token& after) { return number(expect_token(after, "a number")); }

  std::string expect_string(const Token& after) {
    Token t = expect_token(after, "a quoted string");
    if (!t.quoted)
      syntax(t, fmt::format("expected a quoted string, got '{}'", printable(t.text)));
    return unescape(t.text);
  }

  // Numbers in [ ... ] (or, where `bare` is set, the same count without brackets).
  std::vector<double> number_list(const Token& after, size_t count, bool bare) {
    std::vector<double> v;
    const Token* p = peek();
    const bool bracket = p && !p->quoted && p->text == "[";
    if (!bracket && !bare) fail("{}: expected [ and {} numbers", where(after), count);
    if (bracket) take();
    while (v.size() < count) v.push_back(expect_number(after));
    if (bracket) {
      Token close = expect_token(after, "]");
      if (close.quoted || close.text != "]")
        syntax(close, fmt::format("expected ] after {} numbers", count));
    }
    return v;
  }

  std::vector<Param> param_list() {
    std::vector<Param> params;
    while (const Token* p = peek()) {
      if (!p->quoted) break;
      Token decl = *take();
      std::string_view rest = decl.text, type, name, extra;
      if (!next_token(rest, type) || !next_token(rest, name) || next_token(rest, extra))
        syntax(decl, fmt::format("expected a parameter declaration \"TYPE NAME\", got \"{}\"",
                                 printable(decl.text)));
      Param par;
      par.type = std::string(type);
      par.name = std::string(name);
      par.line = decl.line;
      if (std::find(std::begin(kParamTypes), std::end(kParamTypes), par.type) ==
          std::end(kParamTypes))
        syntax(decl, fmt::format("unknown parameter type '{}'", printable(par.type)));
      for (const auto& q : params)
        if (q.name == par.name)
          syntax(decl, fmt::format("parameter '{}' given twice", printable(par.name)));
      Token v = expect_token(decl, "a parameter value");
      auto add_value = [&](const Token& t) {
        if (t.quoted) {
          par.strings.push_back(unescape(t.text));
        } else if (t.text == "true" || t.text == "false") {
          par.strings.push_back(std::string(t.text));
        } else if (is_directive(t) || t.text == "[" || t.text == "]") {
          syntax(t, fmt::format("parameter '{}' has a bad value '{}'", printable(par.name),
                                printable(t.text)));
        } else {
          par.numbers.push_back(number(t));
        }
      };
      if (!v.quoted && v.text == "[") {
        for (;;) {
          Token t = expect_token(decl, "]");
          if (!t.quoted && t.text == "]") break;
          add_value(t);
        }
      } else {
        add_value(v);
      }
      const bool numeric = is_numeric_type(par.type);
      if (par.type == "spectrum" && par.numbers.empty() && par.strings.size() == 1) {
        // a named spectrum or a file
      } else if (numeric ? !par.strings.empty() : !par.numbers.empty()) {
        syntax(decl,
               fmt::format("parameter \"{} {}\" has values of the wrong kind", par.type, par.name));
      }
      if (par.type == "bool")
        for (const auto& s : par.strings)
          if (s != "true" && s != "false")
            syntax(decl, fmt::format("bool parameter '{}' must be true or false (got \"{}\")",
                                     par.name, s));
      if (par.numbers.empty() && par.strings.empty())
        syntax(decl, fmt::format("parameter '{}' has no value", par.name));
      params.push_back(std::move(par));
    }
    return params;
  }

  // --- typed parameter access ---

  class Params {
   public:
    Params(PbrtReader& r, const Token& directive, std::string what, std::vector<Param> params)
        : m_r(r), m_at(directive), m_what(std::move(what)), m_params(std::move(params)) {}
    ~Params() = default;

    const Param* find(const char* name) const {
      for (const auto& p : m_params)
        if (p.name == name) {
          p.used = true;
          return &p;
        }
      return nullptr;
    }
    [[noreturn]] void bad(const Param& p, const std::string& what) const {
      fail("{}: {}: parameter \"{} {}\" {}", m_r.where(m_at.file, p.line), m_what, p.type, p.name,
           what);
    }
    const Param* typed(const char* name, std::initializer_list<const char*> types) const {
      const Param* p = find(name);
      if (!p) return nullptr;
      for (const char* t : types)
        if (p->type == t) return p;
      std::string list;
      for (const char* t : types) list += (list.empty() ? "" : " or ") + std::string(t);
      bad(*p, fmt::format("must be of type {}", list));
    }
    double one_number(const Param& p) const {
      if (p.numbers.size() != 1) bad(p, fmt::format("needs 1 value (got {})", p.numbers.size()));
      return p.numbers[0];
    }
    float get_float(const char* name, float def) const {
      const Param* p = typed(name, {"float"});
      return p ? float(one_number(*p)) : def;
    }
    int get_int(const char* name, int def) const {
      const Param* p = typed(name, {"integer"});
      if (!p) return def;
      const double v = one_number(*p);
      if (v != std::floor(v) || std::abs(v) > 2147483647.0) bad(*p, "must be an integer");
      return int(v);
    }
    bool get_bool(const char* name, bool def) const {
      const Param* p = typed(name, {"bool"});
      if (!p) return def;
      if (p->strings.size() != 1) bad(*p, "needs 1 value");
      return p->strings[0] == "true";
    }
    std::optional<std::string> get_string(const char* name) const {
      const Param* p = typed(name, {"string"});
      if (!p) return std::nullopt;
      if (p->strings.size() != 1) bad(*p, "needs 1 value");
      return p->strings[0];
    }
    std::optional<std::string> get_texture(const char* name) const {
      const Param* p = find(name);
      if (!p || p->type != "texture") return std::nullopt;
      if (p->strings.size() != 1) bad(*p, "needs 1 value");
      return p->strings[0];
    }
    std::optional<Vec3> get_point(const char* name) const {
      const Param* p = typed(name, {"point3", "point", "vector3", "vector", "normal3", "normal"});
      if (!p) return std::nullopt;
      if (p->numbers.size() != 3)
        bad(*p, fmt::format("needs 3 values (got {})", p->numbers.size()));
      return Vec3(float(p->numbers[0]), float(p->numbers[1]), float(p->numbers[2]));
    }
    // All values of a numeric array parameter, in groups of `group`.
    const std::vector<double>* get_array(const char* name, std::initializer_list<const char*> types,
                                         size_t group) const {
      const Param* p = typed(name, types);
      if (!p) return nullptr;
      if (p->numbers.size() % group != 0)
        bad(*p, fmt::format("needs a multiple of {} values (got {})", group, p->numbers.size()));
      return &p->numbers;
    }
    // A colour: rgb, blackbody, or spectrum (a named one, or wavelength-value pairs reduced to
    // their mean).
    std::optional<Rgb> get_spectrum(const char* name) const {
      const Param* p = find(name);
      if (!p) return std::nullopt;
      if (p->type == "rgb" || p->type == "color") {
        if (p->numbers.size() != 3)
          bad(*p, fmt::format("needs 3 values (got {})", p->numbers.size()));
        Rgb c(float(p->numbers[0]), float(p->numbers[1]), float(p->numbers[2]));
        if (min_component(c) < 0) bad(*p, "must not be negative");
        return c;
      }
      if (p->type == "blackbody") {
        const double t = one_number(*p);
        const Rgb c = t > 0 ? blackbody_rgb(t) : Rgb(0);
        if (!(t > 0) || !is_finite(c) || !(luminance(c) > 0))
          bad(*p, "needs a positive temperature at which a blackbody glows");
        return c;
      }
      if (p->type == "float") {  // pbrt-v4 accepts a float for a spectrum in some places
        const float v = float(one_number(*p));
        return Rgb(v);
      }
      if (p->type != "spectrum") bad(*p, "must be of type rgb, spectrum or blackbody");
      if (!p->strings.empty()) {
        const std::string& s = p->strings[0];
        for (const auto& m : kMetals) {
          if (s == fmt::format("metal-{}-eta", m.name)) return m.eta;
          if (s == fmt::format("metal-{}-k", m.name)) return m.k;
        }
        if (s.rfind("stdillum-", 0) == 0 || s.rfind("illum-", 0) == 0) return Rgb(1);
        if (s == "glass-BK7") return Rgb(1.5168f);
        if (s.rfind("glass-", 0) == 0) return Rgb(1.5f);
        m_r.warn(
            "spectrum " + s,
            fmt::format("{}: {}: spectrum \"{}\" is not one rll knows; parameter '{}' keeps its "
                        "default",
                        m_r.where(m_at.file, p->line), m_what, s, p->name));
        return std::nullopt;
      }
      if (p->numbers.size() < 2 || p->numbers.size() % 2 != 0)
        bad(*p, "needs wavelength-value pairs");
      double sum = 0;
      for (size_t i = 1; i < p->numbers.size(); i += 2) sum += p->numbers[i];
      const float mean = to_float(sum / double(p->numbers.size() / 2));
      return Rgb(std::max(0.0f, mean));
    }
    void warn_unused() const {
      for (const auto& p : m_params)
        if (!p.used)
          m_r.warn(m_what + " param " + p.name,
                   fmt::format("{}: {}: parameter \"{} {}\" is not supported; ignored",
                               m_r.where(m_at.file, p.line), m_what, p.type, p.name));
    }

   private:
    PbrtReader& m_r;
    Token m_at;
    std::string m_what;
    std::vector<Param> m_params;
  };

  // Skips the arguments of a directive rll does not render, up to the next directive.
  void skip_arguments() {
    int depth = 0;
    while (const Token* p = peek()) {
      if (is_directive(*p) && depth == 0) break;
      Token t = *take();
      if (!t.quoted && t.text == "[") ++depth;
      if (!t.quoted && t.text == "]" && --depth < 0) syntax(t, "] without [");
    }
  }

  void unsupported(const Token& t, const std::string& what) {
    warn(what, fmt::format("{}: {} is not supported; skipped", where(t), what));
  }

  // --- directives ---

  void directive(const Token& t) {
    const std::string_view d = t.text;
    const bool known = !t.quoted && is_directive(t) && pbrt_directives().count(d);
    // An included file that does not begin with a directive is not a pbrt file at all (say,
    // Include "/etc/passwd"): its content stays out of the message.
    if (!known && !m_begun[t.file] && !m_included_from[t.file].empty())
      syntax(t, "this is not a pbrt file (it does not begin with a pbrt directive)");
    m_begun[t.file] = true;
    if (t.quoted)
      syntax(t, fmt::format("expected a directive, got \"{}\"", printable(t.text)));
    if (!is_directive(t))
      syntax(t, fmt::format("expected a directive, got '{}'", printable(t.text)));
    if (!known) syntax(t, fmt::format("unknown directive '{}'", printable(d)));
    GraphicsState& g = m_state;
    if (d == "Identity") {
      g.ctm = Mat4();
    } else if (d == "Translate") {
      auto v = number_list(t, 3, true);
      concat(t, translate(v[0], v[1], v[2]));
    } else if (d == "Scale") {
      auto v = number_list(t, 3, true);
      concat(t, scale(v[0], v[1], v[2]));
    } else if (d == "Rotate") {
      auto v = number_list(t, 4, true);
      if (v[1] == 0 && v[2] == 0 && v[3] == 0) syntax(t, "Rotate needs a non-zero axis");
      concat(t, rotate(v[0], v[1], v[2], v[3]));
    } else if (d == "LookAt") {
      auto v = number_list(t, 9, true);
      look_at(t, v);
    } else if (d == "Transform" || d == "ConcatTransform") {
      auto v = number_list(t, 16, false);
      Mat4 m;  // pbrt lists the matrix column by column
      for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) m.m[j][i] = v[size_t(i * 4 + j)];
      if (d == "Transform") {
        g.ctm = Mat4();
        concat(t, m);
      } else {
        concat(t, m);
      }
    } else if (d == "CoordinateSystem") {
      m_named_frames[expect_string(t)] = g.ctm;
    } else if (d == "CoordSysTransform") {
      std::string name = expect_string(t);
      auto it = m_named_frames.find(name);
      if (it == m_named_frames.end())
        warn("coordsys " + name,
             fmt::format("{}: CoordSysTransform: no coordinate system named \"{}\"; ignored",
                         where(t), name));
      else
        g.ctm = it->second;
    } else if (d == "AttributeBegin" || d == "TransformBegin") {
      m_stack.push_back({g, d == "TransformBegin", t.line});
    } else if (d == "AttributeEnd" || d == "TransformEnd") {
      if (m_stack.empty()) syntax(t, fmt::format("{} without a matching begin", d));
      Saved s = m_stack.back();
      m_stack.pop_back();
      if (s.transform_only)
        g.ctm = s.state.ctm;
      else
        g = s.state;
    } else if (d == "ReverseOrientation") {
      g.reverse_orientation = !g.reverse_orientation;
    } else if (d == "WorldBegin") {
      g.ctm = Mat4();
      m_named_frames["world"] = g.ctm;
    } else if (d == "WorldEnd") {
      // pbrt-v3's end of the scene: nothing to do
    } else if (d == "Include" || d == "Import") {
      include(t);
    } else if (d == "Camera") {
      camera(t);
    } else if (d == "Film") {
      film(t);
    } else if (d == "Material") {
      std::string type = expect_string(t);
      Params p(*this, t, fmt::format("Material \"{}\"", type), param_list());
      g.material = make_material(t, type, p);
      p.warn_unused();
    } else if (d == "MakeNamedMaterial") {
      std::string name = expect_string(t);
      Params p(*this, t, fmt::format("MakeNamedMaterial \"{}\"", name), param_list());
      auto type = p.get_string("type");
      if (!type) fail("{}: MakeNamedMaterial \"{}\" needs a \"string type\"", where(t), name);
      if (m_named_materials.count(name))
        syntax(t, fmt::format("named material \"{}\" defined twice", name));
      m_named_materials[name] = make_material(t, *type, p);
      p.warn_unused();
    } else if (d == "NamedMaterial") {
      std::string name = expect_string(t);
      auto it = m_named_materials.find(name);
      if (it == m_named_materials.end())
        syntax(t, fmt::format("NamedMaterial \"{}\" was not defined", name));
      g.material = it->second;
    } else if (d == "Texture") {
      texture(t);
    } else if (d == "AreaLightSource") {
      area_light(t);
    } else if (d == "LightSource") {
      light(t);
    } else if (d == "Shape") {
      shape(t);
    } else if (d == "ObjectBegin") {
      std::string name = expect_string(t);
      if (m_object) syntax(t, "ObjectBegin inside another ObjectBegin");
      m_stack.push_back({g, false, t.line});
      m_object = true;
      m_object_name = name;
      m_object_triangle = m_scene.mesh.triangle_count();
      m_object_vertex = m_scene.mesh.positions.size();
    } else if (d == "ObjectEnd") {
      if (!m_object) syntax(t, "ObjectEnd without ObjectBegin");
      end_object();
      if (m_stack.empty()) syntax(t, "ObjectEnd without ObjectBegin");
      g = m_stack.back().state;
      m_stack.pop_back();
    } else if (d == "ObjectInstance") {
      std::string name = expect_string(t);
      if (m_object) syntax(t, "ObjectInstance inside ObjectBegin");
      auto it = m_objects.find(name);
      if (it == m_objects.end())
        syntax(t, fmt::format("ObjectInstance \"{}\": no such object", name));
      instance(t, it->second);
    } else {
      // Rendering settings and features rll does not have: Sampler, Integrator, PixelFilter,
      // Accelerator, ColorSpace, Option, Attribute, media, motion blur.
      unsupported(t, std::string(d));
      skip_arguments();
    }
  }

  void concat(const Token& t, const Mat4& m) {
    m_state.ctm = m_state.ctm * m;
    for (const auto& row : m_state.ctm.m)
      for (double v : row)
        if (!std::isfinite(v)) syntax(t, "the transform is not finite");
  }

  void look_at(const Token& t, const std::vector<double>& v) {
    const Vec3 pos{float(v[0]), float(v[1]), float(v[2])},
        look{float(v[3]), float(v[4]), float(v[5])}, up{float(v[6]), float(v[7]), float(v[8])};
    if (!(length_sq(look - pos) > 0))
      syntax(t, "LookAt: the eye and the target are the same point");
    const Vec3 dir = normalize(look - pos);
    if (!(length_sq(up) > 0) || !(length_sq(cross(normalize(up), dir)) > 0))
      syntax(t, "LookAt: the up vector is zero or parallel to the viewing direction");
    const Vec3 right = normalize(cross(normalize(up), dir)), new_up = cross(dir, right);
    Mat4 world_from_camera;
    const Vec3 cols[4] = {right, new_up, dir, pos};
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 3; ++r) world_from_camera.m[r][c] = cols[c][r];
    auto camera_from_world = inverse(world_from_camera);
    if (!camera_from_world) syntax(t, "LookAt: degenerate");
    concat(t, *camera_from_world);
  }

  fs::path resolve(const std::string& name) const {
    fs::path p(name);
    return (p.is_absolute() ? p : m_base / p).lexically_normal();
  }

  // A file the scene refers to: it must exist, and reading files must be allowed.
  fs::path referenced_file(const Token& t, const std::string& what, const std::string& name) const {
    if (name.empty()) syntax(t, fmt::format("{}: empty file name", what));
    if (!m_policy.read_files)
      syntax(t, fmt::format("{}: '{}': reading other files is turned off", what, printable(name)));
    fs::path p = resolve(name);
    if (const std::string why = unreadable_reason(p); !why.empty())
      syntax(t, fmt::format("{}: '{}' {} ({})", what, printable(name), why,
                            printable(p.string(), 256)));
    return p;
  }

  void include(const Token& t) {
    const std::string name = expect_string(t);
    const fs::path p = referenced_file(t, std::string(t.text), name);
    std::error_code ec;
    fs::path canon = fs::weakly_canonical(p, ec);
    const std::string key = (ec ? p : canon).string();
    if (std::find(m_open.begin(), m_open.end(), key) != m_open.end())
      syntax(t, fmt::format("{} \"{}\" includes a file that is already being read (recursive "
                            "include)",
                            t.text, printable(name)));
    if (m_tokenizers.size() >= size_t(kMaxIncludeDepth))
      syntax(t, fmt::format("includes nested more than {} deep", kMaxIncludeDepth));
    m_texts.push_back(read_text_file(p));
    // The peeked token (if any) belongs to the including file: tokens of the included file
    // must come first, so the peek is pushed back by re-reading after the include.
    if (m_peeked) syntax(t, "internal: token pending at an include");
    push_file(m_texts.back(), p.string(), key, fmt::format("{}:{}: {}: ", m_names[t.file], t.line, t.text));
  }

  void camera(const Token& t) {
    std::string type = expect_string(t);
    Params p(*this, t, fmt::format("Camera \"{}\"", type), param_list());
    m_named_frames["camera"] = inverse(m_state.ctm).value_or(Mat4());
    if (type != "perspective") {
      unsupported(t, fmt::format("Camera \"{}\"", type));
      return;
    }
    auto world_from_camera = inverse(m_state.ctm);
    if (!world_from_camera) syntax(t, "Camera: the camera transform is singular");
    m_camera_fov = p.get_float("fov", 90);
    if (!(m_camera_fov > 0 && m_camera_fov < 180))
      syntax(t, fmt::format("Camera: fov must be in (0, 180) degrees (got {})", m_camera_fov));
    if (p.get_float("lensradius", 0) > 0)
      warn("lensradius", fmt::format("{}: Camera: depth of field (lensradius) is not supported; "
                                     "rendered as a pinhole",
                                     where(t)));
    p.find("focaldistance");
    m_world_from_camera = *world_from_camera;
    m_has_camera = true;
    p.warn_unused();
  }

  void film(const Token& t) {
    std::string type = expect_string(t);
    Params p(*this, t, fmt::format("Film \"{}\"", type), param_list());
    const int w = p.get_int("xresolution", 1280), h = p.get_int("yresolution", 720);
    if (w <= 0 || h <= 0 || w > 65536 || h > 65536)
      syntax(t, fmt::format("Film: resolution {}x{} is out of range", w, h));
    m_scene.width = w;
    m_scene.height = h;
    // Output settings that do not change the image rll renders.
    for (const char* name : {"filename", "iso", "whitebalance", "sensor", "exposuretime",
                             "savefp16", "maxcomponentvalue", "diagonal", "writefp16"})
      p.find(name);
    p.warn_unused();
  }

  // --- materials and textures ---

  // pbrt's roughness to a GGX alpha: "remaproughness" (the default) takes the square root.
  static float alpha_of(const Params& p, float def = 0) {
    float r = p.get_float("roughness", def);
    const float u = p.get_float("uroughness", r), v = p.get_float("vroughness", r);
    r = 0.5f * (u + v);  // rll's GGX is isotropic
    if (r < 0) r = 0;
    return p.get_bool("remaproughness", true) ? std::sqrt(r) : r;
  }

  // The reflectance of a material: a colour, or an image texture (times its scale).
  void reflectance(const Token& t, const Params& p, const char* name, Material& m, Rgb def) {
    m.albedo = def;
    if (auto tex = p.get_texture(name)) {
      auto it = m_textures.find(*tex);
      if (it == m_textures.end()) {
        warn("texture " + *tex, fmt::format("{}: texture \"{}\" is not an image texture rll read; "
                                            "the material uses its default",
                                            where(t), *tex));
        return;
      }
      m.albedo = Rgb(it->second.scale);
      m.albedo_texture = it->second.index;
      return;
    }
    if (auto c = p.get_spectrum(name)) m.albedo = *c;
  }

  int make_material(const Token& t, const std::string& type, const Params& p) {
    Material m;
    m.name = fmt::format("{} (line {})", type, t.line);
    p.find("normalmap");
    p.find("displacement");
    if (type == "diffuse") {
      m.type = MaterialType::Diffuse;
      reflectance(t, p, "reflectance", m, Rgb(0.5f));
    } else if (type == "coateddiffuse") {
      m.type = MaterialType::Plastic;
      reflectance(t, p, "reflectance", m, Rgb(0.5f));
      m.roughness = alpha_of(p);
      m.ior = p.get_float("eta", 1.5f);
      m.specular = Rgb(1);
      for (const char* name : {"thickness", "albedo", "g", "maxdepth", "nsamples"}) p.find(name);
    } else if (type == "conductor" || type == "coatedconductor") {
      m.type = MaterialType::Conductor;
      const std::string prefix = type == "conductor" ? "" : "conductor.";
      m.eta = kMetals[0].eta;  // pbrt's default metal is copper
      m.k = kMetals[0].k;
      if (auto e = p.get_spectrum((prefix + "eta").c_str())) m.eta = max(*e, Rgb(1e-3f));
      if (auto k = p.get_spectrum((prefix + "k").c_str())) m.k = *k;
      if (auto r = p.get_spectrum("reflectance")) {
        // Reflectance instead of eta/k: a near-white metal tinted by it.
        m.eta = kTintableEta;
        m.k = kTintableK;
        m.specular = *r;
      }
      if (type == "conductor") {
        m.roughness = alpha_of(p);
      } else {
        float r = p.get_float("conductor.roughness", 0);
        r = 0.5f *
            (p.get_float("conductor.uroughness", r) + p.get_float("conductor.vroughness", r));
        m.roughness = p.get_bool("remaproughness", true) ? std::sqrt(std::max(0.0f, r)) : r;
        warn("coatedconductor", fmt::format("{}: Material \"coatedconductor\" is rendered as its "
                                            "conductor without the coating",
                                            where(t)));
        for (const char* name : {"interface.eta", "interface.roughness", "interface.uroughness",
                                 "interface.vroughness", "thickness", "albedo", "g"})
          p.find(name);
      }
    } else if (type == "dielectric" || type == "thindielectric") {
      // rll has no transmission: the nearest material is the dielectric's reflection alone, a
      // clear coating over black.
      m.type = MaterialType::Plastic;
      m.albedo = Rgb(0);
      m.specular = Rgb(1);
      float eta = 1.5f;
      if (const Param* e = p.find("eta")) {
        if (e->type == "float")
          eta = float(p.one_number(*e));
        else if (auto c = p.get_spectrum("eta"))
          eta = c->y;
      }
      m.ior = std::max(1.0f, eta);
      m.roughness = alpha_of(p);
      warn("dielectric", fmt::format("{}: Material \"{}\": rll has no transmission, so glass is "
                                     "rendered as its reflection alone (a clear coating over "
                                     "black)",
                                     where(t), type));
    } else if (type == "interface") {
      warn("interface", fmt::format("{}: Material \"interface\" (an invisible medium boundary) "
                                    "is not supported; its shapes are skipped",
                                    where(t)));
      return kInvisible;
    } else {
      warn("material " + type,
           fmt::format("{}: Material \"{}\" is not supported; rendered as diffuse grey 0.5",
                       where(t), type));
      m.albedo = Rgb(0.5f);
      p.find("reflectance");
    }
    m_scene.materials.push_back(m);
    return int(m_scene.materials.size() - 1);
  }

  void texture(const Token& t) {
    const std::string name = expect_string(t), kind = expect_string(t), cls = expect_string(t);
    Params p(*this, t, fmt::format("Texture \"{}\"", name), param_list());
    if (kind != "spectrum" && kind != "color" && kind != "rgb") {
      // Float textures (bump, roughness, alpha maps) have no use in rll.
      unsupported(t, fmt::format("Texture of type \"{}\"", kind));
      return;
    }
    if (cls != "imagemap") {
      unsupported(t, fmt::format("Texture class \"{}\"", cls));
      return;
    }
    auto file = p.get_string("filename");
    if (!file) fail("{}: Texture \"{}\": imagemap needs a \"string filename\"", where(t), name);
    const fs::path path = referenced_file(t, "Texture", *file);
    std::string encoding = p.get_string("encoding").value_or("sRGB");
    if (encoding != "sRGB" && encoding != "linear") {
      warn("encoding " + encoding,
           fmt::format("{}: Texture: encoding \"{}\" is read as sRGB", where(t), encoding));
      encoding = "sRGB";
    }
    ImageTexture tex;
    tex.scale = p.get_float("scale", 1);
    if (p.get_bool("invert", false)) unsupported(t, "Texture \"invert\"");
    for (const char* uv : {"uscale", "vscale"})
      if (p.get_float(uv, 1) != 1) unsupported(t, fmt::format("Texture \"{}\"", uv));
    for (const char* uv : {"udelta", "vdelta"})
      if (p.get_float(uv, 0) != 0) unsupported(t, fmt::format("Texture \"{}\"", uv));
    for (const char* ignored : {"filter", "maxanisotropy", "wrap", "mapping"}) p.find(ignored);
    auto cached = m_image_cache.find(path.string() + "|" + encoding);
    if (cached != m_image_cache.end()) {
      tex.index = cached->second;
    } else {
      try {
        m_scene.textures.push_back(read_image(path, encoding == "sRGB"));
      } catch (const Error& e) {
        fail("{}: Texture \"{}\": {}", where(t), name, e.what());
      }
      tex.index = int(m_scene.textures.size() - 1);
      m_image_cache[path.string() + "|" + encoding] = tex.index;
    }
    m_textures[name] = tex;
    p.warn_unused();
  }

  // --- lights ---

  void area_light(const Token& t) {
    std::string type = expect_string(t);
    Params p(*this, t, fmt::format("AreaLightSource \"{}\"", type), param_list());
    if (type != "diffuse") {
      unsupported(t, fmt::format("AreaLightSource \"{}\"", type));
      return;
    }
    Rgb L = p.get_spectrum("L").value_or(Rgb(1));
    const float s = p.get_float("scale", 1);
    if (!(s >= 0)) syntax(t, "AreaLightSource: scale must not be negative");
    m_state.emissive = true;
    m_state.emission = L * s;
    m_state.two_sided = p.get_bool("twosided", false);
    if (p.find("filename")) unsupported(t, "AreaLightSource \"filename\" (an image emitter)");
    if (p.find("power")) unsupported(t, "light \"power\" (normalization to a power)");
    p.warn_unused();
  }

  void light(const Token& t) {
    std::string type = expect_string(t);
    Params p(*this, t, fmt::format("LightSource \"{}\"", type), param_list());
    const float s = p.get_float("scale", 1);
    if (!(s >= 0)) syntax(t, "LightSource: scale must not be negative");
    if (p.find("power") || p.find("illuminance"))
      unsupported(t, "light \"power\"/\"illuminance\" (normalization)");
    if (type == "point") {
      Rgb I = p.get_spectrum("I").value_or(Rgb(1)) * s;
      Vec3 from = p.get_point("from").value_or(Vec3(0));
      m_lights.push_back(make_point_light(apply_point(m_state.ctm, from), I));
    } else if (type == "distant") {
      Rgb L = p.get_spectrum("L").value_or(Rgb(1)) * s;
      Vec3 from = p.get_point("from").value_or(Vec3(0)),
           to = p.get_point("to").value_or(Vec3(0, 0, 1));
      Vec3 d = apply_vector(m_state.ctm, from - to);
      if (!(length_sq(d) > 0) || !is_finite(d))
        syntax(t, "LightSource \"distant\": from and to are the same point");
      m_lights.push_back(make_directional_light(normalize(d), L));
    } else if (type == "infinite") {
      infinite_light(t, p, s);
    } else {
      unsupported(t, fmt::format("LightSource \"{}\"", type));
      return;
    }
    p.find("portal");
    p.warn_unused();
  }

  void infinite_light(const Token& t, const Params& p, float s) {
    if (m_scene.sky) {
      warn("second infinite",
           fmt::format("{}: a second infinite light is not supported; skipped", where(t)));
      return;
    }
    auto L = p.get_spectrum("L");
    auto file = p.get_string("filename");
    if (L && file)
      syntax(t, "LightSource \"infinite\": give either \"L\" or \"filename\", not both");
    SkyDome sky;
    sky.full_sphere = true;
    sky.triangles = kInfiniteLightTriangles;
    sky.radiance = L.value_or(Rgb(1)) * s;
    if (file) {
      const fs::path path = referenced_file(t, "LightSource \"infinite\"", *file);
      auto map = std::make_shared<EnvironmentMap>();
      try {
        map->image = read_image(path);
      } catch (const Error& e) {
        fail("{}: LightSource \"infinite\": {}", where(t), e.what());
      }
      const int w = map->image.width(), h = map->image.height();
      if (w == h) {
        map->mapping = EnvironmentMap::Mapping::EqualArea;
      } else if (w == 2 * h) {
        map->mapping = EnvironmentMap::Mapping::Equirect;
        warn("equirect", fmt::format("{}: LightSource \"infinite\": a 2:1 image is read as an "
                                     "equirectangular map (pbrt-v3); pbrt-v4 wants a square "
                                     "equal-area one",
                                     where(t)));
      } else {
        syntax(t, fmt::format("LightSource \"infinite\": '{}' is {}x{}: an environment map must be "
                              "square (equal-area) or 2:1 (equirectangular)",
                              *file, w, h));
      }
      m_map_light_from_world = inverse(m_state.ctm);
      if (!m_map_light_from_world) syntax(t, "LightSource \"infinite\": singular transform");
      sky.map = map;
    }
    m_scene.sky = sky;
  }

  // --- shapes ---

  static constexpr int kInvisible = -2;

  // The material of the next shape, with the active area light's emission.
  uint32_t shape_material() {
    int base = m_state.material;
    if (base == -1) {
      if (m_default_material < 0) {
        Material m;
        m.name = "default";
        m.albedo = Rgb(0.5f);
        m_scene.materials.push_back(m);
        m_default_material = int(m_scene.materials.size() - 1);
      }
      base = m_default_material;
    }
    if (!m_state.emissive) return uint32_t(base);
    auto key = std::make_tuple(base, m_state.emission.x, m_state.emission.y, m_state.emission.z,
                               m_state.two_sided);
    auto it = m_emissive.find(key);
    if (it != m_emissive.end()) return it->second;
    Material m = m_scene.materials[size_t(base)];
    m.emission = m_state.emission;
    m.two_sided_emission = m_state.two_sided;
    m.name += " (emitting)";
    m_scene.materials.push_back(m);
    return m_emissive[key] = uint32_t(m_scene.materials.size() - 1);
  }

  void shape(const Token& t) {
    std::string type = expect_string(t);
    Params p(*this, t, fmt::format("Shape \"{}\"", type), param_list());
    Mesh mesh;
    bool quadric = false;  // pbrt orients quadrics by their parametrization, meshes by N
    if (type == "trianglemesh") {
      triangle_mesh(t, p, mesh);
    } else if (type == "plymesh") {
      auto file = p.get_string("filename");
      if (!file) syntax(t, "Shape \"plymesh\" needs a \"string filename\"");
      const fs::path path = referenced_file(t, "Shape \"plymesh\"", *file);
      try {
        mesh = parse_ply(read_text_file(path), path.string());
      } catch (const Error& e) {
        fail("{}: Shape \"plymesh\": {}", where(t), e.what());
      }
      for (const char* name : {"displacement", "edgelength"})
        if (p.find(name)) unsupported(t, "Shape \"plymesh\" displacement");
    } else if (type == "bilinearmesh") {
      bilinear_mesh(t, p, mesh);
    } else if (type == "sphere") {
      sphere(t, p, mesh);
      quadric = true;
    } else if (type == "disk") {
      disk(t, p, mesh);
      quadric = true;
    } else {
      unsupported(t, fmt::format("Shape \"{}\"", type));
      return;
    }
    for (const char* name : {"alpha", "emission"})
      if (p.find(name)) unsupported(t, fmt::format("Shape parameter \"{}\"", name));
    p.warn_unused();
    if (m_state.material == kInvisible) return;
    add_mesh(t, std::move(mesh), quadric);
  }

  void add_mesh(const Token& t, Mesh mesh, bool quadric) {
    const Affine x = to_affine(m_state.ctm);
    if (!(std::abs(x.det()) > 0) || !std::isfinite(x.det()))
      syntax(t, "Shape: the transform is singular");
    transform_mesh(mesh, x, 0, 0);
    const bool swaps = x.det() < 0;
    if (quadric ? (m_state.reverse_orientation != swaps) : m_state.reverse_orientation) {
      for (auto& tri : mesh.triangles) std::swap(tri[1], tri[2]);
      if (quadric)
        for (auto& n : mesh.normals) n = -n;
    }
    if (!quadric && !mesh.normals.empty()) {
      // pbrt's shading normals decide which side of a mesh triangle is its front.
      for (auto& tri : mesh.triangles) {
        const Vec3 n = mesh.normals[tri[0]] + mesh.normals[tri[1]] + mesh.normals[tri[2]];
        const Vec3 g = cross(mesh.positions[tri[1]] - mesh.positions[tri[0]],
                             mesh.positions[tri[2]] - mesh.positions[tri[0]]);
        if (dot(n, g) < 0) std::swap(tri[1], tri[2]);
      }
    }
    if (m_scene.mesh.triangle_count() + mesh.triangle_count() > m_policy.max_triangles)
      syntax(t, fmt::format("the scene has more than {} triangles", m_policy.max_triangles));
    mesh.material.assign(mesh.triangle_count(), shape_material());
    mesh.light.assign(mesh.triangle_count(), -1);
    m_scene.mesh.append(mesh, 0);
  }

  void triangle_mesh(const Token& t, const Params& p, Mesh& mesh) {
    const auto* P = p.get_array("P", {"point3", "point"}, 3);
    if (!P || P->empty()) syntax(t, "Shape \"trianglemesh\" needs \"point3 P\"");
    const size_t nv = P->size() / 3;
    fill_vertices(t, p, mesh, *P, "trianglemesh");
    const auto* I = p.get_array("indices", {"integer"}, 3);
    if (!I) {
      if (nv != 3)
        syntax(t, fmt::format("Shape \"trianglemesh\": \"integer indices\" are needed unless there "
                              "are exactly 3 vertices (got {})",
                              nv));
      mesh.triangles.push_back({0, 1, 2});
      return;
    }
    mesh.triangles.reserve(I->size() / 3);
    for (size_t i = 0; i < I->size(); i += 3) {
      std::array<uint32_t, 3> tri;
      for (int k = 0; k < 3; ++k)
        tri[size_t(k)] = index(t, "trianglemesh", (*I)[i + size_t(k)], nv);
      mesh.triangles.push_back(tri);
    }
    for (const char* ignored : {"S", "faceIndices"}) p.find(ignored);
  }

  uint32_t index(const Token& t, const char* shape, double v, size_t count) const {
    if (v != std::floor(v) || v < 0 || v >= double(count))
      syntax(t, fmt::format("Shape \"{}\": index {} is out of range (there are {} vertices)", shape,
                            v, count));
    return uint32_t(v);
  }

  // P, and N and uv when given, which must have one entry per vertex.
  void fill_vertices(const Token& t, const Params& p, Mesh& mesh, const std::vector<double>& P,
                     const char* shape) {
    const size_t nv = P.size() / 3;
    mesh.positions.resize(nv);
    for (size_t i = 0; i < nv; ++i)
      mesh.positions[i] = Vec3(float(P[3 * i]), float(P[3 * i + 1]), float(P[3 * i + 2]));
    if (const auto* N = p.get_array("N", {"normal3", "normal"}, 3)) {
      if (N->size() != P.size())
        syntax(t,
               fmt::format("Shape \"{}\": {} normals for {} vertices", shape, N->size() / 3, nv));
      mesh.normals.resize(nv);
      for (size_t i = 0; i < nv; ++i)
        mesh.normals[i] = Vec3(float((*N)[3 * i]), float((*N)[3 * i + 1]), float((*N)[3 * i + 2]));
    }
    const std::vector<double>* uv = p.get_array("uv", {"point2", "float"}, 2);
    if (!uv) uv = p.get_array("st", {"point2", "float"}, 2);
    if (uv) {
      if (uv->size() / 2 != nv)
        syntax(t, fmt::format("Shape \"{}\": {} uvs for {} vertices", shape, uv->size() / 2, nv));
      mesh.uvs.resize(nv);
      for (size_t i = 0; i < nv; ++i)
        mesh.uvs[i] = Vec2{float((*uv)[2 * i]), float((*uv)[2 * i + 1])};
    }
  }

  void bilinear_mesh(const Token& t, const Params& p, Mesh& mesh) {
    const auto* P = p.get_array("P", {"point3", "point"}, 3);
    if (!P || P->empty()) syntax(t, "Shape \"bilinearmesh\" needs \"point3 P\"");
    const size_t nv = P->size() / 3;
    Mesh corners;
    fill_vertices(t, p, corners, *P, "bilinearmesh");
    std::vector<double> default_indices = {0, 1, 2, 3};
    const auto* I = p.get_array("indices", {"integer"}, 4);
    if (!I) {
      if (nv != 4)
        syntax(t, fmt::format("Shape \"bilinearmesh\": \"integer indices\" are needed unless there "
                              "are exactly 4 vertices (got {})",
                              nv));
      I = &default_indices;
    }
    const bool has_n = !corners.normals.empty(), has_uv = !corners.uvs.empty();
    for (size_t i = 0; i < I->size(); i += 4) {
      uint32_t v[4];
      for (int k = 0; k < 4; ++k) v[k] = index(t, "bilinearmesh", (*I)[i + size_t(k)], nv);
      // pbrt's patch: p(u, v) = lerp over p00 = v0, p10 = v1, p01 = v2, p11 = v3.
      const Vec3 p00 = corners.positions[v[0]], p10 = corners.positions[v[1]],
                 p01 = corners.positions[v[2]], p11 = corners.positions[v[3]];
      const Vec3 e1 = p10 - p00, e2 = p01 - p00;
      const float size = std::max({length(e1), length(e2), length(p11 - p00), 1e-30f});
      const bool planar = std::abs(dot(p11 - p00, cross(e1, e2))) <= 1e-5f * size * size * size;
      const int n = planar ? 1 : kBilinearGrid;
      if (mesh.triangle_count() + size_t(2 * n * n) > m_policy.max_triangles)
        syntax(t, fmt::format("the scene has more than {} triangles", m_policy.max_triangles));
      const uint32_t base = uint32_t(mesh.positions.size());
      auto bilerp = [](float u, float w, auto a, auto b, auto c, auto d) {
        return a * ((1 - u) * (1 - w)) + b * (u * (1 - w)) + c * ((1 - u) * w) + d * (u * w);
      };
      for (int j = 0; j <= n; ++j)
        for (int k = 0; k <= n; ++k) {
          const float u = float(k) / n, w = float(j) / n;
          mesh.positions.push_back(bilerp(u, w, p00, p10, p01, p11));
          if (has_n)
            mesh.normals.push_back(bilerp(u, w, corners.normals[v[0]], corners.normals[v[1]],
                                          corners.normals[v[2]], corners.normals[v[3]]));
          if (has_uv) {
            const Vec2 a = corners.uvs[v[0]], b = corners.uvs[v[1]], c = corners.uvs[v[2]],
                       d = corners.uvs[v[3]];
            mesh.uvs.push_back(
                Vec2{bilerp(u, w, a.x, b.x, c.x, d.x), bilerp(u, w, a.y, b.y, c.y, d.y)});
          } else {
            mesh.uvs.push_back(Vec2{u, w});  // pbrt's default (u, v) over the patch
          }
        }
      for (int j = 0; j < n; ++j)
        for (int k = 0; k < n; ++k) {
          const uint32_t a = base + uint32_t(j * (n + 1) + k), b = a + 1, c = a + uint32_t(n + 1),
                         d = c + 1;
          // Front face along dp/du x dp/dv, as pbrt's patch normal.
          mesh.triangles.push_back({a, b, d});
          mesh.triangles.push_back({a, d, c});
        }
    }
    if (!has_n) mesh.normals.clear();
  }

  void sphere(const Token& t, const Params& p, Mesh& mesh) {
    const float r = p.get_float("radius", 1);
    const float z0 = p.get_float("zmin", -r), z1 = p.get_float("zmax", r);
    const float phimax = p.get_float("phimax", 360);
    if (!(r > 0)) syntax(t, "Shape \"sphere\": radius must be positive");
    if (!(phimax > 0 && phimax <= 360)) syntax(t, "Shape \"sphere\": phimax must be in (0, 360]");
    const float zmin = clamp(std::min(z0, z1), -r, r), zmax = clamp(std::max(z0, z1), -r, r);
    const float th0 = std::acos(zmax / r), th1 = std::acos(zmin / r);
    if (!(th1 > th0)) syntax(t, "Shape \"sphere\": zmin and zmax leave nothing");
    const float phi_max = radians(phimax);
    const int segs = std::max(3, int(std::ceil(kSphereSegments * phimax / 360))),
              rings = std::max(1, int(std::ceil(kSphereRings * (th1 - th0) / kPi)));
    const bool full = phimax >= 360;
    const int cols = full ? segs : segs + 1;  // a full sphere shares its seam
    // Poles (when reached) are single vertices; rings in between have `cols` vertices.
    const bool top = th0 <= 0, bottom = th1 >= kPi;
    auto vertex = [&](float th, float ph) {
      const Vec3 n(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
      mesh.positions.push_back(n * r);
      mesh.normals.push_back(n);
      mesh.uvs.push_back(Vec2{ph / phi_max, (th - th0) / (th1 - th0)});
    };
    std::vector<uint32_t> ring_start;
    for (int i = 0; i <= rings; ++i) {
      const float th = th0 + (th1 - th0) * float(i) / rings;
      ring_start.push_back(uint32_t(mesh.positions.size()));
      if ((i == 0 && top) || (i == rings && bottom)) {
        vertex(th, 0);
        continue;
      }
      for (int j = 0; j < cols; ++j) vertex(th, phi_max * float(j) / segs);
    }
    auto at = [&](int i, int j) {
      if ((i == 0 && top) || (i == rings && bottom)) return ring_start[size_t(i)];
      return ring_start[size_t(i)] + uint32_t(full ? j % segs : j);
    };
    // Wound outwards below, as pbrt's sphere faces (before ReverseOrientation).
    for (int i = 0; i < rings; ++i)
      for (int j = 0; j < segs; ++j) {
        const uint32_t a = at(i, j), b = at(i, j + 1), c = at(i + 1, j), d = at(i + 1, j + 1);
        if (a != b) mesh.triangles.push_back({a, c, b});
        if (c != d) mesh.triangles.push_back({b, c, d});
      }
    orient_outward(mesh);
  }

  void disk(const Token& t, const Params& p, Mesh& mesh) {
    const float r = p.get_float("radius", 1), ri = p.get_float("innerradius", 0),
                h = p.get_float("height", 0), phimax = p.get_float("phimax", 360);
    if (!(r > 0) || !(ri >= 0) || !(ri < r))
      syntax(t, "Shape \"disk\": needs 0 <= innerradius < radius");
    if (!(phimax > 0 && phimax <= 360)) syntax(t, "Shape \"disk\": phimax must be in (0, 360]");
    const float phi_max = radians(phimax);
    const int segs = std::max(3, int(std::ceil(kDiskSegments * phimax / 360)));
    const bool full = phimax >= 360;
    const int cols = full ? segs : segs + 1;
    for (int ring = 0; ring < 2; ++ring)
      for (int j = 0; j < cols; ++j) {
        const float ph = phi_max * float(j) / segs, rad = ring == 0 ? r : ri;
        mesh.positions.push_back(Vec3(rad * std::cos(ph), rad * std::sin(ph), h));
        mesh.uvs.push_back(Vec2{ph / phi_max, float(ring)});
      }
    for (int j = 0; j < segs; ++j) {
      const uint32_t a = uint32_t(j), b = uint32_t(full ? (j + 1) % segs : j + 1),
                     c = uint32_t(cols) + a, d = uint32_t(cols) + b;
      mesh.triangles.push_back({a, b, d});  // normal +z, as pbrt's disk
      if (ri > 0) mesh.triangles.push_back({a, d, c});
    }
    if (ri == 0) {
      // The inner ring collapsed to the centre: keep one vertex there.
      for (auto& tri : mesh.triangles)
        for (auto& v : tri)
          if (v >= uint32_t(cols)) v = uint32_t(cols);
      mesh.positions.resize(size_t(cols) + 1);
      mesh.uvs.resize(size_t(cols) + 1);
    }
  }

  // Winds every triangle of a closed convex-ish shape around the origin with its normal out.
  static void orient_outward(Mesh& mesh) {
    for (auto& tri : mesh.triangles) {
      const Vec3 a = mesh.positions[tri[0]], b = mesh.positions[tri[1]], c = mesh.positions[tri[2]];
      if (dot(cross(b - a, c - a), a + b + c) < 0) std::swap(tri[1], tri[2]);
    }
  }

  // --- objects ---

  void end_object() {
    Mesh& all = m_scene.mesh;
    ObjectMesh obj;
    const size_t t0 = m_object_triangle, v0 = m_object_vertex;
    obj.mesh.positions.assign(all.positions.begin() + long(v0), all.positions.end());
    if (!all.normals.empty())
      obj.mesh.normals.assign(all.normals.begin() + long(v0), all.normals.end());
    if (!all.uvs.empty()) obj.mesh.uvs.assign(all.uvs.begin() + long(v0), all.uvs.end());
    for (size_t t = t0; t < all.triangles.size(); ++t) {
      const auto& tri = all.triangles[t];
      obj.mesh.triangles.push_back(
          {uint32_t(tri[0] - v0), uint32_t(tri[1] - v0), uint32_t(tri[2] - v0)});
    }
    obj.mesh.material.assign(all.material.begin() + long(t0), all.material.end());
    obj.mesh.light.assign(obj.mesh.triangles.size(), -1);
    all.positions.resize(v0);
    if (!all.normals.empty()) all.normals.resize(v0);
    if (!all.uvs.empty()) all.uvs.resize(v0);
    all.triangles.resize(t0);
    all.material.resize(t0);
    all.light.resize(t0);
    m_objects[m_object_name] = std::move(obj);
    m_object = false;
  }

  void instance(const Token& t, const ObjectMesh& obj) {
    if (m_scene.mesh.triangle_count() + obj.mesh.triangle_count() > m_policy.max_triangles)
      syntax(t, fmt::format("the scene has more than {} triangles", m_policy.max_triangles));
    const Affine x = to_affine(m_state.ctm);
    if (!(std::abs(x.det()) > 0) || !std::isfinite(x.det()))
      syntax(t, "ObjectInstance: the transform is singular");
    const size_t t0 = m_scene.mesh.triangle_count(), v0 = m_scene.mesh.positions.size();
    m_scene.mesh.append(obj.mesh, 0);
    transform_mesh(m_scene.mesh, x, t0, v0);
  }

  // --- the end: camera, mirror, lights, warnings ---

  void finish() {
    m_scene.lights.insert(m_scene.lights.end(), m_lights.begin(), m_lights.end());
    if (m_has_camera) {
      const Mat4& c = m_world_from_camera;
      const Vec3 pos = apply_point(c, Vec3(0)), fwd = normalize(apply_vector(c, Vec3(0, 0, 1))),
                 up = normalize(apply_vector(c, Vec3(0, 1, 0))),
                 right = apply_vector(c, Vec3(1, 0, 0));
      if (!is_finite(pos) || !is_finite(fwd) || !is_finite(up) || !(length_sq(cross(fwd, up)) > 0))
        fail("{}: the camera transform is degenerate", m_names[0]);
      Camera& cam = m_scene.camera;
      cam.position = pos;
      cam.target = pos + fwd;
      cam.up = up;
      // pbrt's fov spans the shorter image side; rll's the vertical one.
      const float w = float(m_scene.width), h = float(m_scene.height);
      cam.fov = m_camera_fov;
      if (h > w) cam.fov = 2 * std::atan(std::tan(radians(m_camera_fov) / 2) * h / w) * (180 / kPi);
      m_scene.has_camera = true;
      // pbrt's camera space is left-handed: the image's right is the camera's +x, which for most
      // transforms is the mirror image of rll's right (forward x up). Mirroring the world through
      // the plane of the camera's forward and up vectors renders the image pbrt renders.
      const Vec3 rll_right = normalize(cross(fwd, up));
      if (dot(rll_right, right) < 0) mirror_world(pos, rll_right);
    }
    if (m_scene.sky && m_scene.sky->map) {
      auto map = std::make_shared<EnvironmentMap>(*m_scene.sky->map);
      // World directions to the light's frame (pbrt looks maps up in the light's space).
      const Mat4& lw = *m_map_light_from_world;
      double h[3][3];
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          h[i][j] = (i == j ? 1.0 : 0.0) -
                    (m_mirrored ? 2.0 * m_mirror_normal[i] * m_mirror_normal[j] : 0.0);
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
          double s = 0;
          for (int k = 0; k < 3; ++k) s += lw.m[i][k] * h[k][j];
          map->world_to_map[i][j] = to_float(s);
        }
      m_scene.sky->map = std::move(map);
    }
    for (const auto& [message, count] : m_warnings)
      m_scene.warnings.push_back(
          count > 1 ? fmt::format("{} (and {} more times)", message, count - 1) : message);
  }

  void mirror_world(const Vec3& origin, const Vec3& n) {
    m_mirrored = true;
    m_mirror_normal = n;
    auto point = [&](const Vec3& p) { return p - n * (2 * dot(p - origin, n)); };
    auto vector = [&](const Vec3& v) { return v - n * (2 * dot(v, n)); };
    Mesh& mesh = m_scene.mesh;
    for (auto& p : mesh.positions) p = point(p);
    for (auto& v : mesh.normals) v = vector(v);
    for (auto& tri : mesh.triangles) std::swap(tri[1], tri[2]);
    for (auto& l : m_scene.lights) {
      if (l.type == LightType::Point) l.p0 = point(l.p0);
      if (l.type == LightType::Directional) l.p0 = vector(l.p0);
    }
    if (m_scene.sky) m_scene.sky->up = vector(m_scene.sky->up);
  }

  struct Saved {
    GraphicsState state;
    bool transform_only;
    size_t line;
  };

  fs::path m_base;
  Scene& m_scene;
  ReadPolicy m_policy;
  std::deque<std::string> m_texts;  // included files, alive while their tokens are
  std::vector<std::string> m_names;
  std::vector<std::string> m_included_from;  // per file: "FILE:LINE: Include: ", or ""
  std::vector<bool> m_begun;                  // per file: whether a directive was read
  std::vector<Tokenizer> m_tokenizers;
  std::vector<std::string> m_open;  // canonical paths of the files being read
  std::optional<Token> m_peeked;

  GraphicsState m_state;
  std::vector<Saved> m_stack;
  std::map<std::string, Mat4> m_named_frames;
  std::map<std::string, int> m_named_materials;
  std::map<std::string, ImageTexture> m_textures;
  std::map<std::string, int> m_image_cache;
  std::map<std::tuple<int, float, float, float, bool>, uint32_t> m_emissive;
  int m_default_material = -1;

  bool m_object = false;
  std::string m_object_name;
  size_t m_object_triangle = 0, m_object_vertex = 0;
  std::map<std::string, ObjectMesh> m_objects;

  bool m_has_camera = false;
  float m_camera_fov = 90;
  Mat4 m_world_from_camera;
  std::vector<Light> m_lights;
  std::optional<Mat4> m_map_light_from_world;
  bool m_mirrored = false;
  Vec3 m_mirror_normal;

  std::vector<std::pair<std::string, size_t>> m_warnings;
  std::map<std::string, size_t> m_warning_index;
};

}  // namespace

void parse_pbrt(std::string_view text, const std::string& name, const fs::path& base_dir,
                Scene& scene, const ReadPolicy& policy) {
  PbrtReader(base_dir, scene, policy).read(text, name);
}

void load_pbrt(const fs::path& path, Scene& scene) {
  const std::string file = path.string();
  if (!fs::exists(path)) fail("{}: file not found", file);
  const std::string text = read_text_file(path);
  parse_pbrt(text, file, path.parent_path(), scene);
}

}  // namespace rll
