// One untrusted input through one scene parser, as the fuzz targets and the regression test
// run it: an rll::Error is a clean rejection; anything else (another exception, a crash, a
// sanitizer report) is a bug.
#pragma once

#include <string>
#include <string_view>

#include "rll/io/load.h"

namespace rll::fuzz {

enum class Format { Ply, Gltf, Pbrt, Json, Obj };

// An OBJ input carries its MTL after this line: the part before it is the OBJ, the part after
// it is served from memory as "fuzz.mtl" (the name the seeds' mtllib gives), so that one target
// fuzzes both readers and how they meet.
inline constexpr std::string_view kMtlSeparator = "\n#--- fuzz.mtl ---\n";

// Parses `bytes` with file access turned off and the geometry capped, so that a small input
// can neither read files nor allocate without bound. A PLY input that begins with gzip's magic
// bytes goes through gunzip first (at most 16 MB out).
inline void parse_untrusted(Format format, std::string_view bytes) {
  ReadPolicy policy;
  policy.read_files = false;
  policy.max_triangles = size_t(1) << 20;
  Scene scene;
  switch (format) {
    case Format::Ply:
      // A gzip-compressed PLY (.ply.gz) is inflated as read_ply_file does, its output capped.
      if (is_gzip(bytes)) {
        parse_ply(gunzip(bytes, "fuzz.ply.gz", size_t(1) << 24), "fuzz.ply.gz");
        break;
      }
      parse_ply(bytes, "fuzz.ply");
      break;
    case Format::Gltf:
      parse_gltf(bytes, "fuzz.gltf", "", scene, policy);
      break;
    case Format::Pbrt:
      parse_pbrt(bytes, "fuzz.pbrt", "", scene, policy);
      break;
    case Format::Json:
      parse_json_scene(bytes, "fuzz.json", "", scene, policy);
      break;
    case Format::Obj: {
      const size_t cut = bytes.find(kMtlSeparator);
      if (cut != std::string_view::npos)
        policy.memory_files["fuzz.mtl"] = std::string(bytes.substr(cut + kMtlSeparator.size()));
      parse_obj(bytes.substr(0, cut), "fuzz.obj", "", scene, policy);
      break;
    }
  }
}

}  // namespace rll::fuzz
