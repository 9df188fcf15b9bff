// Small helpers on file paths shared by the readers, the writers and the command line.
#pragma once

#include <algorithm>
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

// NAME.0007.exr for item 7 of `count`: the number before the extension, with at least four
// digits and as many as the last item needs, so that the names sort in order; `p` itself when
// there is only one.
inline std::filesystem::path numbered_path(const std::filesystem::path& p, int index, int count) {
  if (count <= 1) return p;
  const std::string digits = std::to_string(index), last = std::to_string(count - 1);
  const size_t width = std::max<size_t>(4, last.size());
  std::filesystem::path q = p;
  q.replace_extension("." + std::string(width - std::min(width, digits.size()), '0') + digits +
                      p.extension().string());
  return q;
}

}  // namespace rll
