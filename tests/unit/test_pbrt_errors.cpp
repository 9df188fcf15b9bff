// pbrt reader, bad input to the directives added for the pbrt-v4 scenes (loopsubdiv, plymesh with
// .ply.gz, imagemap/scale/mix textures, named spectra, lens parameters, Film iso, ColorSpace):
// each gives an rll::Error naming the file and the line of the offending directive or
// parameter, or, where rll skips what it cannot use, a warning that names them.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <chrono>
#include <string>

#include "rll/core/memory_budget.h"
#include "rll/io/load.h"
#include "rll/io/save.h"
#include "support/test_support.h"

using namespace rll;
using rll::test::error_of;
using rll::test::expect_mentions;
using rll::test::BudgetScope;
using rll::test::TempDir;

namespace {

// "WorldBegin" on line 1, so that the snippet's first line is line 2 of bad.pbrt.
std::string error_in_world(const TempDir& dir, const std::string& snippet) {
  return error_of([&] {
    Scene s;
    load_pbrt(dir.write("bad.pbrt", "WorldBegin\n" + snippet), s);
  });
}

Scene load_world(const TempDir& dir, const std::string& snippet) {
  Scene s;
  load_pbrt(dir.write("s.pbrt", "WorldBegin\n" + snippet), s);
  return s;
}

// The first warning that contains every one of `parts` ("" when none does).
std::string warning_with(const Scene& s, std::initializer_list<std::string> parts) {
  for (const auto& w : s.warnings) {
    bool all = true;
    for (const auto& p : parts) all = all && w.find(p) != std::string::npos;
    if (all) return w;
  }
  return "";
}

// A PLY of a 20 x 20 grid (800 triangles), big enough that its gzip has a real deflate body.
std::string grid_ply() {
  Mesh m;
  const int n = 20;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) m.positions.push_back(Vec3(float(i), 0, float(j)));
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const uint32_t a = uint32_t(j * (n + 1) + i), b = a + 1, c = a + uint32_t(n + 1), d = c + 1;
      m.triangles.push_back({a, c, b});
      m.triangles.push_back({b, c, d});
    }
  return ply_bytes(m, PlyEncoding::Ascii);
}

const char* kTetraP = "\"point3 P\" [ 1 1 1  1 -1 -1  -1 1 -1  -1 -1 1 ]";
const char* kTetraI = "\"integer indices\" [ 0 1 2  0 3 1  0 2 3  1 3 2 ]";

std::string tetra(const std::string& levels) {
  return "Shape \"loopsubdiv\" " + levels + "\n  " + kTetraP + "\n  " + kTetraI + "\n";
}

}  // namespace

// --- Shape "loopsubdiv" ---

TEST(PbrtErrors, LoopsubdivGoodLevelsLoad) {
  // The baseline the bad cases differ from: 4 triangles at 2 levels are 64.
  TempDir dir;
  EXPECT_EQ(load_world(dir, tetra("\"integer levels\" 2")).mesh.triangle_count(), 64u);
  EXPECT_EQ(load_world(dir, tetra("\"integer levels\" 0")).mesh.triangle_count(), 4u);
}

TEST(PbrtErrors, LoopsubdivNegativeLevels) {
  TempDir dir;
  expect_mentions(error_in_world(dir, tetra("\"integer levels\" -1")),
                  {"bad.pbrt:2:", "loopsubdiv", "levels", "negative", "-1"});
}

TEST(PbrtErrors, LoopsubdivNonIntegerLevels) {
  TempDir dir;
  // The parameter is on line 3: the message points at it.
  expect_mentions(error_in_world(dir, "Shape \"loopsubdiv\"\n  \"integer levels\" 2.5\n  " +
                                          std::string(kTetraP) + " " + kTetraI + "\n"),
                  {"bad.pbrt:3:", "loopsubdiv", "levels", "must be an integer"});
  expect_mentions(error_in_world(dir, tetra("\"float levels\" 2")),
                  {"bad.pbrt:2:", "levels", "integer"});
  expect_mentions(error_in_world(dir, tetra("\"integer levels\" [ 1 2 ]")),
                  {"bad.pbrt:2:", "levels", "1 value"});
  // A whole number in float notation is read exactly, then checked against the range.
  expect_mentions(error_in_world(dir, tetra("\"integer levels\" 1e12")),
                  {"bad.pbrt:2:", "levels", "out of range", "1000000000000"});
  expect_mentions(error_in_world(dir, tetra("\"integer levels\" 1.25e1")),
                  {"bad.pbrt:2:", "levels", "must be an integer"});
}

