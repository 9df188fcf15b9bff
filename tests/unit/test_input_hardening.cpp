// Scene input that is hostile or can only render black (issue 13): bytes from files are escaped in
// messages, referenced paths are named for what they are, the in-memory readers the fuzz targets
// use keep to their policy, and zero-power lights count as no lights.
#include <gtest/gtest.h>

#include "rll/core/error.h"
#include "rll/scene/builder.h"
#include "rll/io/load.h"
#include "rll/io/text_scan.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;
namespace fs = std::filesystem;

namespace {

TEST(Printable, KeepsPrintableAsciiAndEscapesEverythingElse) {
  EXPECT_EQ(printable("Shape \"sphere\" [ 1 ]"), "Shape \"sphere\" [ 1 ]");
  EXPECT_EQ(printable(std::string("a\x1b[2Jb\x07\n\t\x7f\0z", 12)),
            "a\\x1b[2Jb\\x07\\x0a\\x09\\x7f\\x00z");
  EXPECT_EQ(printable("caf\xc3\xa9"), "caf\\xc3\\xa9");  // non-ASCII bytes too
  // A backslash is doubled, so that "\x1b" in a file cannot pass for an escaped byte.
  EXPECT_EQ(printable("\\x1b"), "\\\\x1b");
}

TEST(Printable, CutsLongInputAndMarksTheCut) {
  const std::string long_line(1000, 'z');
  EXPECT_EQ(printable(long_line), std::string(48, 'z') + "...");
  EXPECT_EQ(printable(long_line, 5), "zzzzz...");
  EXPECT_EQ(printable(std::string(48, 'y')), std::string(48, 'y'));  // exactly at the cap: no cut
  // The cap counts input bytes: escapes lengthen the output, never the amount shown.
  EXPECT_EQ(printable(std::string(10, '\x01'), 2), "\\x01\\x01...");
}

TEST(Printable, WholeMessagesLoseOnlyTheirControlBytes) {
  EXPECT_EQ(without_control_bytes("caf\xc3\xa9.pbrt:3: '\\x1b' \x1b[0m"),
            "caf\xc3\xa9.pbrt:3: '\\x1b' \\x1b[0m");
}

TEST(UnreadableReason, NamesFoldersDevicesAndMissingFiles) {
  TempDir dir;
  fs::create_directory(dir / "folder.png");
  dir.write("file.png", "x");
  EXPECT_EQ(unreadable_reason(dir / "file.png"), "");
  EXPECT_EQ(unreadable_reason(dir / "folder.png"), "is a folder, not a file");
  EXPECT_EQ(unreadable_reason(dir / "missing.png"), "not found");
  EXPECT_EQ(unreadable_reason("/dev/zero"), "is not a regular file");
}

ReadPolicy no_files() {
  ReadPolicy p;
  p.read_files = false;
  return p;
}

TEST(InMemoryReaders, ObjReadsItsMtlFromMemoryAndNoFileFromDisk) {
  ReadPolicy policy = no_files();
  policy.memory_files["m.mtl"] = "newmtl lamp\nKd 0\nKe 2 3 4\n";
  Scene scene;
  parse_obj("mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl lamp\nf 1 2 3\n", "mem.obj", "",
            scene, policy);
  ASSERT_EQ(scene.mesh.triangle_count(), 1u);
  ASSERT_EQ(scene.materials.size(), 1u);
  EXPECT_EQ(scene.materials[0].emission, Rgb(2, 3, 4));
  Scene other;
  expect_mentions(error_of([&] {
                    parse_obj("mtllib other.mtl\nv 0 0 0\n", "mem.obj", "", other, policy);
                  }),
                  {"mem.obj:1:", "other.mtl", "reading other files is turned off"});
  policy.memory_files["m.mtl"] += "map_Kd wood.png\n";
  Scene textured;
  expect_mentions(error_of([&] {
                    parse_obj("mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "mem.obj",
                              "", textured, policy);
                  }),
                  {"wood.png", "reading other files is turned off"});
}

TEST(InMemoryReaders, JsonReadsNoFileWhenFilesAreTurnedOff) {
  Scene scene;
  parse_json_scene(R"({"shapes": [{"type": "quad", "origin": [0, 0, 0], "edge1": [1, 0, 0],
    "edge2": [0, 1, 0]}]})",
                   "mem.json", "", scene, no_files());
  EXPECT_EQ(scene.mesh.triangle_count(), 2u);
  Scene other;
  expect_mentions(error_of([&] {
                    parse_json_scene(R"({"shapes": [{"file": "/etc/passwd.obj"}]})", "mem.json",
                                     "", other, no_files());
                  }),
                  {"/shapes/0/file", "reading other files is turned off"});
}

// A scene of one lit quad and the given extra lights, in code.
Scene quad_scene(const std::vector<Light>& lights, Rgb emission = Rgb(0)) {
  Scene s;
  s.source = "test";
  SceneBuilder b(s);
  const uint32_t m = emission == Rgb(0) ? b.diffuse(Rgb(0.5f)) : b.emitter(emission);
  b.quad(Vec3(0), Vec3(1, 0, 0), Vec3(0, 1, 0), m);
  s.lights = lights;
  s.width = s.height = 4;
  return s;
}

TEST(SceneChecks, ZeroPowerLightsAreRefusedLikeNoLights) {
  for (const Light& dark : {make_point_light(Vec3(0, 0, 1), Rgb(0)),
                            make_directional_light(Vec3(0, 0, 1), Rgb(0))}) {
    Scene s = quad_scene({dark, dark});
    expect_mentions(error_of([&] { s.finalize(); }),
                    {"test", "no lights", "2 light sources emit nothing"});
  }
  // The same scene with a zero emission on the quad fails the same way, before it.
  Scene emissive = quad_scene({}, Rgb(0));
  expect_mentions(error_of([&] { emissive.finalize(); }), {"test", "no lights"});
  // One light that emits is enough, whatever the others are.
  Scene mixed = quad_scene({make_point_light(Vec3(0, 0, 1), Rgb(0)),
                            make_point_light(Vec3(0, 0, 1), Rgb(0, 0, 1e-3f))});
  EXPECT_NO_THROW(mixed.finalize());
  Scene lit_quad = quad_scene({make_point_light(Vec3(0, 0, 1), Rgb(0))}, Rgb(1));
  EXPECT_NO_THROW(lit_quad.finalize());
}

TEST(SceneChecks, GeometryOfZeroAreaIsRefused) {
  Scene s;
  s.source = "test";
  SceneBuilder b(s);
  b.quad(Vec3(0), Vec3(1, 0, 0), Vec3(2, 0, 0), b.diffuse(Rgb(0.5f)));  // a line
  s.lights = {make_point_light(Vec3(0, 0, 1), Rgb(1))};
  s.width = s.height = 4;
  expect_mentions(error_of([&] { s.finalize(); }),
                  {"test", "all 2 triangles have zero area", "scaled to nothing"});
}

TEST(SceneChecks, LightsWithoutGeometryOrSkyAreWarnedAbout) {
  Scene s;
  s.source = "test";
  s.lights = {make_point_light(Vec3(0, 0, 1), Rgb(1))};
  s.width = s.height = 4;
  s.finalize();
  s.finalize();  // idempotent: one warning
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_NE(s.warnings[0].find("no geometry and no sky"), std::string::npos) << s.warnings[0];
}

}  // namespace
