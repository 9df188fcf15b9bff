// HDR RGB images and their files: OpenEXR (linear) and PNG (tone-mapped sRGB), written atomically.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "rll/core/device.h"
#include "rll/core/math.h"

namespace rll {

// An image's texels as kernels read them: row by row from the top, owning nothing.
struct TexelView {
  View<const Rgb> texels;
  int width = 0, height = 0;
  RLL_HD const Rgb& at(int x, int y) const { return texels[size_t(y) * width + x]; }
};

// The largest image rll reads: a header claiming more is refused before anything is allocated.
// 2^28 pixels (16384 x 16384, 3 GiB as floats), at most 65536 a side.
constexpr int64_t kMaxImageSide = int64_t(1) << 16;
constexpr size_t kMaxImagePixels = size_t(1) << 28;

// The most bytes deflate data (a PNG's IDAT chunks, a gzip member) inflates to per byte: zlib's
// documented limit, 1032:1. Readers check what a header claims against it before inflating.
constexpr double kDeflateMaxRatio = 1032;

class Image {
 public:
  Image() = default;
  Image(int width, int height, Rgb fill = Rgb(0))
      : m_w(width), m_h(height), m_px(size_t(width) * height, fill) {}
  // Takes `pixels` (width * height of them, row by row).
  Image(int width, int height, std::vector<Rgb> pixels)
      : m_w(width), m_h(height), m_px(std::move(pixels)) {}
  int width() const { return m_w; }
  int height() const { return m_h; }
  size_t pixel_count() const { return m_px.size(); }
  Rgb& at(int x, int y) { return m_px[size_t(y) * m_w + x]; }
  const Rgb& at(int x, int y) const { return m_px[size_t(y) * m_w + x]; }
  Rgb& operator[](size_t i) { return m_px[i]; }
  const Rgb& operator[](size_t i) const { return m_px[i]; }
  const std::vector<Rgb>& pixels() const { return m_px; }
  std::vector<Rgb>& pixels() { return m_px; }
  TexelView texel_view() const { return {view_of(m_px), m_w, m_h}; }

 private:
  int m_w = 0, m_h = 0;
  std::vector<Rgb> m_px;
};

// Linear value to 8-bit sRGB after exposure (stops) and clamping.
uint8_t to_srgb8(float linear, float exposure_scale = 1.0f);

// Writes by extension: .exr (32-bit float, ZIP), .png (sRGB 8-bit, clamped after exposure).
// The file is written to a temporary name beside the target, then renamed over it.
void write_image(const std::filesystem::path& path, const Image& image, float exposure_stops = 0);
// What a reader makes of an EXR with a luminance channel Y and no R, G, B (OpenEXR's grey
// image): grey pixels (a texture or an environment map, where grey is what the file means, as
// for a grey PNG; a note on stderr says so), or an error (a reference: an RGB render measured
// against a grey image gives a number that looks right and is not). An EXR missing one of R,
// G, B in any other way is always refused, naming the channel: it is never read as black.
enum class LuminanceOnly { read_as_grey, refuse };

// Reads .exr, or any format stb_image reads (.png, .jpg, .hdr, ...); 8-bit files are decoded
// from sRGB to linear when `srgb` is true.
Image read_image(const std::filesystem::path& path, bool srgb = true,
                 LuminanceOnly luminance = LuminanceOnly::read_as_grey);

// An OpenEXR file with what rll keeps beside the pixels: string attributes of the header (a
// render share's metadata) and, optionally, the number of samples behind each pixel (channel
// "count", 32-bit unsigned).
struct ExrFile {
  Image image;
  std::vector<std::pair<std::string, std::string>> attributes;
  std::vector<uint32_t> counts;  // empty, or one per pixel
  // Further 32-bit float channels, one value per pixel each (`rll render --aov` diagnostics).
  std::vector<std::pair<std::string, std::vector<float>>> channels;

  // The value of attribute `name`, or nullptr.
  const std::string* attribute(const std::string& name) const;
};
// Writes atomically, as write_image does for .exr (32-bit float RGB, ZIP).
void write_exr(const std::filesystem::path& path, const ExrFile& file);
// Reads an .exr with its string attributes, its "count" channel (empty if it has none) and its
// other 32-bit float channels.
// It must have R, G and B (a share or a cache entry: LuminanceOnly::refuse).
ExrFile read_exr_file(const std::filesystem::path& path);

// Decodes an image file held in memory (PNG, JPEG and the other formats stb_image reads);
// `name` is for messages.
Image decode_image(const unsigned char* bytes, size_t size, bool srgb, const std::string& name);

// The first texel of `image` that no light can emit, a negative or non-finite one, as "texel
// (X, Y) is (R, G, B)" (x from the left, y from the top), or "" when there is none. Every
// reader of a light's image (an area light's, an image light's, an environment map) refuses
// such an image with it: a negative texel would subtract light, a NaN or infinite one would
// poison every sample that sees it.
std::string bad_emission_texel(const Image& image);

// Writes bytes to `path` atomically (temporary file in the same folder, then rename).
void write_file_atomic(const std::filesystem::path& path, const std::string& bytes);

}  // namespace rll