TEST(PbrtErrors, LoopsubdivHugeLevelsAreRefusedBeforeAllocating) {
  TempDir dir;
  // 14 levels of 4 triangles would be 2^30 triangles (tens of GB), still under the default
  // triangle budget (2^31): the level cap (10) refuses it, at once.
  for (const char* levels : {"11", "14", "1000", "1000000"}) {
    const auto t0 = std::chrono::steady_clock::now();
    expect_mentions(error_in_world(dir, tetra(std::string("\"integer levels\" ") + levels)),
                    {"bad.pbrt:2:", "loopsubdiv", "levels must be at most 10", levels});
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 2.0);
  }
  // Integers are read exactly, not through a float: the message repeats the very number.
  for (const char* levels : {"2147483647", "16777217"})
    expect_mentions(error_in_world(dir, tetra(std::string("\"integer levels\" ") + levels)),
                    {"bad.pbrt:2:", "loopsubdiv", "levels must be at most 10",
                     std::string("got ") + levels + ")"});
  // Under the cap, the triangle budget of the read policy is checked before subdividing.
  ReadPolicy policy;
  policy.max_triangles = 1000;
  Scene s;
  const std::string e = error_of([&] {
    parse_pbrt("WorldBegin\n" + tetra("\"integer levels\" 5"), "budget.pbrt", "", s, policy);
  });
  expect_mentions(e, {"budget.pbrt:2:", "loopsubdiv", "5 levels", "more than 1000 triangles"});
  EXPECT_EQ(s.mesh.triangle_count(), 0u);
}

TEST(PbrtErrors, LoopsubdivIndexCountNotAMultipleOf3) {
  TempDir dir;
  expect_mentions(error_in_world(dir, std::string("Shape \"loopsubdiv\" ") + kTetraP +
                                          "\n  \"integer indices\" [ 0 1 2  0 3 ]\n"),
                  {"bad.pbrt:3:", "loopsubdiv", "indices", "multiple of 3", "got 5"});
  expect_mentions(error_in_world(dir, "Shape \"loopsubdiv\" \"point3 P\" [ 0 0 0 1 0 0 0 1 ]\n  " +
                                          std::string(kTetraI) + "\n"),
                  {"bad.pbrt:2:", "loopsubdiv", "P", "multiple of 3"});
  expect_mentions(error_in_world(dir, std::string("Shape \"loopsubdiv\" ") + kTetraP + "\n"),
                  {"bad.pbrt:2:", "loopsubdiv", "needs \"integer indices\""});
}

TEST(PbrtErrors, LoopsubdivIndexOutOfRange) {
  TempDir dir;
  expect_mentions(error_in_world(dir, std::string("Shape \"loopsubdiv\" ") + kTetraP +
                                          " \"integer indices\" [ 0 1 2  0 3 4 ]\n"),
                  {"bad.pbrt:2:", "loopsubdiv", "index 4 is out of range", "4 vertices"});
  expect_mentions(error_in_world(dir, std::string("Shape \"loopsubdiv\" ") + kTetraP +
                                          " \"integer indices\" [ 0 1 -1 ]\n"),
                  {"bad.pbrt:2:", "loopsubdiv", "index -1 is out of range"});
}

