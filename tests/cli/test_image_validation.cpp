// Image data the `rll` program reads as numbers: `rll error` and `rll compare` refuse the same
// references with the same message (NaN, infinite or negative values, 8-bit files, grey EXRs),
// and `merge` refuses shares missing a colour channel, counting more samples than their spp, or
// whose header claims more bytes than the file holds.
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <ImfStringAttribute.h>
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <fstream>
#include <limits>
#include <sstream>

#include "rll/core/image.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;
namespace fs = std::filesystem;

namespace {

// The line rll printed its error on ("rll: error: ..."); empty if none.
std::string error_line(const CommandResult& r) {
  const size_t at = r.output.find("rll: error: ");
  if (at == std::string::npos) return "";
  return r.output.substr(at, r.output.find('\n', at) - at);
}

void expect_refused(const CommandResult& r, std::initializer_list<std::string> parts) {
  EXPECT_GE(r.exit_code, 1) << r.output;
  EXPECT_LT(r.exit_code, 128) << r.output;
  expect_mentions(r.output, parts);
}

// Runs rll with its address space capped at 1.5 GiB, as a shell's `ulimit -v` does. Not under
// AddressSanitizer, which reserves terabytes of shadow address space as the program starts, so
// that no cap lets it start: there the refusal and its message are checked, and the Release
// build (`make test`) checks that it comes without the memory the file claims.
#if defined(__SANITIZE_ADDRESS__)
constexpr const char* kAddressSpaceCap = "";
#else
constexpr const char* kAddressSpaceCap = "ulimit -v 1572864 && ";
#endif
CommandResult run_rll_in_bounded_memory(const std::vector<std::string>& args) {
  std::string cmd = std::string(kAddressSpaceCap) + "exec '" RLL_BINARY "'";
  for (const auto& a : args) cmd += " '" + a + "'";  // temporary paths: no quotes in them
  cmd += " 2>&1";
  CommandResult r;
  FILE* pipe = ::popen(cmd.c_str(), "r");
  if (!pipe) return r;
  char buf[4096];
  for (size_t n; (n = std::fread(buf, 1, sizeof buf, pipe)) > 0;) r.output.append(buf, n);
  const int status = ::pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return r;
}

// Writes `file` as rll does, but with only the channels named in `channels` (of R, G, B and
// count).
void write_share_channels(const fs::path& path, const ExrFile& file,
                          std::initializer_list<const char*> channels) {
  const Image& im = file.image;
  Imf::Header header(im.width(), im.height());
  for (const auto& [name, value] : file.attributes)
    header.insert(name, Imf::StringAttribute(value));
  Imf::FrameBuffer fb;
  char* base = (char*)im.pixels().data();
  const size_t xs = sizeof(Rgb), ys = sizeof(Rgb) * size_t(im.width());
  for (const std::string c : channels) {
    if (c == "count") {
      header.channels().insert(c, Imf::Channel(Imf::UINT));
      fb.insert(c, Imf::Slice(Imf::UINT, (char*)file.counts.data(), sizeof(uint32_t),
                              sizeof(uint32_t) * size_t(im.width())));
    } else {
      header.channels().insert(c, Imf::Channel(Imf::FLOAT));
      fb.insert(c, Imf::Slice(Imf::FLOAT,
                              base + (c == "R"   ? 0
                                      : c == "G" ? 1
                                                 : 2) *
                                         sizeof(float),
                              xs, ys));
    }
  }
  Imf::OutputFile out(path.c_str(), header);
  out.setFrameBuffer(fb);
  out.writePixels(im.height());
}

// A one-channel (Y) EXR of the given size, 0.5 everywhere.
void write_luminance_exr(const fs::path& path, int w, int h) {
  Imf::Header header(w, h);
  header.channels().insert("Y", Imf::Channel(Imf::FLOAT));
  std::vector<float> y(size_t(w) * h, 0.5f);
  Imf::FrameBuffer fb;
  fb.insert("Y", Imf::Slice(Imf::FLOAT, (char*)y.data(), sizeof(float), sizeof(float) * size_t(w)));
  Imf::OutputFile out(path.c_str(), header);
  out.setFrameBuffer(fb);
  out.writePixels(h);
}

// A copy of `from` whose "rll.share" string attribute claims 2^31 - 1 bytes.
void write_with_huge_share_attribute(const fs::path& from, const fs::path& to) {
  std::stringstream ss;
  ss << std::ifstream(from, std::ios::binary).rdbuf();
  std::string bytes = ss.str();
  const std::string marker = std::string("rll.share") + '\0' + "string" + '\0';
  const size_t at = bytes.find(marker);
  ASSERT_NE(at, std::string::npos);
  for (int b = 0; b < 4; ++b) bytes[at + marker.size() + b] = b == 3 ? '\x7f' : '\xff';
  std::ofstream(to, std::ios::binary) << bytes;
}

}  // namespace

