// Image files: EXR keeps floats exactly, PNG keeps its 8-bit sRGB quantisation, and writes are
// atomic: no temporary file is left behind and a failed write leaves the old file as it was.
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <csignal>
#include <fstream>
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

}  // namespace
