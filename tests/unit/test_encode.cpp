// core/encode.h: the one base64 and the one PNG-in-memory encoder that the reports, glTF's
// embedded buffer and write_image's .png all use.
#include <gtest/gtest.h>
#include <stb/stb_image.h>

#include <filesystem>
#include <fstream>
#include <iterator>

#include "rll/core/encode.h"
#include "rll/core/error.h"
#include "rll/core/image.h"
#include "support/test_support.h"

using namespace rll;

TEST(Encode, Base64TestVectors) {  // RFC 4648, section 10: every length mod 3, padding of 0-2
  EXPECT_EQ(base64(""), "");
  EXPECT_EQ(base64("f"), "Zg==");
  EXPECT_EQ(base64("fo"), "Zm8=");
  EXPECT_EQ(base64("foo"), "Zm9v");
  EXPECT_EQ(base64("foob"), "Zm9vYg==");
  EXPECT_EQ(base64("fooba"), "Zm9vYmE=");
  EXPECT_EQ(base64("foobar"), "Zm9vYmFy");
  // High bytes, a zero byte, and the last two digits ('+' is 62, '/' is 63).
  EXPECT_EQ(base64(std::string("\xff\x00\xfe", 3)), "/wD+");
  EXPECT_EQ(base64(std::string("\xfb\xff", 2)), "+/8=");
  EXPECT_EQ(base64(std::string(1, '\0')), "AA==");
}

TEST(Encode, MarkupEscaping) {
  EXPECT_EQ(escape_markup("a<b>&\"c'"), "a&lt;b&gt;&amp;&quot;c&#39;");
}

namespace {
// The pixels stb_image decodes from PNG bytes, with their size and channels.
std::vector<uint8_t> decode_png(const std::string& png, int& w, int& h, int& channels) {
  unsigned char* px = stbi_load_from_memory(reinterpret_cast<const unsigned char*>(png.data()),
                                            int(png.size()), &w, &h, &channels, 0);
  if (!px) return {};
  std::vector<uint8_t> out(px, px + size_t(w) * h * channels);
  stbi_image_free(px);
  return out;
}
}  // namespace

TEST(Encode, PngBytesDecodeToThePixels) {
  for (int channels : {1, 3}) {
    const int w = 5, h = 3;
    std::vector<uint8_t> px(size_t(w) * h * channels);
    for (size_t i = 0; i < px.size(); ++i) px[i] = uint8_t(i * 37 + 11);
    const std::string png = png_bytes(px, w, h, channels);
    ASSERT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
    int dw = 0, dh = 0, dc = 0;
    EXPECT_EQ(decode_png(png, dw, dh, dc), px) << channels << " channels";
    EXPECT_EQ(dw, w);
    EXPECT_EQ(dh, h);
    EXPECT_EQ(dc, channels);
  }
  EXPECT_THROW(png_bytes(std::vector<uint8_t>(5), 2, 2, 1), Error);  // 5 bytes for 4 pixels
  EXPECT_THROW(png_bytes(std::vector<uint8_t>(8), 2, 2, 2), Error);  // 2 channels
}

// write_image's .png is png_bytes of the tone-mapped pixels, byte for byte.
TEST(Encode, WriteImagePngIsPngBytes) {
  Image image(4, 2);
  for (size_t i = 0; i < image.pixel_count(); ++i)
    image[i] = Rgb(float(i) / 8, 0.25f, i % 2 ? 2.0f : 0.0f);
  const test::TempDir dir;
  const std::filesystem::path path = dir / "a.png";
  write_image(path, image);
  std::ifstream f(path, std::ios::binary);
  const std::string file{std::istreambuf_iterator<char>(f), {}};
  std::vector<uint8_t> px(image.pixel_count() * 3);
  for (size_t i = 0; i < image.pixel_count(); ++i)
    for (int c = 0; c < 3; ++c) px[3 * i + c] = to_srgb8(image[i][c]);
  EXPECT_EQ(file, png_bytes(px, 4, 2, 3));
}