TEST(PbrtErrors, IntegerParametersAreExact) {
  // 16777217 = 2^24 + 1 is the first integer a float cannot hold (it would read as 16777216):
  // the index is read exactly, and so reported.
  TempDir dir;
  const std::string tri = "Shape \"trianglemesh\" \"point3 P\" [ 0 0 0  1 0 0  0 1 0 ]\n";
  expect_mentions(error_in_world(dir, tri + "  \"integer indices\" [ 0 1 16777217 ]\n"),
                  {"bad.pbrt:2:", "trianglemesh", "index 16777217 is out of range", "3 vertices"});
  expect_mentions(error_in_world(dir, tri + "  \"integer indices\" [ 0 1 9223372036854775807 ]\n"),
                  {"bad.pbrt:2:", "index 9223372036854775807 is out of range"});
  expect_mentions(error_in_world(dir, std::string("Shape \"bilinearmesh\" ") +
                                          "\"point3 P\" [ 0 0 0  1 0 0  0 1 0  1 1 0 ]\n"
                                          "  \"integer indices\" [ 0 1 2 16777219 ]\n"),
                  {"bad.pbrt:2:", "bilinearmesh", "index 16777219 is out of range"});
  // The largest 64-bit integers are exact; beyond them, an error naming the value's line.
  expect_mentions(
      error_in_world(dir, tri + "  \"integer indices\" [ 0 1\n  -9223372036854775809 ]\n"),
      {"bad.pbrt:4:", "Shape \"trianglemesh\"", "\"integer indices\"", "-9223372036854775809",
       "out of range"});
  // A value of a 32-bit parameter beyond 32 bits is out of range, not wrapped.
  expect_mentions(error_of([&] {
                    Scene s;
                    load_pbrt(dir.write("bad.pbrt",
                                        "Film \"rgb\" \"integer xresolution\" "
                                        "4294967360\nWorldBegin\n"),
                              s);
                  }),
                  {"bad.pbrt:1:", "Film \"rgb\"", "xresolution", "out of range", "4294967360"});
  // Not a whole number: an error naming the directive, the parameter, the value and its line,
  // in brackets or not.
  expect_mentions(
      error_in_world(dir, tetra("\"integer levels\" [ 1.5 ]")),
      {"bad.pbrt:2:", "Shape \"loopsubdiv\"", "\"integer levels\"", "must be an integer", "'1.5'"});
  expect_mentions(error_in_world(dir, tri + "  \"integer indices\" [ 0 1 2.5 ]\n"),
                  {"bad.pbrt:3:", "\"integer indices\"", "must be an integer", "'2.5'"});
  // A whole number in float notation is read exactly up to 2^53, refused beyond.
  expect_mentions(error_in_world(dir, tri + "  \"integer indices\" [ 0 1 16777217.0 ]\n"),
                  {"bad.pbrt:2:", "index 16777217 is out of range"});
  expect_mentions(error_in_world(dir, tri + "  \"integer indices\" [ 0 1 1e30 ]\n"),
                  {"bad.pbrt:3:", "\"integer indices\"", "1e30 is out of range"});
  expect_mentions(error_in_world(dir, tri + "  \"integer indices\" [ 0 1 2x ]\n"),
                  {"bad.pbrt:3:", "expected a number", "'2x'"});
  // Signs as pbrt writes them.
  EXPECT_EQ(load_world(dir, tri + "  \"integer indices\" [ +0 1 2 ]\n").mesh.triangle_count(), 1u);
}

TEST(PbrtErrors, LoopsubdivNonManifoldControlMesh) {
  TempDir dir;
  // Three triangles on one edge.
  expect_mentions(error_in_world(dir,
                                 "\n\nShape \"loopsubdiv\" \"integer levels\" 1\n"
                                 "  \"point3 P\" [ 0 0 0  1 0 0  0 1 0  0 -1 0  0 0 1 ]\n"
                                 "  \"integer indices\" [ 0 1 2  1 0 3  0 1 4 ]\n"),
                  {"bad.pbrt:4:", "loopsubdiv", "not a manifold"});
  // Two triangles that traverse their shared edge in the same direction (inconsistent winding).
  expect_mentions(error_in_world(dir,
                                 "Shape \"loopsubdiv\" \"integer levels\" 1\n"
                                 "  \"point3 P\" [ 0 0 0  1 0 0  0 1 0  0 -1 0 ]\n"
                                 "  \"integer indices\" [ 0 1 2  0 1 3 ]\n"),
                  {"bad.pbrt:2:", "loopsubdiv", "not consistently oriented"});
  // Two fans meeting at one vertex (a bow tie).
  expect_mentions(error_in_world(dir,
                                 "Shape \"loopsubdiv\" \"integer levels\" 1\n"
                                 "  \"point3 P\" [ 0 0 0  1 0 0  1 1 0  -1 0 0  -1 -1 0 ]\n"
                                 "  \"integer indices\" [ 0 1 2  0 3 4 ]\n"),
                  {"bad.pbrt:2:", "loopsubdiv", "not a manifold"});
  // A degenerate triangle (a vertex used twice).
  expect_mentions(error_in_world(dir, std::string("Shape \"loopsubdiv\" ") + kTetraP +
                                          " \"integer indices\" [ 0 1 1 ]\n"),
                  {"bad.pbrt:2:", "loopsubdiv", "twice"});
}

