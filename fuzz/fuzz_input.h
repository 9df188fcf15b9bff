// One untrusted input through one reader (a scene parser, the gzip inflater, the EXR reader, the
// image decoder), as the fuzz targets and the regression test run it: an rll::Error is a clean
// rejection; anything else (another exception, a crash, a sanitizer report) is a bug.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

#include "rll/core/image.h"
#include "rll/core/memory_budget.h"
#include "rll/io/load.h"

namespace rll::fuzz {

enum class Format { Ply, Gltf, Pbrt, Json, Obj, Gzip, Exr, Image };

// The memory budget an untrusted input is read under: far below the fuzzers' 1 GiB limit on
// resident memory, so that a size claim within it cannot exceed the limit either.
inline constexpr size_t kFuzzBudget = size_t(256) << 20;
struct FuzzBudget {
  FuzzBudget() { set_memory_budget_bytes(kFuzzBudget); }
  ~FuzzBudget() { set_memory_budget_bytes(0); }
};

// The EXR reader takes a path (OpenEXR reads files): the input is written to one file per process
// in the temporary folder, read as a texture is and as a share or reference is.
inline void read_untrusted_exr(std::string_view bytes) {
  static const std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("rll-fuzz-" + std::to_string(::getpid()) + ".exr");
  {
    std::ofstream f(path, std::ios::binary | std::ios::trunc);
    f.write(bytes.data(), std::streamsize(bytes.size()));
  }
  try {
    read_image(path);
    read_exr_file(path);
  } catch (...) {
    std::filesystem::remove(path);
    throw;
  }
  std::filesystem::remove(path);
}

// An OBJ input carries its MTL after this line: the part before it is the OBJ, the part after
// it is served from memory as "fuzz.mtl" (the name the seeds' mtllib gives), so that one target
// fuzzes both readers and how they meet.
inline constexpr std::string_view kMtlSeparator = "\n#--- fuzz.mtl ---\n";

// Parses `bytes` with file access turned off, the geometry capped and the memory budget small, so
// that a small input can neither read files nor allocate without bound. A PLY input that begins
// with gzip's magic bytes goes through gunzip first; a gzip input is inflated as a .ply.gz is
// (within what its PLY header declares) and then parsed.
inline void parse_untrusted(Format format, std::string_view bytes) {
  FuzzBudget budget;
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
    case Format::Gzip:
      parse_ply(gunzip(bytes, "fuzz.ply.gz", 0,
                       [&](std::string_view head) {
                         return ply_declared_bytes(head, "fuzz.ply.gz", bytes.size());
                       }),
                "fuzz.ply.gz");
      break;
    case Format::Exr:
      read_untrusted_exr(bytes);
      break;
    case Format::Image:
      // What stb_image reads (PNG, JPEG, Radiance HDR, BMP, ...), as a glTF image or a texture
      // in memory is decoded: its size claims checked before anything is allocated for them.
      decode_image(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size(), true,
                   "fuzz.png");
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
