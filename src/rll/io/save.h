// Writes a scene in rll's JSON format, its geometry in one OBJ + MTL beside it, so that
// load_scene reads the same scene back (used by `rll convert`).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "rll/scene/scene.h"

namespace rll {

// Writes `json` (which must end in .json) and, beside it, <stem>.obj, <stem>.mtl and each used
// texture as <stem>_tex<N>.exr, every file atomically. The sky dome is written as the "sky"
// entry, not as triangles; point and directional lights as "lights"; triangle lights come back
// from their emissive materials. Materials are written exactly in the JSON and approximately in
// the MTL (for other programs). An animation is not saved: the scene is written as it is now.
void save_json_scene(const Scene& scene, const std::filesystem::path& json);

// The other formats rll reads, written with the mappings of docs/scene-format.md run backwards.
// What a format cannot hold (a sky in glTF, a conductor's tint in pbrt) is written as closely as
// it can be and named in the returned warnings.
// glTF 2.0 (.gltf): one buffer embedded as base64, textures as PNG files beside it.
std::vector<std::string> save_gltf_scene(const Scene& scene, const std::filesystem::path& gltf);
// pbrt-v4 (.pbrt): meshes as binary PLY files and textures as EXR files beside it.
std::vector<std::string> save_pbrt_scene(const Scene& scene, const std::filesystem::path& pbrt);

// The triangles of one material (sky dome excluded) as a mesh of their own: the writers' unit.
struct MaterialMesh {
  uint32_t material = 0;
  Mesh mesh;  // positions, normals, uvs and triangles; no material or light ids
};
std::vector<MaterialMesh> split_by_material(const Scene& scene);

enum class PlyEncoding { Ascii, BinaryLittleEndian, BinaryBigEndian };
// A mesh as the bytes of a PLY file: float positions, normals and uvs when the mesh has them,
// and triangles as uchar-counted int lists (for tests, benchmarks and other programs).
std::string ply_bytes(const Mesh& mesh, PlyEncoding encoding);

}  // namespace rll
