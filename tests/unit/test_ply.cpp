// PLY reader: ASCII and both binary byte orders give the same mesh, normals and uvs are read
// when present, polygons are fan-triangulated, and every malformed file is an rll::Error naming
// the file and the line or byte offset.
#include <gtest/gtest.h>


#include <cstring>

#include "rll/io/load.h"
#include "rll/io/save.h"
#include "support/test_support.h"

using namespace rll;
using rll::test::error_of;
using rll::test::expect_mentions;
using rll::test::TempDir;

namespace {

// Two triangles of a unit quad with normals and uvs.
Mesh quad_mesh() {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0.5f}};
  m.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0.6f, 0.8f}, {0, 0, 1}};
  m.uvs = {{0, 0}, {1, 0}, {1, 1}, {0.25f, 1}};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

std::string ply_error(std::string_view bytes) {
  return error_of([&] { parse_ply(bytes, "bad.ply"); });
}

const char* kHeader =
    "ply\n"
    "format ascii 1.0\n"
    "element vertex 3\n"
    "property float x\n"
    "property float y\n"
    "property float z\n"
    "element face 1\n"
    "property list uchar int vertex_indices\n"
    "end_header\n";

}  // namespace

TEST(PlyReader, AllEncodingsReadTheSameMeshBitForBit) {
  const Mesh m = quad_mesh();
  for (PlyEncoding e :
       {PlyEncoding::Ascii, PlyEncoding::BinaryLittleEndian, PlyEncoding::BinaryBigEndian}) {
    SCOPED_TRACE(int(e));
    Mesh r = parse_ply(ply_bytes(m, e), "m.ply");
    ASSERT_EQ(r.positions.size(), 4u);
    ASSERT_EQ(r.normals.size(), 4u);
    ASSERT_EQ(r.uvs.size(), 4u);
    ASSERT_EQ(r.triangles.size(), 2u);
    for (size_t i = 0; i < 4; ++i) {
      EXPECT_EQ(r.positions[i], m.positions[i]);
      EXPECT_EQ(r.normals[i], m.normals[i]);
      EXPECT_EQ(r.uvs[i].x, m.uvs[i].x);
      EXPECT_EQ(r.uvs[i].y, m.uvs[i].y);
    }
    EXPECT_EQ(r.triangles, m.triangles);
  }
}

TEST(PlyReader, FanTriangulatesPolygonsAndReadsOtherUvNames) {
  const std::string text =
      "ply\r\n"
      "format ascii 1.0\r\n"
      "comment a pentagon, faces before vertices, with an extra element\r\n"
      "element face 1\r\n"
      "property list uchar uint vertex_index\r\n"
      "property uchar flags\r\n"
      "element vertex 5\r\n"
      "property double x\r\n"
      "property double y\r\n"
      "property double z\r\n"
      "property float s\r\n"
      "property float t\r\n"
      "property uchar red\r\n"
      "element edge 1\r\n"
      "property int a\r\n"
      "property int b\r\n"
      "end_header\r\n"
      "5 0 1 2 3 4 7\r\n"
      "0 0 0 0 0 255\r\n"
      "1 0 0 1 0 255\r\n"
      "\r\n"
      "2 1 0 1 1 255\r\n"
      "1 2 0 0.5 1 255\r\n"
      "0 1 0 0 1 255\r\n"
      "0 1\r\n";
  Mesh r = parse_ply(text, "penta.ply");
  ASSERT_EQ(r.triangles.size(), 3u);
  EXPECT_EQ(r.triangles[0], (std::array<uint32_t, 3>{0, 1, 2}));
  EXPECT_EQ(r.triangles[2], (std::array<uint32_t, 3>{0, 3, 4}));
  ASSERT_EQ(r.uvs.size(), 5u);
  EXPECT_FLOAT_EQ(r.uvs[3].x, 0.5f);
  EXPECT_TRUE(r.normals.empty());
}

TEST(PlyReader, LoadPlyAddsADefaultMaterial) {
  TempDir dir;
  Mesh m = quad_mesh();
  auto p = dir.write("quad.ply", ply_bytes(m, PlyEncoding::BinaryLittleEndian));
  Scene s;
  load_ply(p, s);
  EXPECT_EQ(s.mesh.triangle_count(), 2u);
  ASSERT_EQ(s.materials.size(), 1u);
  EXPECT_EQ(s.mesh.material, (std::vector<uint32_t>{0, 0}));
}

