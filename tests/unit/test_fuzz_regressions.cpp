// Every input under tests/fuzz/ (crashes the fuzzers found, and hand-made hostile files) goes
// through its parser as the fuzz targets run it: it may be rejected with an rll::Error, but never
// with anything else, nor take more than 1 GiB (under `make test-asan`, never with a sanitizer
// report either).
#include <gtest/gtest.h>

#include <filesystem>

#include "../../fuzz/fuzz_input.h"
#include "rll/core/error.h"
#include "rll/io/text_scan.h"
#include "support/test_support.h"

using namespace rll;
namespace fs = std::filesystem;

TEST(FuzzRegressions, EveryInputIsParsedOrCleanlyRejected) {
  ::testing::FLAGS_gtest_death_test_style = "threadsafe";
  const fs::path root = fs::path(RLL_SOURCE_DIR) / "tests" / "fuzz";
  const std::pair<const char*, fuzz::Format> formats[] = {
      {"ply", fuzz::Format::Ply},   {"gltf", fuzz::Format::Gltf},  {"pbrt", fuzz::Format::Pbrt},
      {"json", fuzz::Format::Json}, {"obj", fuzz::Format::Obj},    {"gzip", fuzz::Format::Gzip},
      {"exr", fuzz::Format::Exr},   {"image", fuzz::Format::Image}};
  for (const auto& [folder, format] : formats) {
    size_t inputs = 0;
    for (const auto& entry : fs::directory_iterator(root / folder)) {
      SCOPED_TRACE(entry.path().string());
      const std::string bytes = read_text_file(entry.path());
      // As the fuzzers run it (-rss_limit_mb=1024): in a child whose address space may grow by
      // 1 GiB at most, so that an input the fuzzer found taking too much memory fails here too.
      auto parse = [&] {
        try {
          fuzz::parse_untrusted(format, bytes);
        } catch (const Error& e) {
          if (std::string(e.what()).empty()) std::_Exit(4);
          throw;
        }
      };
      EXPECT_EXIT(test::run_in_bounded_memory(parse, size_t(1) << 30, true),
                  ::testing::ExitedWithCode(0), "");
      ++inputs;
    }
    EXPECT_GT(inputs, 0u) << folder;
  }
}
