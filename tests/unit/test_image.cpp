// Image files: EXR keeps floats exactly, PNG keeps its 8-bit sRGB quantisation, and writes are
// atomic: no temporary file is left behind and a failed write leaves the old file as it was.
// Reads check a header's size claim before taking memory for it.
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <ImfPreviewImageAttribute.h>
#include <ImfStringAttribute.h>
#include <ImfStringVectorAttribute.h>
#include <ImfTiledOutputFile.h>
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstring>
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
      fb.insert(c == 0   ? "R"
                : c == 1 ? "G"
                         : "B",
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
                    decode_image(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size(),
                                 true, "mem.hdr");
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

// A 4 x 3 EXR of the given float channels, channel k holding (k + 1) / 4 everywhere, with
// `header` filled in further by `more` (attributes).
void write_exr_channels(const fs::path& path, const std::vector<std::string>& channels,
                        const std::function<void(Imf::Header&)>& more = {}) {
  const int w = 4, h = 3;
  Imf::Header header(w, h);
  for (const auto& c : channels) header.channels().insert(c, Imf::Channel(Imf::FLOAT));
  if (more) more(header);
  std::vector<std::vector<float>> data;
  Imf::FrameBuffer fb;
  for (size_t k = 0; k < channels.size(); ++k) {
    data.emplace_back(size_t(w) * h, float(k + 1) / 4);
    fb.insert(channels[k], Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(data.back().data()),
                                      sizeof(float), sizeof(float) * w));
  }
  Imf::OutputFile file(path.c_str(), header);
  file.setFrameBuffer(fb);
  file.writePixels(h);
}