TEST(PlyReader, HeaderErrorsNameTheLine) {
  expect_mentions(ply_error("plx\n"), {"bad.ply", "not a PLY file"});
  expect_mentions(ply_error("ply\nformat ascii 1.0\nelement vertex 3\n"),
                  {"bad.ply", "no 'end_header'"});
  expect_mentions(ply_error("ply\nformat ascii 2.0\nend_header\n"), {"bad.ply:2:", "version"});
  expect_mentions(ply_error("ply\nformat text 1.0\nend_header\n"), {"bad.ply:2:", "'text'"});
  expect_mentions(ply_error("ply\nformat ascii 1.0\nproperty float x\nend_header\n"),
                  {"bad.ply:3:", "before any element"});
  expect_mentions(ply_error("ply\nformat ascii 1.0\nelement vertex -3\nend_header\n"),
                  {"bad.ply:3:", "'-3'"});
  expect_mentions(
      ply_error("ply\nformat ascii 1.0\nelement vertex 1\nproperty real x\nend_header\n"),
      {"bad.ply:4:", "unknown property type 'real'"});
  expect_mentions(
      ply_error("ply\nformat ascii 1.0\nelement vertex 0\nelement face 0\nend_header\n"),
      {"bad.ply:3:", "no 'x'"});
  expect_mentions(ply_error("ply\nelement vertex 0\nend_header\n"), {"no 'format'"});
  std::string no_faces =
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty "
      "float y\nproperty float z\nend_header\n0 0 0\n";
  expect_mentions(ply_error(no_faces), {"bad.ply", "no 'face' element"});
  std::string float_indices = std::string(kHeader);
  float_indices.replace(float_indices.find("uchar int"), 9, "uchar float");
  expect_mentions(ply_error(float_indices), {"bad.ply:7:", "integer type"});
}

