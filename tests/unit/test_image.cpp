// Image files: EXR keeps floats exactly, PNG keeps its 8-bit sRGB quantisation, and writes are
// atomic: no temporary file is left behind and a failed write leaves the old file as it was.
// Reads check a header's size claim before taking memory for it.
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <ImfTiledOutputFile.h>
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <unistd.h>

#include <chrono>
#include <csignal>
#include <fstream>
#include <functional>
#include <sstream>

#include "rll/core/error.h"
#include "rll/core/image.h"
#include "rll/core/rng.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;
namespace fs = std::filesystem;

namespace {

Image test_image(int w, int h, float scale, uint64_t seed) {
  Image img(w, h);
  Pcg32 rng(seed);
  for (auto& p : img.pixels())
    p = Rgb(rng.next_float(), rng.next_float(), rng.next_float()) * scale;
  return img;
}

std::string read_bytes(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

std::vector<std::string> folder_entries(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

float srgb_to_linear(float c) {
  return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

TEST(ImageFiles, ExrRoundTripIsExact) {
  TempDir dir;
  Image img = test_image(37, 23, 1000.0f, 1);
  img.at(0, 0) = Rgb(0, 1e-30f, 6.5e4f);  // tiny and half-overflowing values survive as floats
  img.at(36, 22) = Rgb(1e30f, 0.1f, 3);
  write_image(dir / "a.exr", img);
  Image back = read_image(dir / "a.exr");
  ASSERT_EQ(back.width(), img.width());
  ASSERT_EQ(back.height(), img.height());
  for (size_t i = 0; i < img.pixel_count(); ++i) ASSERT_EQ(back[i], img[i]) << "pixel " << i;
}

TEST(ImageFiles, PngRoundTripKeepsSrgbQuantisation) {
  TempDir dir;
  Image img = test_image(19, 11, 1.2f, 2);  // some values above 1 clip to white
  for (float exposure : {0.0f, -1.0f}) {
    write_image(dir / "a.png", img, exposure);
    Image back = read_image(dir / "a.png");
    ASSERT_EQ(back.width(), img.width());
    ASSERT_EQ(back.height(), img.height());
    const float scale = std::exp2(exposure);
    for (size_t i = 0; i < img.pixel_count(); ++i)
      for (int c = 0; c < 3; ++c) {
        float expected = srgb_to_linear(to_srgb8(img[i][c], scale) / 255.0f);
        ASSERT_NEAR(back[i][c], expected, 1e-6f) << "pixel " << i << " channel " << c;
        ASSERT_NEAR(back[i][c], std::min(1.0f, img[i][c] * scale), 0.02f);
      }
  }
  // Without sRGB decoding the 8-bit codes come back as they are.
  Image raw = read_image(dir / "a.png", false);
  EXPECT_NEAR(raw[0].x, to_srgb8(img[0].x, 0.5f) / 255.0f, 1e-6f);
}

TEST(ImageFiles, WritesReplaceAtomicallyWithoutLeftovers) {
  TempDir dir;
  for (const char* name : {"a.exr", "a.png"}) {
    write_image(dir / name, test_image(8, 8, 1, 3));
    write_image(dir / name, test_image(8, 8, 1, 4));  // over an existing file
  }
  write_file_atomic(dir / "a.json", "{}\n");
  write_file_atomic(dir / "a.json", "{\"x\": 1}\n");
  EXPECT_EQ(read_bytes(dir / "a.json"), "{\"x\": 1}\n");
  EXPECT_EQ(folder_entries(dir.path()), (std::vector<std::string>{"a.exr", "a.json", "a.png"}));
  Image back = read_image(dir / "a.exr");
  EXPECT_EQ(back[5], test_image(8, 8, 1, 4)[5]);
}

TEST(ImageFiles, RejectedWritesLeaveTheOldFile) {
  TempDir dir;
  write_image(dir / "a.png", test_image(4, 4, 1, 5));
  const std::string before = read_bytes(dir / "a.png");
  EXPECT_THROW(write_image(dir / "a.tiff", test_image(4, 4, 1, 6)), Error);  // unknown extension
  EXPECT_THROW(write_image(dir / "missing" / "a.png", test_image(4, 4, 1, 6)), Error);
  EXPECT_THROW(write_image(dir / "a.png", Image()), Error);  // empty image
  EXPECT_THROW(write_file_atomic(dir / "missing" / "a.json", "{}"), Error);
  EXPECT_TRUE(read_bytes(dir / "a.png") == before) << "a.png changed";
  EXPECT_EQ(folder_entries(dir.path()), std::vector<std::string>{"a.png"});
}

// A file size limit makes the write itself fail half-way (EFBIG), as a full disk would.
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    m_old_handler = std::signal(SIGXFSZ, SIG_IGN);  // fail the write instead of killing us
    getrlimit(RLIMIT_FSIZE, &m_old);
    rlimit lim = m_old;
    lim.rlim_cur = bytes;
    setrlimit(RLIMIT_FSIZE, &lim);
  }
  ~FileSizeLimit() {
    setrlimit(RLIMIT_FSIZE, &m_old);
    std::signal(SIGXFSZ, m_old_handler);
  }

 private:
  rlimit m_old;
  void (*m_old_handler)(int);
};

TEST(ImageFiles, FailedWritesLeaveTheOldFileAndNoTemporary) {
  TempDir dir;
  const Image small = test_image(4, 4, 1, 7);
  const Image big = test_image(256, 256, 100, 8);  // noise: compresses to far over the limit
  write_image(dir / "a.exr", small);
  write_image(dir / "a.png", small);
  write_file_atomic(dir / "a.json", "{}\n");
  const std::string exr = read_bytes(dir / "a.exr"), png = read_bytes(dir / "a.png");
  ASSERT_LT(std::max(exr.size(), png.size()), 4000u);
  {
    FileSizeLimit limit(8000);
    EXPECT_THROW(write_image(dir / "a.exr", big), Error);
    EXPECT_THROW(write_image(dir / "a.png", big), Error);
    EXPECT_THROW(write_file_atomic(dir / "a.json", std::string(100000, 'x')), Error);
  }
  EXPECT_TRUE(read_bytes(dir / "a.exr") == exr) << "a.exr changed";
  EXPECT_TRUE(read_bytes(dir / "a.png") == png) << "a.png changed";
  EXPECT_EQ(read_bytes(dir / "a.json"), "{}\n");
  EXPECT_EQ(folder_entries(dir.path()), (std::vector<std::string>{"a.exr", "a.json", "a.png"}));
}

// An EXR whose header claims w x h pixels and which holds none of them: a few kilobytes (the
// header and a table of chunk offsets, all zero).
void write_exr_claim(const fs::path& path, int w, int h, Imf::Compression compression) {
  Imf::Header header(w, h);
  header.compression() = compression;
  for (const char* c : {"R", "G", "B"}) header.channels().insert(c, Imf::Channel(Imf::HALF));
  Imf::OutputFile file(path.c_str(), header);
}

// A Radiance .hdr whose header claims w x h pixels, followed by `rows` run-length coded
// scanlines of one grey.
std::string hdr_claim(int w, int h, int rows = 1) {
  std::string s = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n" + fmt::format("-Y {} +X {}\n", h, w);
  for (int r = 0; r < rows; ++r) {
    s += std::string{2, 2, char((w >> 8) & 0xff), char(w & 0xff)};
    for (int c = 0; c < 4; ++c)
      for (int left = w; left > 0; left -= 127)
        s += std::string{char(128 + std::min(left, 127)), char(c == 3 ? 128 : 100)};
  }
  return s;
}

// Runs `read` with the address space allowed to grow by 1.5 GiB at most, then exits: 0 when it
// threw an rll::Error (whose message goes to stderr) that is not a failed allocation, else
// non-zero. Run
// in a death test's child: a false size claim must be refused without the memory it claims
// (and without a std::bad_alloc).
[[noreturn]] void read_in_bounded_memory(const std::function<void()>& read) {
  long pages = 0;
  std::ifstream("/proc/self/statm") >> pages;
  const rlim_t cap = rlim_t(pages) * rlim_t(sysconf(_SC_PAGESIZE)) + (rlim_t(3) << 29);
  const rlimit limit{cap, cap};
  setrlimit(RLIMIT_AS, &limit);
  try {
    read();
  } catch (const Error& e) {
    std::fprintf(stderr, "%s\n", e.what());
    // An allocation that failed under the cap, passed on as an rll::Error, is no refusal.
    std::_Exit(std::string(e.what()).find("bad_alloc") == std::string::npos ? 0 : 3);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "not an rll::Error: %s\n", e.what());
    std::_Exit(1);
  }
  std::_Exit(2);
}

#define EXPECT_REFUSED_IN_BOUNDED_MEMORY(read, pattern) \
  EXPECT_EXIT(read_in_bounded_memory([&] { read; }), ::testing::ExitedWithCode(0), pattern)

TEST(ImageFiles, ExrClaimingPixelsItDoesNotHoldIsRefusedWithoutTakingTheirMemory) {
  ::testing::FLAGS_gtest_death_test_style = "threadsafe";
  TempDir dir;
  // 16000 x 16000 is within the size rll reads: 3 GiB as floats, which the file cannot back.
  for (auto compression : {Imf::ZIP_COMPRESSION, Imf::PIZ_COMPRESSION, Imf::RLE_COMPRESSION}) {
    write_exr_claim(dir / "claim.exr", 16000, 16000, compression);
    ASSERT_LT(fs::file_size(dir / "claim.exr"), 200000u);
    const auto start = std::chrono::steady_clock::now();
    EXPECT_REFUSED_IN_BOUNDED_MEMORY(read_image(dir / "claim.exr"), "claim.exr");
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 10);
  }
  // Uncompressed, the claim is checked against the file's size before anything is read.
  write_exr_claim(dir / "raw.exr", 16000, 16000, Imf::NO_COMPRESSION);
  expect_mentions(error_of([&] { read_image(dir / "raw.exr"); }),
                  {"raw.exr", "16000x16000", "uncompressed", "1536000000 bytes", "only"});
}

