// Every input under tests/fuzz/ (crashes the fuzzers found, and hand-made hostile files) goes
// through its parser as the fuzz targets run it: it may be rejected with an rll::Error, but never
// with anything else (under `make test-asan`, never with a sanitizer report either).
#include <gtest/gtest.h>

#include <filesystem>

#include "../../fuzz/fuzz_input.h"
#include "rll/core/error.h"
#include "rll/io/text_scan.h"

using namespace rll;
namespace fs = std::filesystem;

TEST(FuzzRegressions, EveryInputIsParsedOrCleanlyRejected) {
  const fs::path root = fs::path(RLL_SOURCE_DIR) / "tests" / "fuzz";
  const std::pair<const char*, fuzz::Format> formats[] = {
      {"ply", fuzz::Format::Ply},   {"gltf", fuzz::Format::Gltf}, {"pbrt", fuzz::Format::Pbrt},
      {"json", fuzz::Format::Json}, {"obj", fuzz::Format::Obj},   {"gzip", fuzz::Format::Gzip},
      {"exr", fuzz::Format::Exr}};
  for (const auto& [folder, format] : formats) {
    size_t inputs = 0;
    for (const auto& entry : fs::directory_iterator(root / folder)) {
      SCOPED_TRACE(entry.path().string());
      const std::string bytes = read_text_file(entry.path());
      try {
        fuzz::parse_untrusted(format, bytes);
      } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()), "");
      }
      ++inputs;
    }
    EXPECT_GT(inputs, 0u) << folder;
  }
}