TEST(PlyReader, AsciiDataErrorsNameTheLine) {
  const std::string h = kHeader;  // 9 header lines; data starts on line 10
  expect_mentions(ply_error(h + "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n"),
                  {"bad.ply:13:", "vertex index 7 is out of range"});
  expect_mentions(ply_error(h + "0 0 0\n1 zero 0\n0 1 0\n3 0 1 2\n"), {"bad.ply:11:", "'zero'"});
  expect_mentions(ply_error(h + "0 0 0\n1 0 0 4\n0 1 0\n3 0 1 2\n"), {"bad.ply:11:", "too many"});
  expect_mentions(ply_error(h + "0 0 0\n1 0\n0 1 0\n3 0 1 2\n"), {"bad.ply:11:", "too few"});
  expect_mentions(ply_error(h + "0 0 0\n1 0 0\n0 1 0\n3 0 1\n"), {"bad.ply:13:", "too few"});
  expect_mentions(ply_error(h + "0 0 0\n1 0 0\n0 1 0\n2 0 1\n"),
                  {"bad.ply:13:", "at least 3 are needed"});
  expect_mentions(ply_error(h + "0 0 0\n1 0 0\n0 1 0\n3 0 1 -2\n"), {"bad.ply:13:", "-2"});
  expect_mentions(ply_error(h + "0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n"), {"bad.ply:11:", "non-finite"});
  expect_mentions(ply_error(h + "0 0 0\n1 0 0\n"), {"bad.ply", "ends after 2 of 3"});
  expect_mentions(ply_error(h + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n9 9\n"),
                  {"bad.ply:14:", "after the last element"});
  expect_mentions(ply_error(h + "0 0 0\n1 0 0\n0 1 0\n300 0 1 2\n"), {"bad.ply:13:", "300"});
}

TEST(PlyReader, BinaryErrorsNameTheByteOffset) {
  const std::string good = ply_bytes(quad_mesh(), PlyEncoding::BinaryLittleEndian);
  const size_t body = good.find("end_header\n") + 11;
  // Truncated anywhere in the data: an error, never a read past the end.
  for (size_t cut = body; cut < good.size(); cut += 7)
    expect_mentions(ply_error(good.substr(0, cut)), {"bad.ply", "truncated"});
  // An index out of range in the second face (the last 13 bytes: count + 3 ints).
  std::string bad = good;
  const int32_t big = 99;
  std::memcpy(&bad[bad.size() - 4], &big, 4);
  expect_mentions(ply_error(bad),
                  {"bad.ply: byte " + std::to_string(good.size() - 13), "vertex index 99"});
  // Faces first: their lists take more than the least the header check counts, so the
  // vertices after them must be checked when they are read (a fuzzer found this overrun).
  std::string faces_first =
      "ply\nformat binary_little_endian 1.0\nelement face 1\nproperty list uchar int "
      "vertex_indices\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "end_header\n";
  faces_first += std::string("\x03", 1) + std::string(12, '\0') + std::string(30, '\0');
  expect_mentions(ply_error(faces_first), {"bad.ply: byte 182", "truncated", "'vertex'"});
  // A count that claims more vertices than the bytes could hold.
  std::string lie = good;
  lie.replace(lie.find("vertex 4"), 8, "vertex 400000000");
  expect_mentions(ply_error(lie), {"bad.ply", "truncated"});
}

namespace {

void expect_same_mesh(const Mesh& a, const Mesh& b) {
  ASSERT_EQ(a.positions.size(), b.positions.size());
  ASSERT_EQ(a.triangles, b.triangles);
  EXPECT_EQ(std::memcmp(a.positions.data(), b.positions.data(), a.positions.size() * sizeof(Vec3)),
            0);
  ASSERT_EQ(a.uvs.size(), b.uvs.size());
  EXPECT_EQ(std::memcmp(a.uvs.data(), b.uvs.data(), a.uvs.size() * sizeof(Vec2)), 0);
  ASSERT_EQ(a.normals.size(), b.normals.size());
}

}  // namespace

TEST(PlyReader, GzipCompressedPlyReadsLikeThePlainFile) {
  TempDir dir;
  for (PlyEncoding e : {PlyEncoding::Ascii, PlyEncoding::BinaryLittleEndian}) {
    const std::string plain = ply_bytes(quad_mesh(), e);
    const std::string gz = gzip(plain);
    ASSERT_TRUE(is_gzip(gz));
    ASSERT_FALSE(is_gzip(plain));
    const Mesh a = read_ply_file(dir.write("quad.ply", plain));
    const Mesh b = read_ply_file(dir.write("quad.ply.gz", gz));
    expect_same_mesh(a, b);
    EXPECT_EQ(gunzip(gz, "x.gz"), plain);
    // Two gzip members one after the other are one file (RFC 1952).
    EXPECT_EQ(gunzip(gzip(plain.substr(0, 10)) + gzip(plain.substr(10)), "x.gz"),
              plain);
  }
  // The command's reader takes the compressed file too.
  Scene s;
  load_ply(dir / "quad.ply.gz", s);
  EXPECT_EQ(s.mesh.triangle_count(), quad_mesh().triangle_count());
}

TEST(PlyReader, ScenesReadFromPlyGzAsFromPly) {
  // `rll render x.ply.gz` goes through the same reader as x.ply: a lit quad's scene loads alike
  // from both (a PLY carries no lights: the unlit one is refused alike).
  TempDir dir;
  const std::string plain = ply_bytes(quad_mesh(), PlyEncoding::Ascii);
  dir.write("quad.ply", plain);
  dir.write("quad.ply.gz", gzip(plain));
  const std::string a = error_of([&] { load_scene((dir / "quad.ply").string(), {}); });
  const std::string b = error_of([&] { load_scene((dir / "quad.ply.gz").string(), {}); });
  EXPECT_NE(b.find("no lights"), std::string::npos) << b;
  EXPECT_EQ(a.substr(a.find(": ")), b.substr(b.find(": ")));
}

TEST(PlyReader, TruncatedOrCorruptGzipIsAClearError) {
  TempDir dir;
  const std::string gz = gzip(ply_bytes(quad_mesh(), PlyEncoding::BinaryLittleEndian));
  auto p = dir.write("cut.ply.gz", gz.substr(0, gz.size() / 2));
  expect_mentions(error_of([&] { read_ply_file(p); }), {"cut.ply.gz", "truncated"});
  std::string bad = gz;
  bad[12] = char(~bad[12]);
  bad[13] = char(~bad[13]);
  auto q = dir.write("bad.ply.gz", bad);
  expect_mentions(error_of([&] { read_ply_file(q); }), {"bad.ply.gz"});
  expect_mentions(error_of([&] { gunzip(gz + "xyz", "tail.gz"); }), {"tail.gz", "after the end"});
  expect_mentions(error_of([&] { gunzip(gz, "big.gz", 10); }), {"big.gz", "more than 10 bytes"});
}