// Files of more rows than one band of the reader, with a data window that does not start at the
// origin, scanline and tiled: every pixel lands where it belongs.
TEST(ImageFiles, ExrReadsInBandsKeepEveryPixel) {
  TempDir dir;
  const int w = 53, h = 700;  // three bands of 256 rows, the last partial
  const Image img = test_image(w, h, 10.0f, 9);
  std::vector<float> rgb(size_t(w) * h * 3);
  for (size_t i = 0; i < img.pixel_count(); ++i)
    for (int c = 0; c < 3; ++c) rgb[3 * i + c] = img[i][c];
  const Imath::Box2i window({-7, -300}, {w - 8, h - 301});
  auto header = [&](Imf::Compression compression) {
    Imf::Header hd(window, window);
    hd.compression() = compression;
    for (const char* c : {"R", "G", "B"}) hd.channels().insert(c, Imf::Channel(Imf::FLOAT));
    return hd;
  };
  auto frame = [&] {
    Imf::FrameBuffer fb;
    char* base = reinterpret_cast<char*>(rgb.data()) -
                 (ptrdiff_t(window.min.y) * w + window.min.x) * ptrdiff_t(3 * sizeof(float));
    for (int c = 0; c < 3; ++c)
      fb.insert(c == 0 ? "R" : c == 1 ? "G" : "B",
                Imf::Slice(Imf::FLOAT, base + c * sizeof(float), 3 * sizeof(float),
                           3 * sizeof(float) * w));
    return fb;
  };
  for (auto compression : {Imf::ZIP_COMPRESSION, Imf::PIZ_COMPRESSION}) {
    {
      Imf::OutputFile out((dir / "lines.exr").c_str(), header(compression));
      out.setFrameBuffer(frame());
      out.writePixels(h);
    }
    {
      Imf::Header hd = header(compression);
      hd.setTileDescription(Imf::TileDescription(32, 48));
      Imf::TiledOutputFile out((dir / "tiles.exr").c_str(), hd);
      out.setFrameBuffer(frame());
      out.writeTiles(0, out.numXTiles() - 1, 0, out.numYTiles() - 1);
    }
    for (const char* name : {"lines.exr", "tiles.exr"}) {
      const Image back = read_image(dir / name);
      ASSERT_EQ(back.width(), w) << name;
      ASSERT_EQ(back.height(), h) << name;
      for (size_t i = 0; i < img.pixel_count(); ++i) ASSERT_EQ(back[i], img[i]) << name << " " << i;
    }
  }
}

