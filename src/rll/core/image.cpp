#include "rll/core/image.h"

#include <Iex.h>
#include <ImfArray.h>
#include <ImfAttribute.h>
#include <ImfBoxAttribute.h>
#include <ImfChannelList.h>
#include <ImfChannelListAttribute.h>
#include <ImfCompressionAttribute.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfStringAttribute.h>
#include <ImfTileDescriptionAttribute.h>
#include <fmt/ranges.h>
#include <stb/stb_image.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <optional>

#include "rll/core/encode.h"
#include "rll/core/error.h"
#include "rll/core/file_checks.h"
#include "rll/core/memory_budget.h"
#include "rll/core/params.h"
#include "rll/core/paths.h"

namespace rll {
namespace fs = std::filesystem;

namespace {

// The file that writing `path` replaces (its link's target, if it is a link), after the checks
// every output gets; the temporaries that killed writes of it left behind are deleted.
fs::path prepare_write(const fs::path& path) {
  check_output_file(path, "output");
  const fs::path target = write_target(path);
  if (target.has_parent_path() && !fs::is_directory(target.parent_path()))
    fail("cannot write '{}': folder '{}' does not exist", path.string(),
         target.parent_path().string());
  remove_stale_temporaries(target);
  return target;
}

void commit(const fs::path& tmp, const fs::path& path) {
  std::error_code ec;
  // `tmp` lies beside the target: the name to replace is the target's, not a link's.
  const fs::path target = write_target(path);
  if (WriteBatch::defer(tmp, target, path)) return;  // renamed in with the batch's other files
  fs::rename(tmp, target, ec);
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

// A claim of an image's size, checked before anything is allocated for it.
void check_claimed_size(int64_t w, int64_t h, const std::string& name) {
  if (w <= 0 || h <= 0) fail("cannot read '{}': its header claims a size of {}x{}", name, w, h);
  if (w > kMaxImageSide || h > kMaxImageSide || w * h > int64_t(kMaxImagePixels))
    fail(
        "cannot read '{}': its header claims {}x{} pixels; rll reads images of at most {} "
        "pixels a side and {} in all",
        name, w, h, kMaxImageSide, kMaxImagePixels);
}

// The fewest bytes a Radiance .hdr file of w x h pixels can take as stb_image reads it: each
// scanline flat (4 bytes a pixel) or, for widths in [8, 32768), run-length coded (a 4-byte
// header, then per channel at most 127 pixels per 2 bytes). stb_image reads a truncated file as
// black rows rather than failing, so the claim is checked against the file instead.
uint64_t min_hdr_bytes(int64_t w, int64_t h) {
  uint64_t line = 4 * uint64_t(w);
  if (w >= 8 && w < 32768) line = std::min(line, 4 + 4 * 2 * uint64_t((w + 126) / 127));
  return line * uint64_t(h);
}

// A file's bytes, for stb_image to decode from memory (the checks below read its headers).
std::string read_file_bytes(const fs::path& path) {
  std::error_code ec;
  const uintmax_t size = fs::file_size(path, ec);
  if (ec) fail("cannot read '{}': {}", path.string(), ec.message());
  // stb_image takes an int length; no image rll reads (2^28 pixels) needs a larger file.
  if (size > uintmax_t(INT32_MAX))
    fail("cannot read '{}': the file has {} bytes, more than the {} an image may have",
         path.string(), size, INT32_MAX);
  std::ifstream f(path, std::ios::binary);
  std::string bytes(size_t(size), '\0');
  if (!f || !f.read(bytes.data(), std::streamsize(size)))
    fail("cannot read '{}': read error", path.string());
  return bytes;
}

uint32_t big_endian32(const unsigned char* p) {
  return uint32_t(p[0]) << 24 | uint32_t(p[1]) << 16 | uint32_t(p[2]) << 8 | uint32_t(p[3]);
}

// A PNG's claim checked against its compressed data: stb_image allocates the whole inflated
// size its header claims before inflating (a 300-byte file claiming 16384x16384 pixels would
// take 805 MB before failing), while all its IDAT chunks together inflate to at most
// kDeflateMaxRatio times their size. Anything this walk cannot read is left to stb_image.
void check_png_data(const unsigned char* bytes, size_t size, int64_t w, int64_t h,
                    const std::string& name) {
  static const unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (size < 33 || std::memcmp(bytes, kSignature, 8) != 0 || std::memcmp(bytes + 12, "IHDR", 4))
    return;
  const int depth = bytes[24], colour = bytes[25];
  int channels = 0;
  switch (colour) {
    case 0:  // grey
    case 3:  // palette indices
      channels = 1;
      break;
    case 2:
      channels = 3;
      break;
    case 4:
      channels = 2;
      break;
    case 6:
      channels = 4;
      break;
    default:
      return;
  }
  uint64_t idat = 0;
  for (uint64_t at = 8; at + 8 <= size;) {
    const uint64_t length = big_endian32(bytes + at);
    const bool is_idat = std::memcmp(bytes + at + 4, "IDAT", 4) == 0;
    // stb_image allocates an IDAT chunk's length before it reads the chunk (the fuzzer's case: a
    // 110-byte file whose chunk claims 1.9 GB).
    if (is_idat && length > size - at - 8)
      fail(
          "cannot read '{}': its IDAT chunk at byte {} claims {} bytes, but the file has only {} "
          "left: a truncated or hostile PNG",
          name, at, length, size - at - 8);
    if (is_idat) idat += length;
    if (std::memcmp(bytes + at + 4, "IEND", 4) == 0) break;
    at += 12 + length;  // length, type, data, CRC
  }
  // The pixels' bits alone (without the rows' filter bytes): a lower bound, interlaced or not.
  const double pixel_bytes = double(w) * double(h) * channels * depth / 8;
  const double most = double(idat) * kDeflateMaxRatio + 1024;
  if (pixel_bytes > most)
    fail(
        "cannot read '{}': its header claims {}x{} pixels ({} channel{} of {} bits: {:.0f} "
        "bytes once inflated), but its {} bytes of compressed data (IDAT) inflate to at most "
        "{:.0f}: a damaged or hostile PNG",
        name, w, h, channels, channels == 1 ? "" : "s", depth, pixel_bytes, idat, most);
}

// A JPEG's claim checked against its size: stb_image allocates a plane per component at the
// frame header, before the data, and decodes data that ends early as grey rather than failing.
// Every 8x8 block of the component at full resolution takes at least one bit (its DC code),
// in baseline and progressive files alike.
void check_jpeg_data(size_t size, int64_t w, int64_t h, const std::string& name) {
  const double blocks = double((w + 7) / 8) * double((h + 7) / 8);
  if (blocks > 8 * double(size))
    fail(
        "cannot read '{}': its header claims {}x{} pixels ({:.0f} blocks of 8x8, each at least "
        "a bit of data), but the file has only {} bytes: a damaged or hostile JPEG",
        name, w, h, blocks, size);
}

// Uncompressed formats checked against their size: stb_image allocates the image a binary
// PNM (P5, P6) or an uncompressed BMP claims, then reads it, and a BMP that ends early comes
// out black rather than failing. (stb_image reads no compressed BMP.)
void check_raw_data(const unsigned char* bytes, size_t size, int64_t w, int64_t h, bool wide,
                    const std::string& name) {
  double need = 0;
  const char* format = "";
  if (size >= 2 && bytes[0] == 'P' && (bytes[1] == '5' || bytes[1] == '6')) {
    need = double(w) * double(h) * (bytes[1] == '5' ? 1 : 3) * (wide ? 2 : 1);
    format = "binary PNM";
  } else if (size >= 30 && bytes[0] == 'B' && bytes[1] == 'M') {
    const uint32_t header = uint32_t(bytes[14]) | uint32_t(bytes[15]) << 8 |
                            uint32_t(bytes[16]) << 16 | uint32_t(bytes[17]) << 24;
    const size_t at = header == 12 ? 24 : 28;  // bits per pixel (OS/2 or Windows header)
    const int bpp = int(bytes[at]) | int(bytes[at + 1]) << 8;
    const double row = std::floor((double(w) * bpp + 31) / 32) * 4;  // rows pad to 4 bytes
    need = row * double(h);
    format = "BMP";
  }
  if (need > double(size))
    fail(
        "cannot read '{}': its header claims {}x{} pixels, {:.0f} bytes of uncompressed {} data, "
        "but the file has only {} bytes: a truncated or hostile image",
        name, w, h, need, format, size);
}

// The most memory decoding a w x h image holds at once, checked against the memory budget
// before stb_image allocates any of it: first stb_image's own buffers (a PNG's inflated rows
// and its output in the file's `channels` of `bits` each, a JPEG's planes and its output), its
// conversion to RGB, then that RGB (8-bit, or float for `as_float`) beside rll's Image.
void check_decoding_memory(int64_t w, int64_t h, int channels, int bits, bool as_float,
                           const std::string& name) {
  const double out = as_float ? 3 * sizeof(float) : 3;
  const double per_pixel = std::max(2.0 * channels * (bits / 8.0) + out, out + double(sizeof(Rgb)));
  const double bytes = double(w) * double(h) * per_pixel;
  if (!(bytes <= double(memory_budget_bytes())))
    fail(
        "cannot read '{}': its {}x{} pixels take {} to decode, more than {}; use a smaller "
        "image",
        name, w, h, format_bytes(bytes), memory_budget_phrase());
}

// An image stb_image reads (PNG, JPEG, Radiance HDR, ...) from its bytes, its size claims
// checked first; `as_float` decodes through stb_image's float path (a Radiance file, or any
// file named .hdr, as read_image always has), otherwise through its 8-bit one.
Image decode_stb(const unsigned char* bytes, size_t size, bool srgb, bool as_float,
                 const std::string& name) {
  if (size > size_t(INT32_MAX)) fail("cannot read '{}': the image is too large", name);
  const int len = int(size);
  int w = 0, h = 0, n = 0;
  if (!stbi_info_from_memory(bytes, len, &w, &h, &n))
    fail("cannot read '{}': {}", name, stbi_failure_reason());
  check_claimed_size(w, h, name);
  const bool hdr = stbi_is_hdr_from_memory(bytes, len);
  if (hdr && min_hdr_bytes(w, h) > size)
    fail(
        "cannot read '{}': its header claims {}x{} pixels, which take at least {} bytes, but "
        "it has only {}",
        name, w, h, min_hdr_bytes(w, h), size);
  check_png_data(bytes, size, w, h, name);
  if (size >= 2 && bytes[0] == 0xff && bytes[1] == 0xd8) check_jpeg_data(size, w, h, name);
  // A Radiance file's pixels are RGBE, a byte a channel as far as memory goes.
  const bool wide = !hdr && stbi_is_16_bit_from_memory(bytes, len);
  check_raw_data(bytes, size, w, h, wide, name);
  const int bits = wide ? 16 : 8;
  check_decoding_memory(w, h, std::max(n, 1), bits, as_float, name);
  if (as_float) {
    float* data = stbi_loadf_from_memory(bytes, len, &w, &h, &n, 3);
    if (!data) fail("cannot read '{}': {}", name, stbi_failure_reason());
    Image img(w, h);
    for (size_t i = 0; i < img.pixel_count(); ++i)
      img[i] = Rgb(data[3 * i], data[3 * i + 1], data[3 * i + 2]);
    stbi_image_free(data);
    return img;
  }
  unsigned char* data = stbi_load_from_memory(bytes, len, &w, &h, &n, 3);
  return from_8bit(data, w, h, srgb, name);
}

// An attribute name or type as a message can show it: UTF-8 as it is (OpenEXR names are
// UTF-8), other bytes and control characters as \xNN, at most 64 bytes (shown_text).
std::string shown(const std::string& text) {
  return shown_text(text, 64, true);
}

// One attribute's value as OpenEXR's reader for its type sees it: exactly the `size` bytes the
// attribute's size field gives, read from the file; reading past them throws.
class AttributeValue : public Imf::IStream {
 public:
  AttributeValue(std::ifstream& in, uint64_t start, uint64_t size)
      : Imf::IStream("attribute value"), m_in(in), m_start(start), m_size(size) {}
  bool read(char c[], int n) override {
    if (n < 0 || m_pos + uint64_t(n) > m_size)
      throw Iex::InputExc("its value runs past those bytes");
    m_in.seekg(std::streamoff(m_start + m_pos));
    if (!m_in.read(c, n)) throw Iex::InputExc("the file ends inside it");
    m_pos += uint64_t(n);
    return m_pos < m_size;
  }
  uint64_t tellg() override { return m_pos; }
  void seekg(uint64_t pos) override { m_pos = pos; }
  void clear() override { m_in.clear(); }

 private:
  std::ifstream& m_in;
  uint64_t m_start, m_size, m_pos = 0;
};

// The rows OpenEXR compresses together, and so holds in its buffers at once (OpenEXR's
// "compression" document); the most of any where the method is unknown.
int64_t rows_per_chunk(Imf::Compression compression) {
  switch (compression) {
    case Imf::NO_COMPRESSION:
    case Imf::RLE_COMPRESSION:
    case Imf::ZIPS_COMPRESSION:
      return 1;
    case Imf::ZIP_COMPRESSION:
    case Imf::PXR24_COMPRESSION:
      return 16;
    case Imf::PIZ_COMPRESSION:
    case Imf::B44_COMPRESSION:
    case Imf::B44A_COMPRESSION:
    case Imf::DWAA_COMPRESSION:
      return 32;
    default:
      return 256;
  }
}

// What one part's header claims that OpenEXR allocates for when it opens the file, before rll
// reads a pixel: its data window (checked as every image size is), and a line buffer and the
// compressor's buffers for one chunk (rows, or a tile) of every channel, each about as large as
// the chunk (a fuzzed header of 6.3 M x 1 M pixels made OpenEXR take 1.2 GB for them).
struct PartClaims {
  std::optional<Imath::Box2i> window;
  Imf::ChannelList channels;
  Imf::Compression compression = Imf::ZIP_COMPRESSION;  // Imf::Header's default
  std::optional<Imf::TileDescription> tiles;

  void note(const std::string& attr, const Imf::Attribute& value) {
    if (const auto* a = dynamic_cast<const Imf::Box2iAttribute*>(&value); a && attr == "dataWindow")
      window = a->value();
    if (const auto* a = dynamic_cast<const Imf::ChannelListAttribute*>(&value);
        a && attr == "channels")
      channels = a->value();
    if (const auto* a = dynamic_cast<const Imf::CompressionAttribute*>(&value);
        a && attr == "compression")
      compression = a->value();
    if (const auto* a = dynamic_cast<const Imf::TileDescriptionAttribute*>(&value);
        a && attr == "tiles")
      tiles = a->value();
  }
  void check(const std::string& name) const {
    if (!window) return;
    const int64_t w = int64_t(window->max.x) - window->min.x + 1;
    const int64_t h = int64_t(window->max.y) - window->min.y + 1;
    check_claimed_size(w, h, name);
    double pixel_bytes = 0, channel_count = 0;
    for (auto c = channels.begin(); c != channels.end(); ++c, ++channel_count)
      pixel_bytes += c.channel().type == Imf::HALF ? 2 : 4;
    const double chunk = tiles ? double(tiles->xSize) * double(tiles->ySize)
                               : double(w) * double(rows_per_chunk(compression));
    check_memory_budget(3 * pixel_bytes * chunk,
                        fmt::format("opening '{}' (OpenEXR's buffers for chunks of {} pixels in "
                                    "{} channels)",
                                    name, chunk, channel_count));
  }
};

// OpenEXR takes the memory an attribute's size field claims before it reads the value (a
// string attribute claiming 2^31 - 1 bytes costs 2 GiB in a file of 300 bytes), and its reader
// has no bound to set. So the header is walked here first, reading only the header's bytes, and
// every attribute's size is checked against the bytes the file has left. (The counts inside
// values, a string vector's lengths, a preview's size, a tiled file's offset table, OpenEXR
// 3.1 checks itself: tests/unit/test_image.cpp keeps them in bounded memory.) The layout
// (OpenEXR's "file layout" document): magic number and version (8 bytes), then per part the
// attributes (name\0 type\0 int32 size, value), ended by an empty name; a multi-part file ends
// its list of headers with one more empty name.
//
// OpenEXR reads a value of a type it knows by the type (a float takes 4 bytes, a channel list
// runs to its empty name), not by the size field, and goes on from where that reading ends: a
// size that disagrees with its value would let OpenEXR's reading part from this walk and reach
// a size claim the walk never saw (the fuzzer's case: a channel list longer than its size, then
// an unknown attribute claiming 1.8 GB). So each such value is read here by OpenEXR's own
// reader, from exactly its bytes, and must fill them; a value of a type OpenEXR does not know it
// reads by the size, as this walk does.
void check_exr_header(const fs::path& path) {
  const std::string name = path.string();
  std::error_code ec;
  const uint64_t file_size = fs::file_size(path, ec);
  std::ifstream in(path, std::ios::binary);
  if (ec || !in) fail("cannot read '{}'", name);
  auto damaged = [&](const std::string& why) {
    fail("cannot read '{}': not an OpenEXR file, or a damaged one ({})", name, why);
  };
  unsigned char head[8];
  if (!in.read(reinterpret_cast<char*>(head), 8)) damaged("shorter than its 8-byte preamble");
  if (head[0] != 0x76 || head[1] != 0x2f || head[2] != 0x31 || head[3] != 0x01)
    damaged("no OpenEXR magic number");
  const bool multipart = head[5] & 0x10;  // bit 12 of the version field
  const int version = int(uint32_t(head[4]) | uint32_t(head[5]) << 8 | uint32_t(head[6]) << 16 |
                          uint32_t(head[7]) << 24);
  Imf::staticInitialize();  // registers the attribute types OpenEXR knows
  auto text = [&](const char* what) {
    std::string s;
    for (char c; in.get(c) && c != '\0';)
      if (s += c; s.size() > 255)
        damaged(fmt::format("an attribute {} longer than 255 bytes", what));
    if (!in) damaged("it ends inside its header");
    return s;
  };
  auto int32 = [&] {
    unsigned char b[4];
    if (!in.read(reinterpret_cast<char*>(b), 4)) damaged("it ends inside its header");
    return int32_t(uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 |
                   uint32_t(b[3]) << 24);
  };
  for (bool more = true; more;) {
    int attributes = 0;
    PartClaims claims;
    for (std::string attr = text("name"); !attr.empty(); attr = text("name"), ++attributes) {
      const std::string type = text("type");
      const int32_t size = int32();
      const uint64_t start = uint64_t(in.tellg()), left = file_size - start;
      if (size < 0) damaged(fmt::format("attribute '{}' claims {} bytes", shown(attr), size));
      if (uint64_t(size) > left)
        fail(
            "cannot read '{}': its header attribute '{}' claims a {} value of {} bytes, but the "
            "file has only {} bytes left",
            name, shown(attr), shown(type), size, left);
      if (Imf::Attribute::knownType(type.c_str())) {
        const std::unique_ptr<Imf::Attribute> value(Imf::Attribute::newAttribute(type.c_str()));
        AttributeValue bytes(in, start, uint64_t(size));
        try {
          value->readValueFrom(bytes, size, version);
        } catch (const std::exception& e) {
          damaged(fmt::format("attribute '{}' of type {} does not fit its {} bytes: {}",
                              shown(attr), shown(type), size, e.what()));
        }
        if (bytes.tellg() != uint64_t(size))
          damaged(
              fmt::format("attribute '{}' of type {} holds a value of {} bytes, but its size "
                          "field claims {}",
                          shown(attr), shown(type), bytes.tellg(), size));
        claims.note(attr, *value);
      }
      in.seekg(std::streamoff(start + uint64_t(size)));
    }
    if (attributes > 0) claims.check(name);
    more = multipart && attributes > 0;
  }
}

// The R, G and B channels an EXR is read from: the names to read into each (Y three times
// for a grey image), or an error naming the file and what is missing.
std::array<const char*, 3> rgb_channels(const Imf::ChannelList& channels, const std::string& name,
                                        LuminanceOnly luminance) {
  std::vector<std::string> missing, present;
  for (const char* c : {"R", "G", "B"})
    if (!channels.findChannel(c)) missing.push_back(c);
  if (missing.empty()) return {"R", "G", "B"};
  for (auto c = channels.begin(); c != channels.end(); ++c) present.push_back(shown(c.name()));
  if (present.size() > 8) present.resize(8), present.push_back("...");
  const bool grey = missing.size() == 3 && channels.findChannel("Y") &&
                    !channels.findChannel("RY") && !channels.findChannel("BY");
  if (grey && luminance == LuminanceOnly::read_as_grey) {
    fmt::print(stderr, "rll: note: '{}' has a luminance channel Y and no R, G, B: read as grey\n",
               name);
    return {"Y", "Y", "Y"};
  }
  if (grey)
    fail(
        "cannot read '{}': it has a luminance channel Y and no R, G, B; an RGB image measured "
        "against or merged with a grey one gives wrong numbers, so it must have R, G and B",
        name);
  fail(
      "cannot read '{}': it has no channel {} (its channels: {}); rll reads RGB images and "
      "never reads a missing channel as black",
      name, fmt::join(missing, ", "),
      present.empty() ? "none" : fmt::format("{}", fmt::join(present, ", ")));
}

// `extras`: also the string attributes, the "count" channel and further FLOAT channels.
ExrFile read_exr_unchecked(const fs::path& path, bool extras, LuminanceOnly luminance) {
  const std::string name = path.string();
  check_exr_header(path);
  Imf::InputFile file(path.c_str());
  const Imf::Header& header = file.header();
  const std::array<const char*, 3> rgb = rgb_channels(header.channels(), name, luminance);
  ExrFile out;
  const bool has_counts = extras && header.channels().findChannel("count") != nullptr;
  if (has_counts && header.channels().findChannel("count")->type != Imf::UINT)
    fail("cannot read '{}': its channel 'count' is not 32-bit unsigned", name);
  if (extras)
    for (auto c = header.channels().begin(); c != header.channels().end(); ++c) {
      const std::string_view n = c.name();
      if (n != "count" && n != rgb[0] && n != rgb[1] && n != rgb[2] &&
          c.channel().type == Imf::FLOAT)
        out.channels.emplace_back(c.name(), std::vector<float>());
    }
  if (extras)
    for (auto a = header.begin(); a != header.end(); ++a)
      if (const auto* v = dynamic_cast<const Imf::StringAttribute*>(&a.attribute()))
        out.attributes.emplace_back(a.name(), v->value());
  const Imath::Box2i dw = header.dataWindow();
  const int64_t w = int64_t(dw.max.x) - dw.min.x + 1, h = int64_t(dw.max.y) - dw.min.y + 1;
  check_claimed_size(w, h, name);
  {
    // What the pixels take once read (RGB as floats, the counts, the further channels): a
    // compressed file can claim 16384x16384 pixels in a few hundred bytes.
    const double per_pixel =
        double(sizeof(Rgb)) + (has_counts ? 4.0 : 0.0) + 4.0 * double(out.channels.size());
    const double bytes = double(w) * double(h) * per_pixel;
    if (!(bytes <= double(memory_budget_bytes())))
      fail(
          "cannot read '{}': its {}x{} pixels take {} once read, more than {}; use a smaller "
          "image",
          name, w, h, format_bytes(bytes), memory_budget_phrase());
  }
  if (header.compression() == Imf::NO_COMPRESSION) {
    uint64_t pixel_bytes = 0;
    for (auto c = header.channels().begin(); c != header.channels().end(); ++c)
      pixel_bytes += c.channel().type == Imf::HALF ? 2 : 4;
    std::error_code ec;
    const uintmax_t size = fs::file_size(path, ec);
    if (!ec && pixel_bytes * uint64_t(w) * uint64_t(h) > size)
      fail(
          "cannot read '{}': its header claims {}x{} uncompressed pixels ({} bytes), but the "
          "file has only {} bytes",
          name, w, h, pixel_bytes * uint64_t(w) * uint64_t(h), size);
  }
  // A compressed file can claim any size in a few bytes. The pixels are read in bands of rows
  // and memory is taken band by band as the file delivers them, so a false claim fails at its
  // first missing chunk, having allocated little. 256 rows is a whole number of chunks for
  // every compression (1, 16, 32 or 256 rows each).
  constexpr int64_t kBand = 256;
  std::vector<Rgb> px;
  for (int64_t y0 = 0; y0 < h; y0 += kBand) {
    const int64_t rows = std::min(kBand, h - y0);
    const size_t need = size_t((y0 + rows) * w);
    if (need > px.capacity())
      px.reserve(std::min(size_t(w * h), std::max(need, 2 * px.capacity())));
    px.resize(need);
    if (has_counts) out.counts.resize(need);
    for (auto& ch : out.channels) ch.second.resize(need);
    // OpenEXR addresses pixel (x, y) at base + x * xs + y * ys in data-window coordinates.
    const ptrdiff_t origin = ptrdiff_t(((dw.min.y + y0) * w + dw.min.x) * int64_t(sizeof(Rgb)));
    char* base = reinterpret_cast<char*>(px.data() + y0 * w) - origin;
    const size_t xs = sizeof(Rgb), ys = sizeof(Rgb) * size_t(w);
    Imf::FrameBuffer fb;
    // A grey image's Y goes to R, and is copied to G and B below.
    for (int c = 0; c < 3; ++c)
      if (c == 0 || std::string_view(rgb[c]) != rgb[0])
        fb.insert(rgb[c], Imf::Slice(Imf::FLOAT, base + c * sizeof(float), xs, ys));
    if (has_counts) {
      const ptrdiff_t corigin =
          ptrdiff_t(((dw.min.y + y0) * w + dw.min.x) * int64_t(sizeof(uint32_t)));
      char* cbase = reinterpret_cast<char*>(out.counts.data() + y0 * w) - corigin;
      fb.insert("count",
                Imf::Slice(Imf::UINT, cbase, sizeof(uint32_t), sizeof(uint32_t) * size_t(w)));
    }
    for (auto& [cname, values] : out.channels) {
      const ptrdiff_t forigin =
          ptrdiff_t(((dw.min.y + y0) * w + dw.min.x) * int64_t(sizeof(float)));
      char* fbase = reinterpret_cast<char*>(values.data() + y0 * w) - forigin;
      fb.insert(cname, Imf::Slice(Imf::FLOAT, fbase, sizeof(float), sizeof(float) * size_t(w)));
    }
    file.setFrameBuffer(fb);
    file.readPixels(int(dw.min.y + y0), int(dw.min.y + y0 + rows - 1));
  }
  if (std::string_view(rgb[1]) == rgb[0])
    for (Rgb& p : px) p = Rgb(p.x);
  out.image = Image(int(w), int(h), std::move(px));
  return out;
}

// read_exr_unchecked with OpenEXR's exceptions as rll::Errors naming the file.
ExrFile read_exr(const fs::path& path, bool extras, LuminanceOnly luminance) {
  try {
    return read_exr_unchecked(path, extras, luminance);
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    fail("cannot read '{}': {}", path.string(), e.what());
  }
}

// A folder, a missing file or a device gets a clear message before any reader sees it.
void read_image_checks(const fs::path& path) {
  check_path_text(path, "image");
  std::error_code ec;
  const auto status = fs::status(path, ec);
  if (fs::is_directory(status))
    fail("cannot read '{}': it is a folder, not an image", path.string());
  if (!fs::exists(status)) fail("image '{}' not found", path.string());
  if (!fs::is_regular_file(status))
    fail("cannot read '{}': it is not a regular file (a device or a pipe?)", path.string());
}

// Writes the EXR to `tmp` (removed on failure; the caller commits it to `path`).
void write_exr_to(const fs::path& tmp, const fs::path& path, const Image& image,
                  const std::vector<std::pair<std::string, std::string>>& attributes,
                  const std::vector<uint32_t>* counts,
                  const std::vector<std::pair<std::string, std::vector<float>>>& channels) {
  try {
    Imf::Header header(image.width(), image.height());
    header.compression() = Imf::ZIP_COMPRESSION;
    for (const char* c : {"R", "G", "B"}) header.channels().insert(c, Imf::Channel(Imf::FLOAT));
    if (counts) header.channels().insert("count", Imf::Channel(Imf::UINT));
    for (const auto& ch : channels) header.channels().insert(ch.first, Imf::Channel(Imf::FLOAT));
    for (const auto& [name, value] : attributes) header.insert(name, Imf::StringAttribute(value));
    Imf::OutputFile file(tmp.c_str(), header);
    Imf::FrameBuffer fb;
    char* base = (char*)image.pixels().data();
    size_t xs = sizeof(Rgb), ys = sizeof(Rgb) * image.width();
    fb.insert("R", Imf::Slice(Imf::FLOAT, base, xs, ys));
    fb.insert("G", Imf::Slice(Imf::FLOAT, base + sizeof(float), xs, ys));
    fb.insert("B", Imf::Slice(Imf::FLOAT, base + 2 * sizeof(float), xs, ys));
    if (counts)
      fb.insert("count", Imf::Slice(Imf::UINT, (char*)counts->data(), sizeof(uint32_t),
                                    sizeof(uint32_t) * image.width()));
    for (const auto& [cname, values] : channels)
      fb.insert(cname, Imf::Slice(Imf::FLOAT, (char*)values.data(), sizeof(float),
                                  sizeof(float) * image.width()));
    file.setFrameBuffer(fb);
    file.writePixels(image.height());
  } catch (const std::exception& e) {
    std::error_code ec;
    fs::remove(tmp, ec);
    fail("cannot write '{}': {}", path.string(), e.what());
  }
}

// Refuses what no reader can open: an empty image; then prepare_write's checks.
fs::path check_writable_image(const fs::path& path, const Image& image) {
  if (image.width() <= 0 || image.height() <= 0)
    fail("cannot write '{}': empty image", path.string());
  return prepare_write(path);
}

}  // namespace

std::string bad_emission_texel(const Image& image) {
  for (int y = 0; y < image.height(); ++y)
    for (int x = 0; x < image.width(); ++x)
      if (const Rgb& c = image.at(x, y); !is_finite(c) || min_component(c) < 0)
        return fmt::format("texel ({}, {}) is ({}, {}, {})", x, y, c.x, c.y, c.z);
  return "";
}

const std::string* ExrFile::attribute(const std::string& name) const {
  for (const auto& [n, v] : attributes)
    if (n == name) return &v;
  return nullptr;
}

void write_exr(const fs::path& path, const ExrFile& file) {
  if (!file.counts.empty() && file.counts.size() != file.image.pixel_count())
    fail("cannot write '{}': {} sample counts for {} pixels", path.string(), file.counts.size(),
         file.image.pixel_count());
  for (const auto& [name, values] : file.channels)
    if (values.size() != file.image.pixel_count() || name.empty() || name == "count" ||
        name == "R" || name == "G" || name == "B")
      fail("cannot write '{}': channel '{}' has {} values for {} pixels, or a reserved name",
           path.string(), name, values.size(), file.image.pixel_count());
  const fs::path tmp = temp_sibling(check_writable_image(path, file.image));
  write_exr_to(tmp, path, file.image, file.attributes, file.counts.empty() ? nullptr : &file.counts,
               file.channels);
  commit(tmp, path);
}

ExrFile read_exr_file(const fs::path& path) {
  if (lower_extension(path) != ".exr") fail("'{}' is not an OpenEXR file (.exr)", path.string());
  read_image_checks(path);
  return read_exr(path, true, LuminanceOnly::refuse);
}

uint8_t to_srgb8(float v, float scale) {
  v *= scale;
  if (!(v > 0)) return 0;  // also maps NaN to black
  if (v >= 1) return 255;
  float s = v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1 / 2.4f) - 0.055f;
  return uint8_t(clamp(int(s * 255.0f + 0.5f), 0, 255));
}

void write_file_atomic(const fs::path& path, const std::string& bytes) {
  const fs::path tmp = temp_sibling(prepare_write(path));
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
  const fs::path target = check_writable_image(path, image);
  std::string ext = lower_extension(path);
  const fs::path tmp = temp_sibling(target);
  if (ext == ".exr") {
    write_exr_to(tmp, path, image, {}, nullptr, {});
  } else if (ext == ".png") {
    float scale = std::exp2(exposure_stops);
    std::vector<uint8_t> px(image.pixel_count() * 3);
    for (size_t i = 0; i < image.pixel_count(); ++i)
      for (int c = 0; c < 3; ++c) px[3 * i + c] = to_srgb8(image[i][c], scale);
    // Encoded in memory: stbi_write_png ignores errors of its own file writes.
    write_file_atomic(path, png_bytes(px, image.width(), image.height(), 3));
    return;
  } else {
    fail("cannot write '{}': unknown image extension '{}' (use .exr or .png)", path.string(), ext);
  }
  commit(tmp, path);
}

Image read_image(const fs::path& path, bool srgb, LuminanceOnly luminance) {
  read_image_checks(path);
  if (lower_extension(path) == ".exr") return read_exr(path, false, luminance).image;
  const std::string bytes = read_file_bytes(path);
  return decode_stb(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size(), srgb,
                    lower_extension(path) == ".hdr", path.string());
}

Image decode_image(const unsigned char* bytes, size_t size, bool srgb, const std::string& name) {
  if (size > size_t(INT32_MAX)) fail("cannot read '{}': the image is too large", name);
  return decode_stb(bytes, size, srgb, stbi_is_hdr_from_memory(bytes, int(size)) != 0, name);
}

}  // namespace rll