// --- Shape "plymesh" ---

TEST(PbrtErrors, PlymeshMissingFile) {
  TempDir dir;
  expect_mentions(error_in_world(dir, "Shape \"plymesh\" \"string filename\" \"nothere.ply.gz\"\n"),
                  {"bad.pbrt:2:", "plymesh", "nothere.ply.gz"});
  expect_mentions(error_in_world(dir, "Shape \"plymesh\"\n"),
                  {"bad.pbrt:2:", "plymesh", "filename"});
}

TEST(PbrtErrors, PlymeshGzipGoodThenTruncatedAndCorrupt) {
  TempDir dir;
  const std::string gz = gzip(grid_ply());
  ASSERT_GT(gz.size(), 200u);
  dir.write("good.ply.gz", gz);
  EXPECT_EQ(load_world(dir, "Shape \"plymesh\" \"string filename\" \"good.ply.gz\"\n")
                .mesh.triangle_count(),
            800u);
  // Cut inside the deflate stream, and cut to the gzip header alone.
  dir.write("cut.ply.gz", gz.substr(0, gz.size() / 2));
  expect_mentions(error_in_world(dir, "Shape \"plymesh\" \"string filename\" \"cut.ply.gz\"\n"),
                  {"bad.pbrt:2:", "plymesh", "cut.ply.gz", "truncated"});
  dir.write("head.ply.gz", gz.substr(0, 10));
  expect_mentions(error_in_world(dir, "Shape \"plymesh\" \"string filename\" \"head.ply.gz\"\n"),
                  {"bad.pbrt:2:", "plymesh", "head.ply.gz", "truncated"});
  // Damaged deflate data, and a damaged CRC in the trailer.
  std::string bad = gz;
  for (size_t i = 20; i < 60; ++i) bad[i] = char(~uint8_t(bad[i]));
  dir.write("corrupt.ply.gz", bad);
  expect_mentions(error_in_world(dir, "Shape \"plymesh\" \"string filename\" \"corrupt.ply.gz\"\n"),
                  {"bad.pbrt:2:", "plymesh", "corrupt.ply.gz", "corrupt gzip data"});
  std::string crc = gz;
  crc[crc.size() - 6] = char(~uint8_t(crc[crc.size() - 6]));
  dir.write("crc.ply.gz", crc);
  expect_mentions(error_in_world(dir, "Shape \"plymesh\" \"string filename\" \"crc.ply.gz\"\n"),
                  {"bad.pbrt:2:", "plymesh", "crc.ply.gz", "corrupt gzip data"});
  // Good gzip around bytes that are not a PLY, and junk after the gzip stream.
  dir.write("notply.ply.gz", gzip("this is not a PLY file\n"));
  expect_mentions(error_in_world(dir, "Shape \"plymesh\" \"string filename\" \"notply.ply.gz\"\n"),
                  {"bad.pbrt:2:", "plymesh", "notply.ply.gz"});
  dir.write("tail.ply.gz", gz + "junk");
  expect_mentions(error_in_world(dir, "Shape \"plymesh\" \"string filename\" \"tail.ply.gz\"\n"),
                  {"bad.pbrt:2:", "plymesh", "tail.ply.gz", "after the end of the gzip stream"});
}

// --- textures ---

TEST(PbrtErrors, ImagemapMissingFile) {
  TempDir dir;
  expect_mentions(error_in_world(dir,
                                 "Texture \"wood\" \"spectrum\" \"imagemap\"\n"
                                 "  \"string filename\" \"wood.png\"\n"),
                  {"bad.pbrt:2:", "Texture", "wood.png"});
  expect_mentions(error_in_world(dir, "Texture \"wood\" \"spectrum\" \"imagemap\"\n"),
                  {"bad.pbrt:2:", "Texture \"wood\"", "filename"});
  // A file that exists but is not an image.
  dir.write("junk.png", "not a png");
  expect_mentions(error_in_world(dir,
                                 "Texture \"j\" \"float\" \"imagemap\" \"string filename\" "
                                 "\"junk.png\"\n"),
                  {"bad.pbrt:2:", "Texture \"j\"", "junk.png"});
}