TEST(ImageFiles, ImageHeadersClaimingMoreThanTheLimitAreRefused) {
  ::testing::FLAGS_gtest_death_test_style = "threadsafe";
  TempDir dir;
  write_exr_claim(dir / "huge.exr", 100000, 100000, Imf::ZIP_COMPRESSION);
  EXPECT_REFUSED_IN_BOUNDED_MEMORY(read_image(dir / "huge.exr"),
                                   "huge.exr.*100000x100000 pixels.*at most");
  write_exr_claim(dir / "wide.exr", 1 << 20, 1, Imf::ZIP_COMPRESSION);
  expect_mentions(error_of([&] { read_image(dir / "wide.exr"); }), {"1048576x1", "at most"});
  dir.write("huge.hdr", hdr_claim(30000, 30000));
  EXPECT_REFUSED_IN_BOUNDED_MEMORY(read_image(dir / "huge.hdr"), "huge.hdr.*30000x30000 pixels");
}

TEST(ImageFiles, HdrClaimingMoreRowsThanItHoldsIsRefused) {
  TempDir dir;
  // stb_image reads the rows missing from a truncated .hdr as black; the claim is checked
  // against the bytes instead. One whole scanline of 100 is there.
  const std::string bytes = hdr_claim(200, 100);
  dir.write("short.hdr", bytes);
  expect_mentions(error_of([&] { read_image(dir / "short.hdr"); }),
                  {"short.hdr", "200x100", "at least", "only"});
  expect_mentions(error_of([&] {
                    decode_image(reinterpret_cast<const unsigned char*>(bytes.data()),
                                 bytes.size(), true, "mem.hdr");
                  }),
                  {"mem.hdr", "200x100"});
  // A complete file of the same kind reads.
  dir.write("whole.hdr", hdr_claim(200, 100, 100));
  const Image whole = read_image(dir / "whole.hdr");
  EXPECT_EQ(whole.width(), 200);
  EXPECT_EQ(whole.height(), 100);
  EXPECT_NEAR(whole.at(199, 99).y, 100.0f / 256.0f, 1e-6f);  // RGBE: 100 * 2^(128 - 136)
}

TEST(ImageFiles, AFolderIsNotAnImage) {
  TempDir dir;
  fs::create_directory(dir / "tex.png");
  expect_mentions(error_of([&] { read_image(dir / "tex.png"); }), {"tex.png", "is a folder"});
  expect_mentions(error_of([&] { read_image(dir / "missing.png"); }), {"missing.png", "not found"});
}

}  // namespace