TEST(ImageValidation, ErrorAndCompareRefuseTheSameReferencesWithTheSameMessage) {
  TempDir dir;
  const int w = 32, h = 24;  // compare's film below
  const Image good(w, h, Rgb(0.5f));
  write_image(dir / "good.exr", good);
  Image nan = good, inf = good, negative = good;
  nan.at(5, 2).x = std::numeric_limits<float>::quiet_NaN();
  inf.at(0, 3).z = std::numeric_limits<float>::infinity();
  negative.at(7, 1).y = -0.25f;
  write_image(dir / "nan.exr", nan);
  write_image(dir / "inf.exr", inf);
  write_image(dir / "negative.exr", negative);
  write_image(dir / "ldr.png", good);
  write_luminance_exr(dir / "grey.exr", w, h);
  const std::vector<std::pair<std::string, std::string>> cases = {{"nan.exr", "pixel (5, 2)"},
                                                                  {"inf.exr", "pixel (0, 3)"},
                                                                  {"negative.exr", "pixel (7, 1)"},
                                                                  {"ldr.png", "8-bit"},
                                                                  {"grey.exr", "luminance"}};
  for (const auto& [name, why] : cases) {
    SCOPED_TRACE(name);
    const std::string ref = (dir / name).string();
    const CommandResult error = run_rll({"error", (dir / "good.exr").string(), ref});
    expect_refused(error, {ref, why});
    EXPECT_EQ(error.output.find("nan\n"), std::string::npos) << error.output;
    const CommandResult compare =
        run_rll({"compare", "builtin:cornell-box", "--samplers", "power", "--spp", "1", "--res",
                 fmt::format("{}x{}", w, h), "--reference", ref, "--out", (dir / "out").string(),
                 "--quiet"});
    expect_refused(compare, {ref, why});
    EXPECT_EQ(error_line(error), error_line(compare));
  }
  // The measured image and the variance are checked as well.
  expect_refused(run_rll({"error", (dir / "nan.exr").string(), (dir / "good.exr").string()}),
                 {"image '", "nan.exr", "pixel (5, 2)"});
  expect_refused(run_rll({"error", (dir / "good.exr").string(), (dir / "good.exr").string(),
                          "--reference-variance", (dir / "inf.exr").string()}),
                 {"reference variance '", "inf.exr", "pixel (0, 3)"});
}

TEST(ImageValidation, MergeRefusesSharesMissingAChannelOrCountingMoreThanTheirSpp) {
  TempDir dir;
  for (const char* task : {"0/2", "1/2"})
    ASSERT_EQ(run_rll({"render", "builtin:cornell-box", "--res", "8x6", "--spp", "2", "--task",
                       task, "--quiet", "-o", (dir / fmt::format("s{}.exr", task[0])).string()})
                  .exit_code,
              0);
  const std::string s0 = (dir / "s0.exr").string(), out = (dir / "merged.exr").string();
  const CommandResult ok = run_rll({"merge", out, s0, (dir / "s1.exr").string()});
  ASSERT_EQ(ok.exit_code, 0) << ok.output;
  const ExrFile s1 = read_exr_file(dir / "s1.exr");

  // A count of 1000 in a share of 2 spp would weigh its pixel 500 times.
  ExrFile heavy = s1;
  heavy.counts[8 + 3] = 1000;
  write_exr(dir / "heavy.exr", heavy);
  expect_refused(run_rll({"merge", out, s0, (dir / "heavy.exr").string()}),
                 {"heavy.exr", "pixel (3, 1)", "1000", "at most 2"});

  // Without R, the share's red would merge as black.
  write_share_channels(dir / "no_red.exr", s1, {"G", "B", "count"});
  expect_refused(run_rll({"merge", out, s0, (dir / "no_red.exr").string()}),
                 {"no_red.exr", "no channel R"});

  // A header attribute claiming 2 GiB in a file of a few hundred bytes: refused, never allocated.
  write_with_huge_share_attribute(dir / "s1.exr", dir / "huge.exr");
  ASSERT_LT(fs::file_size(dir / "huge.exr"), 4000u);
  const std::string huge = (dir / "huge.exr").string();
  expect_refused(run_rll_in_bounded_memory({"merge", out, s0, huge}),
                 {"huge.exr", "'rll.share'", "2147483647"});
  expect_refused(run_rll_in_bounded_memory({"error", huge, s0}), {"huge.exr", "'rll.share'"});
}
