// Small helpers on file paths shared by the readers, the writers and the command line.
#pragma once

#include <cctype>
#include <filesystem>
#include <string>

namespace rll {

// A path's extension in lower case, dot included (".exr"); empty if it has none.
inline std::string lower_extension(const std::filesystem::path& p) {
  std::string e = p.extension().string();
  for (auto& c : e) c = char(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

}  // namespace rll
