// The pbrt-v4 reader's internals, shared by its source files (load_pbrt.cpp is the entry point;
// pbrt_tokenizer.cpp: tokens and the token stream across included files; pbrt_params.cpp:
// parameter lists; pbrt_directives.cpp: the main loop, transforms, graphics state, includes,
// camera, film, lights, objects; pbrt_materials.cpp: materials and textures; pbrt_shapes.cpp:
// shapes). Private to src/rll/io.
#pragma once

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include "rll/core/error.h"
#include "rll/io/load.h"
#include "rll/io/text_scan.h"
#include "rll/scene/transform.h"

namespace rll::pbrt {
namespace fs = std::filesystem;

// Tessellation of pbrt's analytic shapes (documented in docs/scene-format.md).
inline constexpr int kSphereSegments = 48, kSphereRings = 24;  // a full sphere: 2208 triangles
inline constexpr int kDiskSegments = 64;
inline constexpr int kBilinearGrid = 8;  // a non-planar bilinear patch: 8 x 8 quads
inline constexpr int kInfiniteLightTriangles = 2048;
inline constexpr int kMaxIncludeDepth = 32;

// --- 4x4 matrices in double, as pbrt composes its transforms ---

struct Mat4 {
  double m[4][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}};
};

Mat4 operator*(const Mat4& a, const Mat4& b);
// Inverse by Gauss-Jordan elimination with partial pivoting; nullopt when singular.
std::optional<Mat4> inverse(const Mat4& a);
Vec3 apply_point(const Mat4& t, const Vec3& p);
Vec3 apply_vector(const Mat4& t, const Vec3& d);
Affine to_affine(const Mat4& t);
Mat4 translate(double x, double y, double z);
Mat4 scale(double x, double y, double z);
// Rotation by `deg` degrees about `axis` (pbrt's Rotate).
Mat4 rotate(double deg, double ax, double ay, double az);
// "[1e+30 0 0 0; 0 1e+30 0 0; 0 0 1e+30 0; 0 0 0 1]": a matrix row by row, for messages.
std::string matrix_text(const Mat4& m);
// Why rll cannot apply `m` to geometry (its 3x3 part and offset, in float), "" when it can: it
// is singular (determinant 0), or scales beyond what a float holds, or below it; the message
// says which, by how much, and shows the matrix.
std::string transform_problem(const Mat4& m);

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

  bool next(Token& t);

 private:
  static bool is_space(char c) {
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v';
  }
  std::string_view m_text;
  size_t m_pos = 0, m_line = 1;
  uint32_t m_file;
  std::string m_name, m_included_from;
};

std::string unescape(std::string_view s);

// --- parameter lists ---

struct Param {
  std::string type, name;
  std::vector<double> numbers;       // the values of every numeric type but "integer"
  std::vector<int64_t> integers;     // "integer" values, read exactly from their text
  std::vector<std::string> strings;  // string, texture, bool and named-spectrum values
  size_t line = 0;
  mutable bool used = false;
};

inline constexpr const char* kParamTypes[] = {
    "integer", "float", "point2", "vector2",  "point3",    "vector3", "normal3", "normal", "point",
    "vector",  "rgb",   "color",  "spectrum", "blackbody", "bool",    "string",  "texture"};

bool is_numeric_type(const std::string& t);

const std::set<std::string_view>& pbrt_directives();

struct GraphicsState {
  Mat4 ctm;           // object to world (before WorldBegin: world to camera)
  int material = -1;  // index into the scene's materials; -1: pbrt's default diffuse
  bool reverse_orientation = false;
  bool emissive = false;  // an AreaLightSource is active
  Rgb emission;
  bool two_sided = false;
  float area_power = 0;  // the AreaLightSource's "power" (> 0), or 0
  // An image area light ("filename"): its image (index into Scene::textures), emission being its
  // scale, and the image's mean luminance (pbrt-v4's power normalization divides by it).
  int emission_texture = -1;
  float texture_luminance = 1;
};

// A texture as materials see it: an image (index into Scene::textures) times `scale`, or, with
// index -1, the constant `scale`. Float textures use the first channel.
struct ImageTexture {
  int index = -1;
  Rgb scale{1};
};

// One ObjectBegin/End block: its triangles, in the world space of their definition.
struct ObjectMesh {
  Mesh mesh;
};
class PbrtReader {
 public:
  PbrtReader(const fs::path& base_dir, Scene& scene, const ReadPolicy& policy)
      : m_base(base_dir), m_scene(scene), m_policy(policy) {}

  void read(std::string_view text, const std::string& name);

 private:
  // --- token stream across included files ---

  void push_file(std::string_view text, const std::string& name, const std::string& key,
                 const std::string& included_from);

