// The pbrt reader's main loop, transforms, graphics state, includes, camera, film, lights and
// objects (see pbrt_internal.h).
#include <array>
#include <cctype>

#include "rll/core/parallel.h"
#include "rll/io/pbrt_internal.h"

namespace rll::pbrt {

// --- 4x4 matrices in double, as pbrt composes its transforms ---

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

std::string matrix_text(const Mat4& m) {
  std::string out = "[";
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      out += fmt::format("{:g}{}", m.m[i][j], j < 3 ? " " : i < 3 ? "; " : "]");
  return out;
}

std::string transform_problem(const Mat4& m) {
  const Affine x = to_affine(m);
  const float det = x.det();
  bool finite = true;
  for (int i = 0; i < 3; ++i) {
    finite = finite && std::isfinite(x.t[i]);
    for (int j = 0; j < 3; ++j) finite = finite && std::isfinite(x.a[i][j]);
  }
  if (finite && std::abs(det) > 0 && std::isfinite(det)) return "";
  // The determinant in double, for the message: the factor by which the transform scales volumes.
  double d = 0;
  for (int j = 0; j < 3; ++j)
    d += m.m[0][j] *
         (m.m[1][(j + 1) % 3] * m.m[2][(j + 2) % 3] - m.m[1][(j + 2) % 3] * m.m[2][(j + 1) % 3]);
  const std::string matrix = matrix_text(m);
  if (d == 0)
    return fmt::format(
        "the transform is singular: its determinant is 0 (it flattens the shape onto a plane, a "
        "line or a point); matrix {}",
        matrix);
  if (!finite || !std::isfinite(det) || std::abs(d) >= 1)
    return fmt::format(
        "the transform is too large for rll, which transforms in single precision (at most "
        "3.4e+38): it scales volumes by {:g} (lengths by about {:g}){}; scale the scene down; "
        "matrix {}",
        d, std::cbrt(std::abs(d)), finite ? "" : " and has an entry beyond 3.4e+38", matrix);
  return fmt::format(
      "the transform is degenerate for rll, which transforms in single precision: it scales "
      "volumes by {:g} (lengths by about {:g}), too small a factor for a float; matrix {}",
      d, std::cbrt(std::abs(d)), matrix);
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

void PbrtReader::read(std::string_view text, const std::string& name) {
  std::string key;
  if (m_policy.read_files) {
    std::error_code ec;
    fs::path canon = fs::weakly_canonical(name, ec);
    key = ec ? name : canon.string();
  }
  push_file(text, name, key, "");
  m_first_material = m_scene.materials.size();
  m_scene.width = 1280;  // pbrt's default film
  m_scene.height = 720;
  while (auto t = take()) directive(*t);
  if (!m_stack.empty())
    fail("{}: {} AttributeBegin without AttributeEnd (the first at line {})", name, m_stack.size(),
         m_stack.front().line);
  if (m_object) fail("{}: ObjectBegin \"{}\" without ObjectEnd", name, m_object_name);
  finish();
}

void PbrtReader::directive(const Token& t) {
  const std::string_view d = t.text;
  const bool known = !t.quoted && is_directive(t) && pbrt_directives().count(d);
  // An included file that does not begin with a directive is not a pbrt file at all (say,
  // Include "/etc/passwd"): its content stays out of the message.
  if (!known && !m_begun[t.file] && !m_included_from[t.file].empty())
    syntax(t, "this is not a pbrt file (it does not begin with a pbrt directive)");
  m_begun[t.file] = true;
  if (t.quoted) syntax(t, fmt::format("expected a directive, got \"{}\"", printable(t.text)));
  if (!is_directive(t)) syntax(t, fmt::format("expected a directive, got '{}'", printable(t.text)));
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
    Params p(*this, t, fmt::format("Material \"{}\"", type));
    g.material = make_material(t, type, p);
    p.warn_unused();
  } else if (d == "MakeNamedMaterial") {
    std::string name = expect_string(t);
    Params p(*this, t, fmt::format("MakeNamedMaterial \"{}\"", name));
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
  } else if (d == "ColorSpace") {
    const std::string name = expect_string(t);
    if (name != "srgb")
      syntax(t, fmt::format("ColorSpace \"{}\": rll renders in linear sRGB only (\"srgb\")",
                            printable(name)));
  } else if (d == "PixelFilter") {
    // rll averages the samples of each pixel (a box of radius 0.5): pbrt's box filter of that
    // radius is the same; any other filter is rendered as that box.
    const std::string type = expect_string(t);
    Params p(*this, t, fmt::format("PixelFilter \"{}\"", type));
    const float xr = p.get_float("xradius", 0.5f), yr = p.get_float("yradius", 0.5f);
    if (type != "box" || xr != 0.5f || yr != 0.5f) {
      for (const auto& name : p.names()) p.find(name.c_str());
      warn("PixelFilter", fmt::format("{}: PixelFilter \"{}\" is rendered as rll's box filter of "
                                      "radius 0.5",
                                      where(t), printable(type)));
    }
    p.warn_unused();
  } else if (d == "Option") {
    // Renderer options (pbrt-v4's command-line settings, such as "bool disablepixeljitter"):
    // none changes the scene rll renders.
    Params p(*this, t, "Option");
    for (const auto& name : p.names()) p.find(name.c_str());
    warn("Option", fmt::format("{}: Option is ignored (renderer settings)", where(t)));
  } else {
    // Rendering settings and features rll does not have: Sampler, Integrator, PixelFilter,
    // Accelerator, ColorSpace, Option, Attribute, media, motion blur.
    unsupported(t, std::string(d));
    skip_arguments();
  }
}

void PbrtReader::concat(const Token& t, const Mat4& m) {
  m_state.ctm = m_state.ctm * m;
  for (const auto& row : m_state.ctm.m)
    for (double v : row)
      if (!std::isfinite(v)) syntax(t, "the transform is not finite");
}

void PbrtReader::look_at(const Token& t, const std::vector<double>& v) {
  const Vec3 pos{float(v[0]), float(v[1]), float(v[2])},
      look{float(v[3]), float(v[4]), float(v[5])}, up{float(v[6]), float(v[7]), float(v[8])};
  if (!(length_sq(look - pos) > 0)) syntax(t, "LookAt: the eye and the target are the same point");
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

fs::path PbrtReader::resolve(const std::string& name) const {
  fs::path p(name);
  return (p.is_absolute() ? p : m_base / p).lexically_normal();
}

// A file the scene refers to: it must exist, and reading files must be allowed.
fs::path PbrtReader::referenced_file(const Token& t, const std::string& what,
                                     const std::string& name) const {
  if (name.empty()) syntax(t, fmt::format("{}: empty file name", what));
  if (!m_policy.read_files)
    syntax(t, fmt::format("{}: '{}': reading other files is turned off", what, printable(name)));
  fs::path p = resolve(name);
  if (const std::string why = unreadable_reason(p); !why.empty())
    syntax(t,
           fmt::format("{}: '{}' {} ({})", what, printable(name), why, printable(p.string(), 256)));
  return p;
}

void PbrtReader::include(const Token& t) {
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
  push_file(m_texts.back(), p.string(), key,
            fmt::format("{}:{}: {}: ", m_names[t.file], t.line, t.text));
}

void PbrtReader::camera(const Token& t) {
  std::string type = expect_string(t);
  Params p(*this, t, fmt::format("Camera \"{}\"", type));
  m_named_frames["camera"] = inverse(m_state.ctm).value_or(Mat4());
  if (type != "perspective") {
    unsupported(t, fmt::format("Camera \"{}\"", type));
    return;
  }
  auto world_from_camera = inverse(m_state.ctm);
  if (!world_from_camera)
    syntax(t, fmt::format("Camera: the camera transform is singular (it has no inverse); matrix "
                          "{}",
                          matrix_text(m_state.ctm)));
  m_camera_fov = p.get_float("fov", 90);
  if (!(m_camera_fov > 0 && m_camera_fov < 180))
    syntax(t, fmt::format("Camera: fov must be in (0, 180) degrees (got {})", m_camera_fov));
  // Thin lens (pbrt-v4's defaults: lensradius 0, focaldistance 1e6).
  m_lens_radius = p.get_float("lensradius", 0);
  m_focal_distance = p.get_float("focaldistance", 1e6f);
  if (!(m_lens_radius >= 0) || !std::isfinite(m_lens_radius))
    syntax(t, "Camera: lensradius must not be negative");
  if (!(m_focal_distance > 0) || !std::isfinite(m_focal_distance))
    syntax(t, "Camera: focaldistance must be positive");
  if (const auto* sw = p.get_array("screenwindow", {"float"}, 4)) {
    if (sw->size() != 4)
      syntax(t, fmt::format("Camera: screenwindow needs 4 values (got {})", sw->size()));
    const std::array<float, 4> v{float((*sw)[0]), float((*sw)[1]), float((*sw)[2]),
                                 float((*sw)[3])};
    for (float x : v)
      if (!std::isfinite(x)) syntax(t, "Camera: screenwindow is not finite");
    if (!(v[1] > v[0]) || !(v[3] > v[2]))
      syntax(t, "Camera: screenwindow needs xmin < xmax and ymin < ymax");
    m_screen_window = v;
  }
  // The shutter interval is the exposure time of pbrt-v4's sensor (see film()).
  m_exposure_time = p.get_float("shutterclose", 1) - p.get_float("shutteropen", 0);
  if (!(m_exposure_time > 0)) syntax(t, "Camera: shutterclose must be after shutteropen");
  if (const Param* q = p.typed("frameaspectratio", {"float"})) {
    m_frame_aspect = float(p.one_number(*q));
    m_frame_aspect_where = where(t.file, q->line);
  }
  m_world_from_camera = *world_from_camera;
  m_has_camera = true;
  p.warn_unused();
}

void PbrtReader::film(const Token& t) {
  std::string type = expect_string(t);
  Params p(*this, t, fmt::format("Film \"{}\"", type));
  const int w = p.get_int("xresolution", 1280), h = p.get_int("yresolution", 720);
  if (w <= 0 || h <= 0 || w > 65536 || h > 65536)
    syntax(t, fmt::format("Film: resolution {}x{} is out of range", w, h));
  m_scene.width = w;
  m_scene.height = h;
  // pbrt-v4's sensor scales the image by its imaging ratio, exposure time * ISO / 100 (see
  // finish()).
  m_iso = p.get_float("iso", 100);
  if (!(m_iso > 0) || !std::isfinite(m_iso)) syntax(t, "Film: iso must be positive");
  // Output settings that do not change the image rll renders.
  for (const char* name : {"filename", "savefp16", "diagonal", "writefp16"}) p.find(name);
  // Settings that change pbrt-v4's image and that rll does not have, at their defaults (no white
  // balance, the CIE 1931 sensor, no clamping of samples) or said.
  auto ignored = [&](const char* name, const std::string& value, const char* why) {
    const Param* q = p.find(name);
    warn(fmt::format("Film {}", name),
         fmt::format("{}: Film: parameter \"{} {}\" {} is ignored: {}", where(t.file, q->line),
                     q->type, name, value, why));
  };
  if (const float wb = p.get_float("whitebalance", 0); wb != 0)
    ignored("whitebalance", fmt::format("{}", wb), "rll applies no white balance");
  if (const auto sensor = p.get_string("sensor"); sensor && *sensor != "cie1931")
    ignored("sensor", "\"" + printable(*sensor) + "\"",
            "rll renders linear sRGB as pbrt-v4's default sensor \"cie1931\" does");
  if (const Param* q = p.typed("maxcomponentvalue", {"float"}))
    ignored("maxcomponentvalue", fmt::format("{}", p.one_number(*q)),
            "rll clamps no sample (pbrt-v4's default, infinity)");
  p.warn_unused();
}

// pbrt-v4's "power" (and "illuminance"): a positive value normalizes the light to it; pbrt-v4
// ignores any other value (its default is -1), and so does rll, saying so.
std::optional<float> PbrtReader::normalization(const Token& t, const Params& p, const char* name) {
  const Param* q = p.typed(name, {"float"});
  if (!q) return std::nullopt;
  const float v = float(p.one_number(*q));
  if (!std::isfinite(v)) p.bad(*q, "is not finite");
  if (v > 0) return v;
  if (v != -1)
    warn(fmt::format("{} {}", name, v),
         fmt::format("{}: \"float {}\" [ {} ] is not positive: ignored, as pbrt-v4 does (the light "
                     "keeps its stated emission)",
                     where(t.file, q->line), name, v));
  return std::nullopt;
}

void PbrtReader::area_light(const Token& t) {
  std::string type = expect_string(t);
  Params p(*this, t, fmt::format("AreaLightSource \"{}\"", type));
  if (type != "diffuse") {
    unsupported(t, fmt::format("AreaLightSource \"{}\"", type));
    ++m_skipped_lights["area " + type];
    return;
  }
  const std::optional<Rgb> given_L = p.get_spectrum("L");
  const float s = p.get_float("scale", 1);
  if (!(s >= 0) || !std::isfinite(s))
    syntax(t, "AreaLightSource: scale must be finite and not negative");
  m_state.emissive = true;
  m_state.emission = given_L.value_or(Rgb(1)) * s;
  if (!is_finite(m_state.emission))
    syntax(t, fmt::format("AreaLightSource: L x scale = ({}, {}, {}) is not finite (beyond a "
                          "float's 3.4e+38): lower L or scale",
                          m_state.emission.x, m_state.emission.y, m_state.emission.z));
  m_state.emission_texture = -1;
  m_state.texture_luminance = 1;
  if (const auto file = p.get_string("filename")) {
    // pbrt-v4's image area light: the emission at a point is scale times the image at its uv.
    if (given_L)
      syntax(t, "AreaLightSource \"diffuse\": give either \"L\" or \"filename\", not both "
                "(as pbrt-v4)");
    const fs::path path = referenced_file(t, "AreaLightSource", *file);
    const std::string key = path.string() + "|sRGB";
    auto cached = m_image_cache.find(key);
    if (cached == m_image_cache.end()) {
      Image image;
      try {
        image = read_image(path);
      } catch (const Error& e) {
        fail("{}: AreaLightSource: {}", where(t), e.what());
      }
      if (const std::string bad = bad_emission_texel(image); !bad.empty())
        syntax(t, fmt::format("AreaLightSource: '{}' has a negative or non-finite pixel, which "
                              "no light can emit: {}",
                              *file, bad));
      m_scene.textures.push_back(std::move(image));
      cached = m_image_cache.emplace(key, int(m_scene.textures.size() - 1)).first;
    }
    m_state.emission_texture = cached->second;
    const Image& image = m_scene.textures[size_t(cached->second)];
    double sum = 0;
    for (const Rgb& c : image.pixels()) sum += double(luminance(c));
    m_state.texture_luminance = float(sum / double(std::max<size_t>(1, image.pixel_count())));
    m_state.emission = Rgb(s);
  }
  m_state.two_sided = p.get_bool("twosided", false);
  // pbrt-v4 normalizes each of its shapes to the power: the whole of a sphere or disk, each
  // triangle of a mesh (see add_mesh).
  m_state.area_power = normalization(t, p, "power").value_or(0.0f);
  if (m_state.emission_texture >= 0 && m_state.area_power > 0 && !(m_state.texture_luminance > 0))
    syntax(t, "AreaLightSource: \"power\" with an image that is black everywhere");
  p.warn_unused();
}

void PbrtReader::light(const Token& t) {
  std::string type = expect_string(t);
  Params p(*this, t, fmt::format("LightSource \"{}\"", type));
  const float s = p.get_float("scale", 1);
  if (!(s >= 0) || !std::isfinite(s)) syntax(t, "LightSource: scale must not be negative");
  // Every spectrum is read as linear sRGB of one nit per unit (spectra.h): pbrt-v4's division by
  // the spectrum's photometric value is already made, and its normalizations below are in those
  // units (they ignore the colour's own luminance, as pbrt-v4's do).
  if (type == "point" || type == "spot") {
    Rgb I = p.get_spectrum("I").value_or(Rgb(1)) * s;
    const Vec3 from = p.get_point("from").value_or(Vec3(0));
    const Vec3 pos = apply_point(m_state.ctm, from);
    if (!is_finite(pos)) syntax(t, fmt::format("LightSource \"{}\": the position is not finite", type));
    const auto power = normalization(t, p, "power");
    if (type == "point") {
      if (power) I *= *power / (4 * kPi);
      add_light(t, type, make_point_light(pos, I));
    } else {
      const Vec3 to = p.get_point("to").value_or(Vec3(0, 0, 1));
      const float cone = p.get_float("coneangle", 30), delta = p.get_float("conedeltaangle", 5);
      if (!(cone > 0 && cone <= 180))
        syntax(t, fmt::format("LightSource \"spot\": coneangle must be in (0, 180] degrees (got {})",
                              cone));
      if (!(delta >= 0 && delta <= cone))
        syntax(t, fmt::format("LightSource \"spot\": conedeltaangle must be in [0, coneangle = {}] "
                              "degrees (got {})",
                              cone, delta));
      const Vec3 axis = apply_vector(m_state.ctm, to - from);
      if (!(length_sq(axis) > 0) || !is_finite(axis))
        syntax(t, "LightSource \"spot\": from and to are the same point");
      const float cos_end = std::cos(radians(cone)), cos_start = std::cos(radians(cone - delta));
      if (power) I *= *power / spot_solid_angle(cos_start, cos_end);
      add_light(t, type, make_spot_light(pos, axis, I, cos_start, cos_end));
    }
  } else if (type == "distant") {
    Rgb L = p.get_spectrum("L").value_or(Rgb(1)) * s;
    if (const auto e = normalization(t, p, "illuminance")) L *= *e;
    Vec3 from = p.get_point("from").value_or(Vec3(0)),
         to = p.get_point("to").value_or(Vec3(0, 0, 1));
    Vec3 d = apply_vector(m_state.ctm, from - to);
    if (!(length_sq(d) > 0) || !is_finite(d))
      syntax(t, "LightSource \"distant\": from and to are the same point");
    add_light(t, type, make_directional_light(normalize(d), L));
  } else if (type == "infinite") {
    infinite_light(t, p, s);
  } else if (type == "goniometric" || type == "projection") {
    if (!image_light(t, p, type, s)) return;
  } else {
    unsupported(t, fmt::format("LightSource \"{}\"", type));
    ++m_skipped_lights[type];
    return;
  }
  p.warn_unused();
}

void PbrtReader::infinite_light(const Token& t, const Params& p, float s) {
  auto L = p.get_spectrum("L");
  auto file = p.get_string("filename");
  if (L && file) syntax(t, "LightSource \"infinite\": give either \"L\" or \"filename\", not both");
  if (p.get_array("portal", {"point3", "point"}, 3))
    warn("portal", fmt::format("{}: LightSource \"infinite\" \"portal\" is ignored: rll lights the "
                               "scene with the whole environment (pbrt-v4 samples it through the "
                               "portal and emits only from the portal's front side)",
                               where(t)));
  const auto illuminance = normalization(t, p, "illuminance");
  SkyDome sky;
  sky.full_sphere = true;
  sky.triangles = kInfiniteLightTriangles;
  sky.radiance = L.value_or(Rgb(1)) * s;
  // pbrt-v4: a constant sky of unit radiance gives an upward-facing patch pi of illuminance.
  if (illuminance && !file) sky.radiance *= *illuminance / kPi;
  if (file) {
    const fs::path path = referenced_file(t, "LightSource \"infinite\"", *file);
    auto map = std::make_shared<EnvironmentMap>();
    try {
      map->image = read_image(path);
    } catch (const Error& e) {
      fail("{}: LightSource \"infinite\": {}", where(t), e.what());
    }
    // As every image light: pbrt-v4 would sample a negative texel as negative light, and a
    // NaN or infinite one would poison every sample that sees it.
    if (const std::string bad = bad_emission_texel(map->image); !bad.empty())
      syntax(t, fmt::format("LightSource \"infinite\": '{}' has a negative or non-finite pixel, "
                            "which no light can emit: {}",
                            *file, bad));
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
    if (illuminance) {
      // pbrt-v4's illuminance of the map on a patch facing the map's +z: its sum of luminance x
      // cos over the upper half's pixels, times 2 pi / pixels (pbrt-v4's factor, kept).
      if (map->mapping != EnvironmentMap::Mapping::EqualArea)
        syntax(t, "LightSource \"infinite\": \"illuminance\" needs a square (equal-area) map");
      double e = 0;
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
          const Vec3 d = equal_area_square_to_sphere({(x + 0.5f) / float(w), (y + 0.5f) / float(h)});
          if (d.z > 0) e += double(luminance(map->image.at(x, y))) * d.z;
        }
      e *= 2 * kPi / (double(w) * h);
      if (!(e > 0))
        syntax(t, "LightSource \"infinite\": \"illuminance\" asks to normalize a map that is black "
                  "over its upper half");
      sky.radiance *= float(*illuminance / e);
    }
    sky.map = map;
  }
  if (!is_finite(sky.radiance))
    syntax(t, fmt::format("LightSource \"infinite\": its radiance ({}, {}, {}) is not finite "
                          "(L or the map times scale{} beyond a float's 3.4e+38)",
                          sky.radiance.x, sky.radiance.y, sky.radiance.z,
                          illuminance ? ", normalized to the illuminance," : ""));
  const auto light_from_world = inverse(m_state.ctm);
  if (sky.map && !light_from_world)
    syntax(t, fmt::format("LightSource \"infinite\": the transform is singular (it has no "
                          "inverse); matrix {}",
                          matrix_text(m_state.ctm)));
  m_infinite.push_back({sky.radiance, std::const_pointer_cast<EnvironmentMap>(sky.map),
                        light_from_world.value_or(Mat4())});
  if (m_infinite.size() == 2)
    warn("several infinite",
         fmt::format("{}: several infinite lights are summed into one sky{}", where(t),
                     sky.map || m_infinite[0].map
                         ? " (their maps resampled into one equal-area map in the world's frame)"
                         : ""));
  if (!m_scene.sky) m_scene.sky = sky;
}

// pbrt-v4's goniometric light (an equal-area image of intensity around the light's +y, after
// pbrt-v4's swap of y and z) and projection light (an image projected along the light's +z
// through a perspective of `fov` degrees across the image's shorter side, flipped to stand
// upright), both at the light's origin. False where the light is skipped.
bool PbrtReader::image_light(const Token& t, const Params& p, const std::string& type, float s) {
  const std::string what = fmt::format("LightSource \"{}\"", type);
  const bool gonio = type == "goniometric";
  Rgb I = gonio ? p.get_spectrum("I").value_or(Rgb(1)) * s : Rgb(s);
  const float fov = gonio ? 0.0f : p.get_float("fov", 90);
  if (!gonio && !(fov > 0 && fov < 180))
    syntax(t, fmt::format("{}: fov must be in (0, 180) degrees (got {})", what, fov));
  const auto power = normalization(t, p, "power");
  const auto file = p.get_string("filename");
  if (!file) {
    if (!gonio) syntax(t, fmt::format("{} needs a \"string filename\"", what));
    // pbrt-v4 warns and renders an imageless goniometric light as black.
    warn(what, fmt::format("{}: {} has no \"filename\": it emits nothing (as in pbrt-v4); skipped",
                           where(t), what));
    ++m_skipped_lights[type];
    return false;
  }
  const fs::path path = referenced_file(t, what, *file);
  Image image;
  try {
    image = read_image(path);
  } catch (const Error& e) {
    fail("{}: {}: {}", where(t), what, e.what());
  }
  if (const std::string bad = bad_emission_texel(image); !bad.empty())
    syntax(t, fmt::format("{}: '{}' has a negative or non-finite pixel, which no light can emit: "
                          "{}",
                          what, *file, bad));
  const auto inv = inverse(m_state.ctm);
  if (!inv)
    syntax(t, fmt::format("{}: the transform is singular (it has no inverse); matrix {}", what,
                          matrix_text(m_state.ctm)));
  Vec3 row[3];
  for (int i = 0; i < 3; ++i)
    row[i] = Vec3(to_float(inv->m[i][0]), to_float(inv->m[i][1]), to_float(inv->m[i][2]));
  Vec3 to_light[3];
  if (gonio) {
    if (image.width() != image.height())
      syntax(t, fmt::format("{}: '{}' is {}x{}: a goniometric image must be square (equal-area)",
                            what, *file, image.width(), image.height()));
    // pbrt-v4 reads the mean of R, G and B.
    for (Rgb& c : image.pixels()) c = Rgb((c.x + c.y + c.z) / 3);
    to_light[0] = row[0];
    to_light[1] = row[2];
    to_light[2] = row[1];
  } else {
    const float aspect = float(image.width()) / float(image.height()),
                tan_half = std::tan(radians(fov) / 2);
    const float xmax = aspect > 1 ? aspect : 1, ymax = aspect > 1 ? 1 : 1 / aspect;
    to_light[0] = row[0] / (tan_half * xmax);
    to_light[1] = -row[1] / (tan_half * ymax);
    to_light[2] = row[2];
  }
  const uint32_t index = uint32_t(m_scene.textures.size());
  Light l = make_image_light(gonio ? LightType::Goniometric : LightType::Projection,
                             apply_point(m_state.ctm, Vec3(0)), to_light, I, index, 0);
  l.area = image_light_power_factor(l, image);
  if (power) {
    if (!(l.area > 0)) syntax(t, fmt::format("{}: \"power\" asks to normalize a black image", what));
    l.radiance *= *power / l.area;
  }
  add_light(t, type, l);
  m_scene.textures.push_back(std::move(image));
  return true;
}

void PbrtReader::add_light(const Token& t, const std::string& type, const Light& l) {
  const std::string what = fmt::format("{}: LightSource \"{}\"", where(t), type);
  if (const std::string why = light_parameter_problem(l); !why.empty())
    fail(
        "{}: {}; a light's parameters must be finite and its emission not negative (is a value "
        "or a scale too large?)",
        what, why);
  m_lights.push_back(l);
  m_light_where.push_back(what);
}

// Several infinite lights as one sky: constant ones sum exactly; with maps, their sum is
// resampled into one equal-area map in the world's frame, as fine as the finest of them (within
// 64 and 2048 pixels a side).
void PbrtReader::combine_infinite_lights() {
  SkyDome& sky = *m_scene.sky;
  int res = 0;
  Rgb constant(0);
  for (const InfiniteLight& l : m_infinite)
    if (l.map)
      res = std::max({res, l.map->image.width(), l.map->image.height()});
    else
      constant += l.radiance;
  if (res == 0) {
    sky.radiance = constant;
    sky.map = nullptr;
    return;
  }
  res = std::clamp(res, 64, 2048);
  auto map = std::make_shared<EnvironmentMap>();
  map->mapping = EnvironmentMap::Mapping::EqualArea;
  map->image = Image(res, res);
  parallel_for_each(size_t(res), [&](size_t y) {
    for (int x = 0; x < res; ++x) {
      const Vec3 d = equal_area_square_to_sphere({(x + 0.5f) / float(res), (float(y) + 0.5f) / float(res)});
      Rgb v = constant;
      for (const InfiniteLight& l : m_infinite)
        if (l.map) v += l.radiance * l.map->lookup(d);
      map->image.at(x, int(y)) = v;
    }
  });
  sky.radiance = Rgb(1);
  sky.map = std::move(map);
}

void PbrtReader::end_object() {
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
  m_objects[m_object_name] = std::make_shared<const ObjectMesh>(std::move(obj));
  m_object = false;
}

void PbrtReader::instance(const Token& t, const std::shared_ptr<const ObjectMesh>& obj) {
  // Each instance is a copy of the object's triangles: the copies are counted here and made at
  // the end of the file.
  const size_t count = obj->mesh.triangle_count();
  if (const std::string why = triangle_budget_problem(double(triangles_so_far() + count), m_policy);
      !why.empty())
    syntax(t, fmt::format("ObjectInstance of {} triangles (instance {} of the file): {}", count,
                          m_instances.size() + 1, why));
  if (const std::string why = transform_problem(m_state.ctm); !why.empty())
    syntax(t, "ObjectInstance: " + why);
  const Affine x = to_affine(m_state.ctm);
  m_instances.emplace_back(obj, x);
  m_instanced_triangles += count;
}

void PbrtReader::finish() {
  for (const auto& [obj, x] : m_instances) {
    const size_t t0 = m_scene.mesh.triangle_count(), v0 = m_scene.mesh.positions.size();
    m_scene.mesh.append(obj->mesh, 0);
    transform_mesh(m_scene.mesh, x, t0, v0);
  }
  m_instances.clear();
  m_instanced_triangles = 0;
  // pbrt-v4's imaging ratio scales the whole image linearly: rll scales every emitter instead.
  if (const float ratio = m_exposure_time * m_iso / 100; ratio != 1) {
    for (size_t i = m_first_material; i < m_scene.materials.size(); ++i)
      m_scene.materials[i].emission *= ratio;
    for (size_t i = 0; i < m_lights.size(); ++i) {
      m_lights[i].radiance *= ratio;
      if (const std::string why = light_parameter_problem(m_lights[i]); !why.empty())
        fail("{}: {} once scaled by the film's imaging ratio {} (exposure time x iso / 100)",
             m_light_where[i], why, ratio);
    }
    if (m_scene.sky) m_scene.sky->radiance *= ratio;
    for (auto& l : m_infinite) l.radiance *= ratio;
  }
  m_scene.lights.insert(m_scene.lights.end(), m_lights.begin(), m_lights.end());
  if (m_has_camera) {
    const Mat4& c = m_world_from_camera;
    const Vec3 pos = apply_point(c, Vec3(0)), fwd = normalize(apply_vector(c, Vec3(0, 0, 1))),
               up = normalize(apply_vector(c, Vec3(0, 1, 0))),
               right = apply_vector(c, Vec3(1, 0, 0));
    if (!is_finite(pos) || !is_finite(fwd) || !is_finite(up) || !(length_sq(cross(fwd, up)) > 0))
      fail(
          "{}: the camera transform is degenerate: it places the camera at ({}, {}, {}) looking "
          "along ({}, {}, {}) with up ({}, {}, {}); camera-to-world matrix {}",
          m_names[0], pos.x, pos.y, pos.z, fwd.x, fwd.y, fwd.z, up.x, up.y, up.z, matrix_text(c));
    Camera& cam = m_scene.camera;
    cam.position = pos;
    cam.target = pos + fwd;
    cam.up = up;
    // pbrt's fov spans the shorter image side; rll's the vertical one.
    const float w = float(m_scene.width), h = float(m_scene.height);
    cam.fov = m_camera_fov;
    if (h > w) cam.fov = 2 * std::atan(std::tan(radians(m_camera_fov) / 2) * h / w) * (180 / kPi);
    // pbrt-v4 frames the screen window by "frameaspectratio" where no screenwindow is given;
    // rll by the film's aspect ratio: the same where they agree.
    if (m_frame_aspect && !m_screen_window && std::abs(*m_frame_aspect - w / h) > 1e-3f * (w / h))
      m_warnings.push_back(
          {fmt::format("{}: Camera: \"float frameaspectratio\" {} is ignored: rll frames the "
                       "image by the film's aspect ratio, {}x{} ({})",
                       m_frame_aspect_where, *m_frame_aspect, m_scene.width, m_scene.height, w / h),
           1});
    cam.lens_radius = m_lens_radius;
    cam.focal_distance = m_focal_distance;
    if (m_screen_window) {
      // pbrt's screen units are tan(fov / 2) of the shorter side; rll's of the vertical one.
      const float k = h > w ? w / h : 1;
      for (int i = 0; i < 4; ++i) cam.screen_window[size_t(i)] = (*m_screen_window)[size_t(i)] * k;
    }
    m_scene.has_camera = true;
    // pbrt's camera space is left-handed: the image's right is the camera's +x, which for most
    // transforms is the mirror image of rll's right (forward x up). Mirroring the world through
    // the plane of the camera's forward and up vectors renders the image pbrt renders.
    const Vec3 rll_right = normalize(cross(fwd, up));
    if (dot(rll_right, right) < 0) mirror_world(pos, rll_right);
  }
  // World directions to each map's frame (pbrt looks maps up in the light's space, and rll's
  // world may have been mirrored).
  for (InfiniteLight& l : m_infinite) {
    if (!l.map) continue;
    auto map = std::make_shared<EnvironmentMap>(*l.map);
    const Mat4& lw = l.light_from_world;
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
    l.map = std::move(map);
  }
  if (m_infinite.size() == 1) {
    m_scene.sky->map = m_infinite[0].map;
  } else if (m_infinite.size() > 1) {
    combine_infinite_lights();
  }
  summarize_skipped();
  for (const auto& [message, count] : m_warnings)
    m_scene.warnings.push_back(count > 1 ? fmt::format("{} (and {} more times)", message, count - 1)
                                         : message);
}

// One warning at the end listing what the scene has and the image will not show, so that a
// missing object is never silent even among many other warnings.
void PbrtReader::summarize_skipped() {
  auto list = [](const std::map<std::string, int>& m) {
    std::string s;
    int total = 0;
    for (const auto& [name, n] : m) {
      s += fmt::format("{}{} x{}", s.empty() ? "" : ", ", name, n);
      total += n;
    }
    return std::make_pair(total, s);
  };
  std::vector<std::string> parts;
  if (!m_skipped_shapes.empty()) {
    auto [n, s] = list(m_skipped_shapes);
    parts.push_back(fmt::format("{} shape{} skipped ({})", n, n == 1 ? "" : "s", s));
  }
  if (!m_skipped_lights.empty()) {
    auto [n, s] = list(m_skipped_lights);
    parts.push_back(fmt::format("{} light{} skipped ({})", n, n == 1 ? "" : "s", s));
  }
  if (!m_skipped_textures.empty()) {
    auto [n, s] = list(m_skipped_textures);
    parts.push_back(fmt::format("{} texture{} skipped ({})", n, n == 1 ? "" : "s", s));
  }
  if (!m_unsupported_materials.empty()) {
    std::string s;
    for (const auto& name : m_unsupported_materials) s += (s.empty() ? "" : ", ") + name;
    parts.push_back(fmt::format("materials not supported: {} (rendered as diffuse grey)", s));
  }
  if (parts.empty()) return;
  std::string msg = m_names[0] + ": summary: ";
  for (size_t i = 0; i < parts.size(); ++i) msg += (i ? "; " : "") + parts[i];
  m_warnings.push_back({msg, 1});
}

void PbrtReader::mirror_world(const Vec3& origin, const Vec3& n) {
  m_mirrored = true;
  m_mirror_normal = n;
  auto point = [&](const Vec3& p) { return p - n * (2 * dot(p - origin, n)); };
  auto vector = [&](const Vec3& v) { return v - n * (2 * dot(v, n)); };
  Mesh& mesh = m_scene.mesh;
  for (auto& p : mesh.positions) p = point(p);
  for (auto& v : mesh.normals) v = vector(v);
  for (auto& tri : mesh.triangles) std::swap(tri[1], tri[2]);
  for (auto& l : m_scene.lights) {
    if (l.type == LightType::Point || l.type == LightType::Spot) l.p0 = point(l.p0);
    if (l.type == LightType::Spot) l.n = vector(l.n);
    if (l.has_image()) {
      l.p0 = point(l.p0);
      l.p1 = vector(l.p1);
      l.p2 = vector(l.p2);
      l.n = vector(l.n);
    }
    if (l.type == LightType::Directional) l.p0 = vector(l.p0);
  }
  if (m_scene.sky) m_scene.sky->up = vector(m_scene.sky->up);
}

}  // namespace rll::pbrt