TEST(PbrtErrors, ReferenceToAnUndefinedTextureIsAnErrorWithItsLine) {
  // As in pbrt-v4, a texture must be defined (by a Texture directive before it) to be used: the
  // error names the texture, the directive, the parameter and the parameter's line.
  TempDir dir;
  expect_mentions(
      error_in_world(dir,
                     "\nTexture \"s\" \"spectrum\" \"scale\" \"texture tex\" "
                     "\"nosuch\"\n"),
      {"bad.pbrt:3:", "Texture \"s\"", "\"texture tex\"", "texture \"nosuch\"", "not defined"});
  expect_mentions(
      error_in_world(dir,
                     "Texture \"m\" \"float\" \"mix\" \"float tex1\" 0 \"float tex2\" 1\n"
                     "  \"texture amount\" \"missing\"\n"),
      {"bad.pbrt:3:", "Texture \"m\"", "amount", "texture \"missing\""});
  expect_mentions(
      error_in_world(dir, "Material \"diffuse\"\n  \"texture reflectance\" \"nosuch\"\n"),
      {"bad.pbrt:3:", "Material \"diffuse\"", "reflectance", "texture \"nosuch\""});
  expect_mentions(error_in_world(dir,
                                 "MakeNamedMaterial \"m\" \"string type\" \"conductor\"\n"
                                 "  \"texture roughness\" \"r\"\n"),
                  {"bad.pbrt:3:", "MakeNamedMaterial \"m\"", "roughness", "texture \"r\""});
  // Defined after its use is not defined.
  expect_mentions(
      error_in_world(dir,
                     "Material \"coateddiffuse\" \"texture reflectance\" \"late\"\n"
                     "Texture \"late\" \"spectrum\" \"constant\" \"rgb value\" [ 1 0 0 ]\n"),
      {"bad.pbrt:2:", "texture \"late\"", "not defined"});
  // Defined before: read (the baseline of the errors above).
  Scene s = load_world(dir,
                       "Texture \"early\" \"spectrum\" \"constant\" \"rgb value\" [ 1 0 0 ]\n"
                       "Material \"diffuse\" \"texture reflectance\" \"early\"\n"
                       "Shape \"trianglemesh\" \"point3 P\" [ 0 0 0  1 0 0  0 1 0 ]\n");
  ASSERT_EQ(s.mesh.triangle_count(), 1u);
  EXPECT_EQ(s.materials[s.mesh.material[0]].albedo, Rgb(1, 0, 0));
  EXPECT_TRUE(s.warnings.empty());
}

TEST(PbrtErrors, UnsupportedTextureKindsAndClassesAreWarnedWithTheirLine) {
  TempDir dir;
  Scene s = load_world(
      dir,
      "Texture \"a\" \"normal\" \"scale\" \"float scale\" 2\n"
      "Texture \"b\" \"spectrum\" \"checkerboard\"\n"
      "Texture \"c\" \"spectrum\" \"mix\" \"texture tex1\" \"a\" \"texture tex2\" \"b\"\n");
  expect_mentions(warning_with(s, {"Texture of type"}),
                  {"s.pbrt:2:", "\"normal\"", "not supported"});
  expect_mentions(warning_with(s, {"Texture class"}),
                  {"s.pbrt:3:", "\"checkerboard\"", "not supported"});
  // ... and the mix that refers to both says so, on its own line (they were defined, and rll
  // skipped them: a warning, not the error of an undefined texture) ...
  expect_mentions(warning_with(s, {"\"a\" is not a texture"}), {"s.pbrt:4:", "tex1"});
  expect_mentions(warning_with(s, {"\"b\" is not a texture"}), {"s.pbrt:4:", "tex2"});
  // ... and the summary at the end counts them.
  expect_mentions(warning_with(s, {"summary"}),
                  {"s.pbrt: summary:", "2 textures skipped (checkerboard x1, normal x1)"});
  // A malformed operand is an error, naming the parameter's line.
  expect_mentions(error_in_world(dir,
                                 "Texture \"m\" \"spectrum\" \"mix\"\n"
                                 "  \"rgb tex1\" [ 1 0 ]\n"),
                  {"bad.pbrt:3:", "Texture \"m\"", "tex1", "3 values"});
  expect_mentions(error_in_world(dir, "Texture \"s\" \"float\" \"scale\" \"string scale\" \"x\"\n"),
                  {"bad.pbrt:2:", "Texture \"s\"", "scale", "type float"});
  expect_mentions(error_in_world(dir,
                                 "Texture \"s\" \"float\" \"scale\" \"texture tex\" "
                                 "[ \"a\" \"b\" ]\n"),
                  {"bad.pbrt:2:", "Texture \"s\"", "tex", "1 value"});
}