  std::optional<Token> take();

  const Token* peek();

  std::string where(const Token& t) const { return where(t.file, t.line); }
  std::string where(size_t file, size_t line) const;

  [[noreturn]] void syntax(const Token& t, const std::string& what) const {
    fail("{}: {}", where(t), what);
  }

  void warn(const std::string& key, const std::string& message);

  bool is_directive(const Token& t) const;

  double number(const Token& t) const;
  // The value of an integer parameter, read exactly from the token's text (not through a float):
  // anything but a whole number that fits in 64 bits is an error naming the parameter.
  int64_t integer(const Token& t, const std::string& what, const std::string& param) const;

  Token expect_token(const Token& after, const char* what);

  double expect_number(const Token& after) { return number(expect_token(after, "a number")); }

  std::string expect_string(const Token& after);

  // Numbers in [ ... ] (or, where `bare` is set, the same count without brackets).
  std::vector<double> number_list(const Token& after, size_t count, bool bare);

  // The parameter list after a directive; `what` names the directive in errors.
  std::vector<Param> param_list(const std::string& what);

  // --- typed parameter access ---

  class Params {
   public:
    // Reads the parameter list that follows the directive.
    Params(PbrtReader& r, const Token& directive, std::string what)
        : m_r(r), m_at(directive), m_what(std::move(what)), m_params(r.param_list(m_what)) {}
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
      if (p->integers.size() != 1)
        bad(*p, fmt::format("needs 1 value (got {})", p->integers.size()));
      const int64_t v = p->integers[0];
      if (v < INT32_MIN || v > INT32_MAX) bad(*p, fmt::format("is out of range (got {})", v));
      return int(v);
    }
    // All values of an "integer" array parameter, in groups of `group`.
    const std::vector<int64_t>* get_integers(const char* name, size_t group) const {
      const Param* p = typed(name, {"integer"});
      if (!p) return nullptr;
      if (p->integers.size() % group != 0)
        bad(*p, fmt::format("needs a multiple of {} values (got {})", group, p->integers.size()));
      return &p->integers;
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
    // All values of a numeric array parameter (not "integer": get_integers), in groups of
    // `group`.
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
    std::optional<Rgb> get_spectrum(const char* name) const;
    std::vector<std::string> names() const {
      std::vector<std::string> n;
      for (const auto& p : m_params) n.push_back(p.name);
      return n;
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
  void skip_arguments();

  void unsupported(const Token& t, const std::string& what);

  // --- directives ---

  void directive(const Token& t);

  void concat(const Token& t, const Mat4& m);

  void look_at(const Token& t, const std::vector<double>& v);

  fs::path resolve(const std::string& name) const;

  // A file the scene refers to: it must exist, and reading files must be allowed.
  fs::path referenced_file(const Token& t, const std::string& what, const std::string& name) const;

  void include(const Token& t);

  void camera(const Token& t);

  void film(const Token& t);

  // --- materials and textures ---

  std::optional<ImageTexture> texture_operand(const Token& t, const Params& p, const char* name,
                                              bool is_float);
  std::optional<ImageTexture> bake(const Token& t, const std::string& what,
                                   const std::vector<ImageTexture>& in,
                                   const std::function<Rgb(const Rgb*)>& f);
  std::optional<ImageTexture> image_texture(const Token& t, const std::string& name,
                                            const Params& p);
  void roughness(const Token& t, const Params& p, Material& m, const std::string& prefix,
                 float def);
  Rgb mean_value(const ImageTexture& tex) const;
  float ior_of(const Token& t, const std::string& material, const Params& p, const char* name,
               float def);

  // The reflectance of a material: a colour, or an image texture (times its scale).
  void reflectance(const Token& t, const Params& p, const char* name, Material& m, Rgb def);

  int make_material(const Token& t, const std::string& type, const Params& p);

  void texture(const Token& t);

  // --- lights ---

  void area_light(const Token& t);

  void light(const Token& t);

  void infinite_light(const Token& t, const Params& p, float s);
  std::optional<float> normalization(const Token& t, const Params& p, const char* name);
  void combine_infinite_lights();
  bool image_light(const Token& t, const Params& p, const std::string& type, float s);
  // Adds a light, refusing one whose parameters came out non-finite or negative (say, an
  // intensity that overflows a float once scaled), with the file, line and light named.
  void add_light(const Token& t, const std::string& type, const Light& l);

  // --- shapes ---

  static constexpr int kInvisible = -2;

  // The material of the next shape (at `t`), with the active area light's emission times `k`.
  uint32_t shape_material(const Token& t, float k = 1);
  static constexpr size_t kMaxEmissiveMaterials = 1 << 16;

  void shape(const Token& t);

  void add_mesh(const Token& t, Mesh mesh, bool quadric);

  void triangle_mesh(const Token& t, const Params& p, Mesh& mesh);

  uint32_t index(const Token& t, const char* shape, int64_t v, size_t count) const;

  // P, and N and uv when given, which must have one entry per vertex.
  void fill_vertices(const Token& t, const Params& p, Mesh& mesh, const std::vector<double>& P,
                     const char* shape);

  // pbrt's "loopsubdiv": Loop subdivision to "levels" (3), pushed to the limit surface.
  void loop_subdivision(const Token& t, const Params& p, Mesh& mesh);
  void bilinear_mesh(const Token& t, const Params& p, Mesh& mesh);

  void sphere(const Token& t, const Params& p, Mesh& mesh);

  void disk(const Token& t, const Params& p, Mesh& mesh);

  // Winds every triangle of a closed convex-ish shape around the origin with its normal out.
  static void orient_outward(Mesh& mesh);

  // --- objects ---

  void end_object();

  void instance(const Token& t, const std::shared_ptr<const ObjectMesh>& obj);
  // The scene's triangles so far, the instances still to be built included.
  size_t triangles_so_far() const { return m_scene.mesh.triangle_count() + m_instanced_triangles; }

  // --- the end: camera, mirror, lights, warnings ---

  void finish();

  void summarize_skipped();
  void mirror_world(const Vec3& origin, const Vec3& n);

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
  std::vector<bool> m_begun;                 // per file: whether a directive was read
  std::vector<Tokenizer> m_tokenizers;
  std::vector<std::string> m_open;  // canonical paths of the files being read
  std::optional<Token> m_peeked;

  GraphicsState m_state;
  std::vector<Saved> m_stack;
  std::map<std::string, Mat4> m_named_frames;
  std::map<std::string, int> m_named_materials;
  std::map<std::string, ImageTexture> m_textures;
  std::set<std::string> m_unread_textures;  // names of the Texture directives rll skipped
  std::map<std::string, int> m_image_cache;
  std::map<std::tuple<int, int, float, float, bool>, ImageTexture> m_alpha_cache;
  // (image, scale) -> the image times its scale clamped to [0, 1] (a reflectance above 1)
  std::map<std::tuple<int, float, float, float>, ImageTexture> m_clamped_cache;
  std::map<std::tuple<int, float, float, float, bool, int>, uint32_t> m_emissive;
  int m_default_material = -1;

  bool m_object = false;
  std::string m_object_name;
  size_t m_object_triangle = 0, m_object_vertex = 0;
  // Shared with the instances not yet built, so that a redefinition leaves them theirs.
  std::map<std::string, std::shared_ptr<const ObjectMesh>> m_objects;
  // Instances are built at the end of the file, once their triangles are counted: a file that
  // instances more than the memory budget holds is refused before any copy is made.
  std::vector<std::pair<std::shared_ptr<const ObjectMesh>, Affine>> m_instances;
  size_t m_instanced_triangles = 0;

  bool m_has_camera = false;
  float m_camera_fov = 90;
  float m_lens_radius = 0, m_focal_distance = 1e6f;
  std::optional<std::array<float, 4>> m_screen_window;  // pbrt's screen units
  float m_exposure_time = 1, m_iso = 100;
  size_t m_first_material = 0;  // the scene's materials before this file's
  Mat4 m_world_from_camera;
  std::optional<float> m_frame_aspect;  // the Camera's "frameaspectratio", where given
  std::string m_frame_aspect_where;
  std::vector<Light> m_lights;
  std::vector<std::string> m_light_where;  // per light: "FILE:LINE: LightSource \"KIND\""
  // The bilinear patch of each triangle of the shape being read (bilinear meshes only).
  std::vector<uint32_t> m_shape_of_triangle;
  // Every infinite light read: its radiance scale, map (or none) and, with a map, the light's
  // frame from world space. finish() makes the scene's one sky of them.
  struct InfiniteLight {
    Rgb radiance;
    std::shared_ptr<EnvironmentMap> map;
    Mat4 light_from_world;
  };
  std::vector<InfiniteLight> m_infinite;
  bool m_mirrored = false;
  Vec3 m_mirror_normal;

  // What was left out, for the summary warning at the end: shape types, light types and texture
  // classes (with counts), and material types rendered as diffuse grey.
  std::map<std::string, int> m_skipped_shapes, m_skipped_lights, m_skipped_textures;
  std::set<std::string> m_unsupported_materials;

  std::vector<std::pair<std::string, size_t>> m_warnings;
  std::map<std::string, size_t> m_warning_index;
};

}  // namespace rll::pbrt
