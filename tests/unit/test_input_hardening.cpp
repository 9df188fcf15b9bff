// Scene input that is hostile or can only render black (issue 13): bytes from files are escaped in
// messages, referenced paths are named for what they are, the in-memory readers the fuzz targets
// use keep to their policy, and zero-power lights count as no lights. Sizes a file claims are
// checked against the file and the memory budget before anything is allocated (issue 30), with
// a small budget here so that no test allocates much.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "rll/accel/accel.h"
#include "rll/core/error.h"
#include "rll/core/memory_budget.h"
#include "rll/io/load.h"
#include "rll/io/text_scan.h"
#include "rll/scene/builder.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;
namespace fs = std::filesystem;

namespace {

TEST(Printable, KeepsPrintableTextAndEscapesEverythingElse) {
  EXPECT_EQ(printable("Shape \"sphere\" [ 1 ]"), "Shape \"sphere\" [ 1 ]");
  EXPECT_EQ(printable(std::string("a\x1b[2Jb\x07\n\t\x7f\0z", 12)),
            "a\\x1b[2Jb\\x07\\x0a\\x09\\x7f\\x00z");
  // UTF-8 is shown as it is (a name in any language reads so); bytes that are not UTF-8 and C1
  // controls are escaped.
  EXPECT_EQ(printable("caf\xc3\xa9"), "caf\xc3\xa9");
  EXPECT_EQ(printable("caf\xe9 \xc2\x9b"), "caf\\xe9 \\xc2\\x9b");
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

// A binary PLY header declaring `vertices` xyz float vertices and `faces` triangles (uchar count,
// int indices), without its data.
std::string ply_header(size_t vertices, size_t faces) {
  return "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(vertices) +
         "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
         std::to_string(faces) + "\nproperty list uchar int vertex_indices\nend_header\n";
}

TEST(SizeClaims, GzipInflatesNoFurtherThanThePlyHeaderDeclares) {
  // 3 vertices and 1 face take at most 36 + 1021 bytes after the header: 16 MB of zeros after
  // them stop the inflation there, not at the end of the stream.
  TempDir dir;
  const std::string header = ply_header(3, 1);
  const auto p = dir.write("bomb.ply.gz", gzip(header + std::string(size_t(16) << 20, '\0'), 9));
  const std::string e = error_of([&] { read_ply_file(p); });
  expect_mentions(e, {"bomb.ply.gz", "decompresses to more than", "header declares"});
  EXPECT_NE(e.find(std::to_string(header.size() + 3 * 12 + 1 + 255 * 4)), std::string::npos) << e;
  // The limit is what the header allows: a well-formed file of the same header reads.
  std::string ok = header;
  for (float v : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f})
    ok.append(reinterpret_cast<const char*>(&v), 4);
  ok += '\3';
  for (int32_t i : {0, 1, 2}) ok.append(reinterpret_cast<const char*>(&i), 4);
  EXPECT_EQ(read_ply_file(dir.write("ok.ply.gz", gzip(ok))).triangle_count(), 1u);
}

TEST(SizeClaims, GzipInflatesWithinTheMemoryBudget) {
  // A header that declares 100 M vertices allows 1.2 GB: its 4 KB of gzip data cannot hold that
  // (issue 42: refused by the header, before inflating; test_hardening3_load.cpp has the budget).
  BudgetScope budget(size_t(1) << 20);
  TempDir dir;
  const auto p = dir.write("big.ply.gz",
                           gzip(ply_header(100000000, 1) + std::string(size_t(4) << 20, '\0'), 9));
  expect_mentions(error_of([&] { read_ply_file(p); }),
                  {"big.ply.gz", "100000000 vertices", "inflate to at most"});
  expect_mentions(error_of([&] { gunzip(gzip(std::string(size_t(2) << 20, 'x')), "x.gz"); }),
                  {"x.gz", "a scene may use"});
}

TEST(SizeClaims, GltfAccessorCountsAreCheckedBeforeAllocating) {
  // 2^33 elements of a 36-byte view: refused by the view's size, where reading them first would
  // ask for 96 GB (std::bad_alloc, not a message).
  using json = nlohmann::json;
  TempDir dir;
  const float tri[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  dir.write("buf.bin", std::string(reinterpret_cast<const char*>(tri), sizeof tri));
  auto doc = [&](json accessor) {
    accessor["componentType"] = 5126;
    accessor["type"] = "VEC3";
    return json{{"asset", {{"version", "2.0"}}},
                {"buffers", {{{"byteLength", 36}, {"uri", "buf.bin"}}}},
                {"bufferViews", {{{"buffer", 0}, {"byteLength", 36}}}},
                {"accessors", {accessor}},
                {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}}}}}}},
                {"nodes", {{{"mesh", 0}}}},
                {"scenes", {{{"nodes", {0}}}}}}
        .dump();
  };
  Scene s;
  const auto big = dir.write("big.gltf", doc({{"bufferView", 0}, {"count", size_t(1) << 33}}));
  expect_mentions(error_of([&] { load_gltf(big, s); }),
                  {"big.gltf", "POSITION (accessor 0)", "8589934592 elements", "do not fit"});
  // An accessor without a view is all zeros: its count is held to the memory budget.
  BudgetScope budget(size_t(1) << 20);
  const auto zeros = dir.write("zeros.gltf", doc({{"count", 3 << 18}}));
  expect_mentions(error_of([&] { load_gltf(zeros, s); }),
                  {"zeros.gltf", "POSITION (accessor 0)", "count 786432", "9.0 MiB",
                   "more than the 1.0 MiB a scene may use"});
}

TEST(SizeClaims, EmbreeFailuresSayWhatWasBuilt) {
  // A 100x100 grid (19602 triangles) under a 1 MiB budget: Embree's allocations are held to the
  // budget, and its failure names the build, the geometry and the figures.
  Mesh mesh;
  const int n = 100;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) mesh.positions.push_back(Vec3(float(x), float(y), 0));
  for (int y = 0; y + 1 < n; ++y)
    for (int x = 0; x + 1 < n; ++x) {
      const uint32_t i = uint32_t(y * n + x);
      mesh.triangles.push_back({i, i + 1, i + uint32_t(n)});
      mesh.triangles.push_back({i + 1, i + uint32_t(n) + 1, i + uint32_t(n)});
    }
  {
    BudgetScope budget(size_t(1) << 20);
    expect_mentions(
        error_of([&] { Accel accel(mesh); }),
        {"Embree failed", "acceleration structure over 19602 triangles and 10000 vertices",
         "out of memory", "asked for more than the 1.0 MiB a scene may use"});
  }
  Accel accel(mesh);  // the default budget holds it
  Hit hit;
  EXPECT_TRUE(accel.intersect(Ray{Vec3(10.5f, 10.2f, 1), Vec3(0, 0, -1)}, hit));
}

}  // namespace
