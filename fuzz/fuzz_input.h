// One untrusted input through one scene parser, as the fuzz targets and the regression test
// run it: an rll::Error is a clean rejection; anything else (another exception, a crash, a
// sanitizer report) is a bug.
#pragma once

#include <string_view>

#include "rll/scene/load.h"

namespace rll::fuzz {

enum class Format { Ply, Gltf, Pbrt };

// Parses `bytes` with file access turned off and the geometry capped, so that a small input
// can neither read files nor allocate without bound.
inline void parse_untrusted(Format format, std::string_view bytes) {
  ReadPolicy policy;
  policy.read_files = false;
  policy.max_triangles = size_t(1) << 20;
  Scene scene;
  switch (format) {
    case Format::Ply:
      parse_ply(bytes, "fuzz.ply");
      break;
    case Format::Gltf:
      parse_gltf(bytes, "fuzz.gltf", "", scene, policy);
      break;
    case Format::Pbrt:
      parse_pbrt(bytes, "fuzz.pbrt", "", scene, policy);
      break;
  }
}

}  // namespace rll::fuzz