// Overwrites the 32-bit little-endian integers `skip` bytes after the first `marker` in a file.
void patch_ints_after(const fs::path& path, const std::string& marker, size_t skip,
                      std::initializer_list<int32_t> values) {
  std::string bytes = read_bytes(path);
  const size_t at = bytes.find(marker);
  ASSERT_NE(at, std::string::npos) << "no " << marker << " in " << path;
  size_t pos = at + marker.size() + skip;
  for (int32_t v : values) {
    for (int b = 0; b < 4; ++b) bytes[pos++] = char((uint32_t(v) >> (8 * b)) & 0xff);
  }
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

// An attribute's name and type as they stand in an EXR header, each ended by a zero byte.
std::string attribute_marker(const std::string& name, const std::string& type) {
  return name + std::string(1, '\0') + type + std::string(1, '\0');
}

TEST(ImageFiles, ExrMissingAColourChannelIsRefusedNamingIt) {
  TempDir dir;
  write_exr_channels(dir / "gb.exr", {"G", "B"});
  expect_mentions(error_of([&] { read_image(dir / "gb.exr"); }),
                  {"gb.exr", "no channel R", "B, G"});
  expect_mentions(error_of([&] { read_exr_file(dir / "gb.exr"); }), {"gb.exr", "no channel R"});
  write_exr_channels(dir / "r.exr", {"R", "A"});
  expect_mentions(error_of([&] { read_image(dir / "r.exr"); }), {"r.exr", "no channel G, B"});
  // Luminance and chroma (Y, RY, BY) is not a grey image: reading its Y alone would lose colour.
  write_exr_channels(dir / "yc.exr", {"Y", "RY", "BY"});
  expect_mentions(error_of([&] { read_image(dir / "yc.exr"); }), {"yc.exr", "no channel R, G, B"});
  // Other channels beside R, G and B are no harm.
  write_exr_channels(dir / "rgba.exr", {"R", "G", "B", "A"});
  EXPECT_EQ(read_image(dir / "rgba.exr")[5], Rgb(0.25f, 0.5f, 0.75f));
}

TEST(ImageFiles, LuminanceOnlyExrIsGreyOrRefusedAsTheCallerAsks) {
  TempDir dir;
  write_exr_channels(dir / "y.exr", {"Y"});
  const Image grey = read_image(dir / "y.exr");  // a texture, an environment map
  ASSERT_EQ(grey.pixel_count(), 12u);
  for (size_t i = 0; i < grey.pixel_count(); ++i) ASSERT_EQ(grey[i], Rgb(0.25f)) << "pixel " << i;
  expect_mentions(error_of([&] { read_image(dir / "y.exr", true, LuminanceOnly::refuse); }),
                  {"y.exr", "luminance channel Y", "no R, G, B"});
  // A render share is never grey.
  expect_mentions(error_of([&] { read_exr_file(dir / "y.exr"); }), {"y.exr", "luminance"});
}

TEST(ImageFiles, ExrHeaderClaimsAreCheckedAgainstTheFileWithoutTakingTheirMemory) {
  ::testing::FLAGS_gtest_death_test_style = "threadsafe";
  TempDir dir;
  // A string attribute claiming 2^31 - 1 bytes: OpenEXR alone allocates them before reading.
  const fs::path share = dir / "share.exr";
  write_exr_channels(share, {"R", "G", "B"},
                     [](Imf::Header& h) { h.insert("rll.share", Imf::StringAttribute("{}")); });
  ASSERT_LT(fs::file_size(share), 1000u);
  patch_ints_after(share, attribute_marker("rll.share", "string"), 0, {INT32_MAX});
  EXPECT_REFUSED_IN_BOUNDED_MEMORY(read_exr_file(share), "share.exr.*'rll.share'.*2147483647");
  EXPECT_REFUSED_IN_BOUNDED_MEMORY(read_image(share), "share.exr.*'rll.share'");  // a texture
  // Counts inside values, which OpenEXR 3.1 checks itself (these pass without rll's check too):
  // a string inside a string vector,
  const fs::path names = dir / "names.exr";
  write_exr_channels(names, {"R", "G", "B"}, [](Imf::Header& h) {
    h.insert("names", Imf::StringVectorAttribute({"abc"}));
  });
  patch_ints_after(names, attribute_marker("names", "stringvector"), 4, {INT32_MAX});
  EXPECT_REFUSED_IN_BOUNDED_MEMORY(read_image(names), "names.exr");
  // a preview image of 60000 x 60000 (14 GB) in an attribute of 24 bytes,
  const fs::path preview = dir / "preview.exr";
  write_exr_channels(preview, {"R", "G", "B"}, [](Imf::Header& h) {
    h.insert("preview", Imf::PreviewImageAttribute(Imf::PreviewImage(2, 2)));
  });
  patch_ints_after(preview, attribute_marker("preview", "preview"), 4, {60000, 60000});
  EXPECT_REFUSED_IN_BOUNDED_MEMORY(read_image(preview), "preview.exr");
  // a tiled image of 16000 x 16000 one-pixel tiles: 2 GB of tile offsets the file cannot hold.
  const fs::path tiled = dir / "tiled.exr";
  {
    Imf::Header hd(64, 64);
    for (const char* c : {"R", "G", "B"}) hd.channels().insert(c, Imf::Channel(Imf::HALF));
    hd.setTileDescription(Imf::TileDescription(64, 64));
    Imf::TiledOutputFile out(tiled.c_str(), hd);
  }
  patch_ints_after(tiled, attribute_marker("dataWindow", "box2i"), 4, {0, 0, 15999, 15999});
  patch_ints_after(tiled, attribute_marker("displayWindow", "box2i"), 4, {0, 0, 15999, 15999});
  patch_ints_after(tiled, attribute_marker("tiles", "tiledesc"), 4, {1, 1});
  EXPECT_REFUSED_IN_BOUNDED_MEMORY(read_image(tiled), "tiled.exr");
}

// OpenEXR reads a value of a type it knows by its type, not by its size field, and reads on from
// where the value ends: each value must fill its size exactly, or OpenEXR would read attributes
// that the check of every size claim never saw.
TEST(ImageFiles, ExrAttributeValuesMustFillTheirSizeFields) {
  ::testing::FLAGS_gtest_death_test_style = "threadsafe";
  TempDir dir;
  const std::string aspect = attribute_marker("pixelAspectRatio", "float");
  // A float whose size field claims 4 + 16 bytes, the 16 an attribute of an unknown type claiming
  // 2^31 - 1 bytes: OpenEXR reads the float's 4 bytes, then this hidden attribute, and allocates
  // 2 GiB for it; a walk by the size fields skips it.
  const fs::path hidden = dir / "hidden.exr";
  write_exr_channels(hidden, {"R", "G", "B"});
  {
    std::string bytes = read_bytes(hidden);
    const size_t value = bytes.find(aspect) + aspect.size() + 4;
    const std::string claim =
        attribute_marker("hidden", "blob") + std::string("\xff\xff\xff\x7f", 4);
    bytes.insert(value + 4, claim);
    std::ofstream(hidden, std::ios::binary | std::ios::trunc) << bytes;
  }
  patch_ints_after(hidden, aspect, 0, {4 + 16});
  EXPECT_REFUSED_IN_BOUNDED_MEMORY(read_image(hidden),
                                   "hidden.exr.*'pixelAspectRatio'.*float.*4 bytes.*claims 20");
  // A channel list longer than its size field (the fuzzer's case: OpenEXR reads the whole list
  // and then attributes from inside it; here it would read the file as if nothing were wrong).
  const fs::path list = dir / "list.exr";
  write_exr_channels(list, {"R", "G", "B"});
  patch_ints_after(list, attribute_marker("channels", "chlist"), 0, {19});
  expect_mentions(error_of([&] { read_image(list); }),
                  {"list.exr", "attribute 'channels' of type chlist", "its 19 bytes"});
  // Names are shown as UTF-8 (OpenEXR's names are UTF-8), other bytes escaped, not as '?'.
  const fs::path named = dir / "named.exr";
  write_exr_channels(named, {"R", "G", "B"}, [](Imf::Header& h) {
    h.insert("caf\xc3\xa9", Imf::StringAttribute("x"));
    h.insert("bad\xff", Imf::StringAttribute("y"));
  });
  patch_ints_after(named, attribute_marker("caf\xc3\xa9", "string"), 0, {1 << 30});
  expect_mentions(error_of([&] { read_image(named); }), {"named.exr", "'caf\xc3\xa9'"});
  patch_ints_after(named, attribute_marker("caf\xc3\xa9", "string"), 0, {1});
  patch_ints_after(named, attribute_marker("bad\xff", "string"), 0, {1 << 30});
  expect_mentions(error_of([&] { read_image(named); }), {"named.exr", "'bad\\xff'"});
  // A value of a type OpenEXR does not know is read by its size, as the walk reads it.
  const fs::path opaque = dir / "opaque.exr";
  write_exr_channels(opaque, {"R", "G", "B"},
                     [](Imf::Header& h) { h.insert("note", Imf::StringAttribute("0123456789")); });
  {
    std::string bytes = read_bytes(opaque);
    const std::string note = attribute_marker("note", "string");
    bytes.replace(bytes.find(note), note.size(), attribute_marker("note", "blobby"));
    std::ofstream(opaque, std::ios::binary | std::ios::trunc) << bytes;
  }
  EXPECT_EQ(read_image(opaque)[5], Rgb(0.25f, 0.5f, 0.75f));
}

// OpenEXR takes a line buffer and its compressor's buffers for one chunk of rows of every
// channel when it opens a file, before rll reads a pixel: the data window and the chunk are
// checked before it opens the file.
TEST(ImageFiles, ExrOpeningBuffersAreCheckedBeforeOpenExrTakesThem) {
  ::testing::FLAGS_gtest_death_test_style = "threadsafe";
  TempDir dir;
  const std::string window = attribute_marker("dataWindow", "box2i");
  // 2^23 x 1 pixels (OpenEXR refuses rows of 2 GB and more itself): each of its ZIP buffers
  // (16 rows) takes 1.6 GB, in a file of 400 bytes.
  const fs::path wide = dir / "wide.exr";
  write_exr_channels(wide, {"R", "G", "B"});
  patch_ints_after(wide, window, 4, {0, 0, (1 << 23) - 1, 0});
  EXPECT_REFUSED_IN_BOUNDED_MEMORY(read_image(wide), "wide.exr.*claims 8388608x1 pixels");
  // 65536 x 1, within the sizes rll reads: 3 buffers of 16 rows, 36 MiB, over a budget of 16 MiB.
  const fs::path chunk = dir / "chunk.exr";
  write_exr_channels(chunk, {"R", "G", "B"});
  patch_ints_after(chunk, window, 4, {0, 0, 65535, 0});
  {
    BudgetScope budget(size_t(16) << 20);
    expect_mentions(error_of([&] { read_image(chunk); }),
                    {"opening '", "chunk.exr", "1048576 pixels in 3 channels", "needs 36.0 MiB"});
  }
}

TEST(ImageFiles, ShareCountsMustBeUnsignedIntegers) {
  TempDir dir;
  write_exr_channels(dir / "float_count.exr", {"R", "G", "B", "count"});
  expect_mentions(error_of([&] { read_exr_file(dir / "float_count.exr"); }),
                  {"float_count.exr", "'count'", "32-bit unsigned"});
}

}  // namespace
