#include "rll/core/image.h"

#include <ImfArray.h>
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <stb/stb_image.h>
#include <stb/stb_image_write.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <fstream>

#include "rll/core/error.h"

namespace rll {
namespace fs = std::filesystem;

namespace {

std::string lower_ext(const fs::path& p) {
  std::string e = p.extension().string();
  for (auto& c : e) c = char(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

fs::path temp_sibling(const fs::path& path) {
  static std::atomic<unsigned> counter{0};
  fs::path tmp = path;
  tmp += fmt::format(".tmp-{}-{}", ::getpid(), counter++);
  return tmp;
}

void commit(const fs::path& tmp, const fs::path& path) {
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) {
    fs::remove(tmp, ec);
    fail("cannot write '{}': {}", path.string(), ec.message());
  }
}

float srgb_to_linear(float c) {
  return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

// An 8-bit RGB image from stb_image (which it frees), decoded from sRGB when `srgb`.
Image from_8bit(unsigned char* data, int w, int h, bool srgb, const std::string& name) {
  if (!data) fail("cannot read '{}': {}", name, stbi_failure_reason());
  Image img(w, h);
  for (size_t i = 0; i < img.pixel_count(); ++i)
    for (int c = 0; c < 3; ++c) {
      float v = data[3 * i + c] / 255.0f;
      img[i][c] = srgb ? srgb_to_linear(v) : v;
    }
  stbi_image_free(data);
  return img;
}

}  // namespace

uint8_t to_srgb8(float v, float scale) {
  v *= scale;
  if (!(v > 0)) return 0;  // also maps NaN to black
  if (v >= 1) return 255;
  float s = v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1 / 2.4f) - 0.055f;
  return uint8_t(clamp(int(s * 255.0f + 0.5f), 0, 255));
}

void write_file_atomic(const fs::path& path, const std::string& bytes) {
  if (path.has_parent_path() && !fs::exists(path.parent_path()))
    fail("cannot write '{}': folder '{}' does not exist", path.string(), path.parent_path().string());
  fs::path tmp = temp_sibling(path);
  std::ofstream f(tmp, std::ios::binary);
  if (!f) fail("cannot write '{}': cannot create a file there", path.string());
  f.write(bytes.data(), std::streamsize(bytes.size()));
  f.close();  // buffered bytes reach the disk here: the write can still fail
  if (!f) {
    std::error_code ec;
    fs::remove(tmp, ec);
    fail("cannot write '{}': write failed", path.string());
  }
  commit(tmp, path);
}

void write_image(const fs::path& path, const Image& image, float exposure_stops) {
  if (image.width() <= 0 || image.height() <= 0) fail("cannot write '{}': empty image", path.string());
  if (path.has_parent_path() && !fs::exists(path.parent_path()))
    fail("cannot write '{}': folder '{}' does not exist", path.string(), path.parent_path().string());
  std::string ext = lower_ext(path);
  fs::path tmp = temp_sibling(path);
  if (ext == ".exr") {
    try {
      Imf::Header header(image.width(), image.height());
      header.compression() = Imf::ZIP_COMPRESSION;
      for (const char* c : {"R", "G", "B"}) header.channels().insert(c, Imf::Channel(Imf::FLOAT));
      Imf::OutputFile file(tmp.c_str(), header);
      Imf::FrameBuffer fb;
      char* base = (char*)image.pixels().data();
      size_t xs = sizeof(Rgb), ys = sizeof(Rgb) * image.width();
      fb.insert("R", Imf::Slice(Imf::FLOAT, base, xs, ys));
      fb.insert("G", Imf::Slice(Imf::FLOAT, base + sizeof(float), xs, ys));
      fb.insert("B", Imf::Slice(Imf::FLOAT, base + 2 * sizeof(float), xs, ys));
      file.setFrameBuffer(fb);
      file.writePixels(image.height());
    } catch (const std::exception& e) {
      std::error_code ec;
      fs::remove(tmp, ec);
      fail("cannot write '{}': {}", path.string(), e.what());
    }
  } else if (ext == ".png") {
    float scale = std::exp2(exposure_stops);
    std::vector<uint8_t> px(image.pixel_count() * 3);
    for (size_t i = 0; i < image.pixel_count(); ++i)
      for (int c = 0; c < 3; ++c) px[3 * i + c] = to_srgb8(image[i][c], scale);
    // Encoded in memory: stbi_write_png ignores errors of its own file writes.
    std::string png;
    auto append = [](void* context, void* data, int size) {
      static_cast<std::string*>(context)->append(static_cast<const char*>(data), size_t(size));
    };
    if (!stbi_write_png_to_func(append, &png, image.width(), image.height(), 3, px.data(),
                                image.width() * 3))
      fail("cannot write '{}': PNG encoding failed", path.string());
    write_file_atomic(path, png);
    return;
  } else {
    fail("cannot write '{}': unknown image extension '{}' (use .exr or .png)", path.string(), ext);
  }
  commit(tmp, path);
}

Image read_image(const fs::path& path, bool srgb) {
  if (!fs::exists(path)) fail("image '{}' not found", path.string());
  std::string ext = lower_ext(path);
  if (ext == ".exr") {
    try {
      Imf::InputFile file(path.c_str());
      Imath::Box2i dw = file.header().dataWindow();
      int w = dw.max.x - dw.min.x + 1, h = dw.max.y - dw.min.y + 1;
      Image img(w, h);
      Imf::FrameBuffer fb;
      char* base = (char*)img.pixels().data() - (size_t(dw.min.x) + size_t(dw.min.y) * w) * sizeof(Rgb);
      size_t xs = sizeof(Rgb), ys = sizeof(Rgb) * w;
      fb.insert("R", Imf::Slice(Imf::FLOAT, base, xs, ys, 1, 1, 0.0));
      fb.insert("G", Imf::Slice(Imf::FLOAT, base + sizeof(float), xs, ys, 1, 1, 0.0));
      fb.insert("B", Imf::Slice(Imf::FLOAT, base + 2 * sizeof(float), xs, ys, 1, 1, 0.0));
      file.setFrameBuffer(fb);
      file.readPixels(dw.min.y, dw.max.y);
      return img;
    } catch (const std::exception& e) {
      fail("cannot read '{}': {}", path.string(), e.what());
    }
  }
  int w = 0, h = 0, n = 0;
  if (ext == ".hdr") {
    float* data = stbi_loadf(path.c_str(), &w, &h, &n, 3);
    if (!data) fail("cannot read '{}': {}", path.string(), stbi_failure_reason());
    Image img(w, h);
    for (size_t i = 0; i < img.pixel_count(); ++i) img[i] = Rgb(data[3 * i], data[3 * i + 1], data[3 * i + 2]);
    stbi_image_free(data);
    return img;
  }
  unsigned char* data = stbi_load(path.c_str(), &w, &h, &n, 3);
  return from_8bit(data, w, h, srgb, path.string());
}

Image decode_image(const unsigned char* bytes, size_t size, bool srgb, const std::string& name) {
  if (size > size_t(INT32_MAX)) fail("cannot read '{}': the image is too large", name);
  int w = 0, h = 0, n = 0;
  if (stbi_is_hdr_from_memory(bytes, int(size))) {
    float* data = stbi_loadf_from_memory(bytes, int(size), &w, &h, &n, 3);
    if (!data) fail("cannot read '{}': {}", name, stbi_failure_reason());
    Image img(w, h);
    for (size_t i = 0; i < img.pixel_count(); ++i) img[i] = Rgb(data[3 * i], data[3 * i + 1], data[3 * i + 2]);
    stbi_image_free(data);
    return img;
  }
  unsigned char* data = stbi_load_from_memory(bytes, int(size), &w, &h, &n, 3);
  return from_8bit(data, w, h, srgb, name);
}

}  // namespace rll