// --- spectra, camera, film, ColorSpace ---

TEST(PbrtErrors, UnknownNamedSpectrumIsAnErrorWithItsLine) {
  // As in pbrt-v4: a name that is neither a named spectrum nor a file is an error naming it, the
  // parameter and its line, and listing the names rll knows.
  TempDir dir;
  expect_mentions(
      error_in_world(dir, "Material \"conductor\"\n  \"spectrum eta\" \"metal-Xx-eta\"\n"),
      {"bad.pbrt:3:", "Material \"conductor\"", "\"spectrum eta\"", "spectrum \"metal-Xx-eta\"",
       "metal-{Cu,Au,Ag,Al,CuZn,MgO,TiO2}-{eta,k}", "glass-*"});
  expect_mentions(error_in_world(dir, "LightSource \"point\" \"spectrum I\" \"stdilum-D65\"\n"),
                  {"bad.pbrt:2:", "LightSource \"point\"", "spectrum \"stdilum-D65\""});
  expect_mentions(error_in_world(dir, "Material \"dielectric\" \"spectrum eta\" \"BK7\"\n"),
                  {"bad.pbrt:2:", "spectrum \"BK7\""});
  // The names rll knows load without a warning.
  Scene known = load_world(dir,
                           "Material \"conductor\" \"spectrum eta\" \"metal-Ag-eta\" "
                           "\"spectrum k\" \"metal-Ag-k\"\n"
                           "Material \"dielectric\" \"spectrum eta\" \"glass-F11\"\n"
                           "LightSource \"point\" \"spectrum I\" \"stdillum-D65\"\n");
  EXPECT_TRUE(known.warnings.empty()) << known.warnings.front();
  // A spectrum file (pbrt-v4 reads one; rll does not) keeps the default, with a warning.
  dir.write("eta.spd", "400 1.5 700 1.4\n");
  Scene s = load_world(dir, "Material \"conductor\"\n  \"spectrum eta\" \"eta.spd\"\n");
  expect_mentions(warning_with(s, {"eta.spd"}),
                  {"s.pbrt:3:", "spectrum file \"eta.spd\"", "'eta'", "default"});
  // Wavelength-value pairs that are not pairs are an error.
  expect_mentions(error_in_world(dir, "Material \"conductor\"\n  \"spectrum k\" [ 400 1 700 ]\n"),
                  {"bad.pbrt:3:", "spectrum k", "pairs"});
}

TEST(PbrtErrors, BadLensParameters) {
  TempDir dir;
  auto camera_error = [&](const std::string& params) {
    return error_of([&] {
      Scene s;
      load_pbrt(dir.write("bad.pbrt", "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" " +
                                          params + "\nWorldBegin\n"),
                s);
    });
  };
  expect_mentions(camera_error("\"float lensradius\" -0.1"),
                  {"bad.pbrt:2:", "lensradius must not be negative"});
  expect_mentions(camera_error("\"float lensradius\" 0.1 \"float focaldistance\" 0"),
                  {"bad.pbrt:2:", "focaldistance must be positive"});
  expect_mentions(camera_error("\"float lensradius\" [ 0.1 0.2 ]"),
                  {"bad.pbrt:2:", "lensradius", "1 value"});
  expect_mentions(camera_error("\"float screenwindow\" [ -1 1 1 ]"),
                  {"bad.pbrt:2:", "screenwindow", "multiple of 4"});
  expect_mentions(camera_error("\"float screenwindow\" [ -1 1 -1 1  -1 1 -1 1 ]"),
                  {"bad.pbrt:2:", "screenwindow needs 4 values"});
  expect_mentions(camera_error("\"float screenwindow\" [ 1 -1 -1 1 ]"),
                  {"bad.pbrt:2:", "screenwindow needs xmin < xmax"});
  expect_mentions(camera_error("\"float shutteropen\" 1 \"float shutterclose\" 0.5"),
                  {"bad.pbrt:2:", "shutterclose must be after shutteropen"});
}

TEST(PbrtErrors, BadFilmIso) {
  TempDir dir;
  for (const char* iso : {"0", "-100"})
    expect_mentions(error_of([&] {
                      Scene s;
                      load_pbrt(dir.write("bad.pbrt", std::string("Camera \"perspective\"\n"
                                                                  "Film \"rgb\" \"float iso\" ") +
                                                          iso + "\nWorldBegin\n"),
                                s);
                    }),
                    {"bad.pbrt:2:", "Film", "iso must be positive"});
}

