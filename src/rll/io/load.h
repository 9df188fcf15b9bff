// Scene loading: builtin:NAME, or a scene file chosen by its extension (JSON, OBJ, glTF, PLY,
// pbrt).
#pragma once

#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <string_view>

#include "rll/scene/scene.h"

namespace rll {

struct LoadOptions {
  int width = 0, height = 0;  // film size override; 0 keeps the scene's
  bool print_warnings = true;  // print Scene::warnings to stderr as "rll: warning: ..."
};

// Loads and finalizes a scene; throws rll::Error naming the file (and line where known).
Scene load_scene(const std::string& spec, const LoadOptions& options = {});
// Reads a scene without finalizing it (no light, camera or sky dome is required or added), as
// `rll convert` writes it back out.
Scene read_scene(const std::string& spec);

// What a reader may do beyond parsing the bytes it is given. The fuzz targets turn file access
// off (a reference to another file is then an error) and cap the geometry a small input may
// multiply into (instances, tessellated shapes).
struct ReadPolicy {
  bool read_files = true;
  size_t max_triangles = size_t(1) << 31;
  // Files served from memory by the name the scene gives them, before the disk is tried (the
  // fuzz target for OBJ hands the reader its MTL this way). Only the OBJ reader looks here.
  std::map<std::string, std::string> memory_files;
};

// What one triangle costs a loaded scene, all told, as the load's estimate: its indices,
// material and light (20 bytes), its share of the vertices (positions, normals and uvs of about
// half a vertex, 16), and the acceleration structure over it with what its build needs (about
// 120).
inline constexpr double kSceneBytesPerTriangle = 160;
// Why a scene may not grow to `triangles` triangles ("" when it may): more than the policy's
// `max_triangles`, or more than the memory budget (memory_budget_bytes()) holds at
// kSceneBytesPerTriangle each. Every reader asks before building what multiplies geometry
// (instances, subdivision, tessellated shapes), and prefixes the answer with what asked.
std::string triangle_budget_problem(double triangles, const ReadPolicy& policy);

// Format readers. Each appends what it reads to `scene` (geometry, materials, textures,
// lights, camera when the format has one) without finalizing it.
void load_json_scene(const std::filesystem::path& path, Scene& scene);
// Wavefront OBJ + MTL through tinyobjloader: Kd, Ks, Ns, Ke, map_Kd (see docs/scene-format.md).
void load_obj(const std::filesystem::path& path, Scene& scene);
// Stanford PLY mesh (ASCII or binary) with a default diffuse material.
void load_ply(const std::filesystem::path& path, Scene& scene);
// glTF 2.0 (.gltf with its buffers and images, or .glb) through tinygltf.
void load_gltf(const std::filesystem::path& path, Scene& scene);
// A pbrt-v4 scene file (the subset in docs/scene-format.md).
void load_pbrt(const std::filesystem::path& path, Scene& scene);

// The parsers behind them, on bytes in memory (`name` is the file name for messages; relative
// references resolve against `base_dir`).
// A PLY file's triangles (polygons fan-triangulated), positions, and normals and uvs when it has
// them; `material` and `light` are left empty.
Mesh parse_ply(std::string_view bytes, const std::string& name);
// A PLY file from disk, gzip-compressed (.ply.gz, recognized by its magic bytes) or not.
Mesh read_ply_file(const std::filesystem::path& path);
// Whether `bytes` begin like gzip data, and that data inflated (concatenated members included);
// a truncated or corrupt stream is an error naming `name`, and so is more output than
// `max_bytes` (0: the memory budget, memory_budget_bytes()) or than `declared` allows:
// `declared` is asked with the output so far until it answers the most bytes the file can hold
// by what its beginning declares (0: not known yet), e.g. ply_declared_bytes.
bool is_gzip(std::string_view bytes);
std::string gunzip(std::string_view bytes, const std::string& name, size_t max_bytes = 0,
                   const std::function<size_t(std::string_view head)>& declared = {});
// The most bytes a PLY file can take by its header (its element counts times the largest entry
// each can have: a list its longest, an ASCII value 64 characters); 0 while `head` does not yet
// hold the whole header. A bad header is an error naming `name`, as parse_ply would give, and
// so is a header whose counts need more than the memory budget (the least data they take and
// the mesh they make), or, where the file is `compressed_bytes` of gzip data (0: unknown), more
// data than those bytes inflate to (kDeflateMaxRatio).
size_t ply_declared_bytes(std::string_view head, const std::string& name,
                          size_t compressed_bytes = 0);
// `bytes` as one gzip member at zlib's `level` (0-9, -1 its default): what a .ply.gz holds (tests,
// benchmarks and fuzz seeds write them).
std::string gzip(std::string_view bytes, int level = -1);
void parse_gltf(std::string_view bytes, const std::string& name,
                const std::filesystem::path& base_dir, Scene& scene,
                const ReadPolicy& policy = {});
// A JSON scene (docs/scene-format.md).
void parse_json_scene(std::string_view text, const std::string& name,
                      const std::filesystem::path& base_dir, Scene& scene,
                      const ReadPolicy& policy = {});
// A Wavefront OBJ file and the MTL files it names.
void parse_obj(std::string_view text, const std::string& name,
               const std::filesystem::path& base_dir, Scene& scene,
               const ReadPolicy& policy = {});
void parse_pbrt(std::string_view text, const std::string& name,
                const std::filesystem::path& base_dir, Scene& scene,
                const ReadPolicy& policy = {});

}  // namespace rll