TEST(PbrtErrors, ColorSpaceOtherThanSrgbAndBadOption) {
  TempDir dir;
  expect_mentions(error_of([&] {
                    Scene s;
                    load_pbrt(dir.write("bad.pbrt", "\nColorSpace \"rec2020\"\nWorldBegin\n"), s);
                  }),
                  {"bad.pbrt:2:", "ColorSpace \"rec2020\"", "srgb"});
  expect_mentions(error_of([&] {
                    Scene s;
                    load_pbrt(dir.write("bad.pbrt", "ColorSpace\nWorldBegin\n"), s);
                  }),
                  {"bad.pbrt:2:", "expected a quoted string"});
  expect_mentions(error_of([&] {
                    Scene s;
                    load_pbrt(dir.write("bad.pbrt", "\nOption \"bool wavefront\" \"maybe\"\n"), s);
                  }),
                  {"bad.pbrt:2:", "wavefront", "true or false"});
}

TEST(PbrtErrors, ImpossibleIndicesOfRefractionAreRefused) {
  // pbrt-v4 checks none of these: it reads eta 0 as 1 and a negative eta gives meaningless
  // Fresnel terms. An index of refraction is positive (an rgb eta is read by its green value).
  TempDir dir;
  const std::string tri = "Shape \"trianglemesh\" \"point3 P\" [ 0 0 0 1 0 0 0 1 0 ]\n";
  for (const char* type : {"dielectric", "thindielectric", "coateddiffuse"})
    for (const char* eta : {"-1.5", "0", "-2"})
      expect_mentions(
          error_in_world(dir, fmt::format("Material \"{}\" \"float eta\" {}\n{}", type, eta, tri)),
          {"bad.pbrt:2:", type, "\"eta\" must be a positive index of refraction", eta});
  expect_mentions(error_in_world(dir, "Material \"dielectric\" \"rgb eta\" [ 1 0 1 ]\n" + tri),
                  {"bad.pbrt:2:", "dielectric", "\"eta\" must be a positive index of refraction"});
  // Below 1, pbrt-v4 renders a relative index (the inside thinner); rll's glass cannot, and says
  // so.
  const Scene s = load_world(dir, "Material \"dielectric\" \"float eta\" 0.5\n" + tri);
  EXPECT_NE(warning_with(s, {"s.pbrt:2", "dielectric", "0.5", "below 1"}), "");
  ASSERT_FALSE(s.materials.empty());
  EXPECT_EQ(s.materials.back().ior, 1.0f);
}

TEST(PbrtErrors, SubdivisionAndInstancesAreCountedBeforeTheyAreBuilt) {
  // A level-6 tetrahedron (16384 triangles) instanced 1000 times is 16 M triangles: against a
  // 256 MiB budget (1.7 M triangles at 160 bytes each) the instance that crosses it is refused,
  // and no instance has been built by then.
  BudgetScope budget(size_t(256) << 20);
  std::string text =
      "WorldBegin\nObjectBegin \"ball\"\n" + tetra("\"integer levels\" 6") + "ObjectEnd\n";
  for (int i = 0; i < 1000; ++i) text += "ObjectInstance \"ball\"\n";
  Scene s;
  const auto t0 = std::chrono::steady_clock::now();
  const std::string e = error_of([&] { parse_pbrt(text, "many.pbrt", "", s, {}); });
  expect_mentions(e, {"many.pbrt:", "ObjectInstance of 16384 triangles", "instance 103 ",
                      "would have 1687552 triangles", "more than the 256.0 MiB a scene may use"});
  EXPECT_EQ(s.mesh.triangle_count(), 0u);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 5.0);
  // Subdivision is estimated before it is made: 10 levels of 4 triangles are 4 M triangles.
  Scene t;
  expect_mentions(error_of([&] {
                    parse_pbrt("WorldBegin\n" + tetra("\"integer levels\" 10"), "deep.pbrt", "", t,
                               {});
                  }),
                  {"deep.pbrt:2:", "loopsubdiv", "10 levels make 4194304 triangles of 4",
                   "need about 640.0 MiB", "256.0 MiB a scene may use"});
}
