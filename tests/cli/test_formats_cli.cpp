// The `rll` program on glTF, PLY and pbrt files and `rll convert`: malformed files give a
// message naming the file (and line or byte) and a non-zero exit, never a crash; warnings go to
// stderr; a converted scene renders.
#include <gtest/gtest.h>

#include <filesystem>

#include "rll/io/save.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;
namespace fs = std::filesystem;

namespace {

void expect_render_failure(const TempDir& dir, const fs::path& scene,
                           std::initializer_list<std::string> mentions) {
  expect_clean_failure({"render", scene.string(), "--quiet", "-o", (dir / "out.png").string()},
                       mentions);
  EXPECT_FALSE(fs::exists(dir / "out.png"));
}

const char* kPbrtHead =
    "LookAt 0 0 5 0 0 0 0 1 0\nCamera \"perspective\"\nFilm \"rgb\" \"integer xresolution\" 8 "
    "\"integer yresolution\" 8\nWorldBegin\n";

}  // namespace

TEST(FormatsCli, MalformedPlyGltfAndPbrtFiles) {
  TempDir dir;
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.triangles = {{0, 1, 2}};
  const std::string ply = ply_bytes(m, PlyEncoding::BinaryBigEndian);
  expect_render_failure(dir, dir.write("cut.ply", ply.substr(0, ply.size() - 5)),
                        {"cut.ply: byte", "truncated"});
  expect_render_failure(dir, dir.write("words.ply", "ply\nformat ascii 1.0\nelement vertex x\n"),
                        {"words.ply:3:", "'x'"});
  expect_render_failure(dir, dir.write("dark.ply", ply), {"dark.ply", "no lights"});
  expect_render_failure(dir, dir.write("bad.gltf", "{\"asset\": {\"version\": \"2.0\"}"),
                        {"bad.gltf"});
  expect_render_failure(dir, dir.write("bad.glb", "glTF\x02\x00\x00\x00"), {"bad.glb"});
  expect_render_failure(dir,
                        dir.write("syntax.pbrt", std::string(kPbrtHead) + "Shape \"sphere\" 1 2\n"),
                        {"syntax.pbrt:5:", "expected a directive"});
  dir.write("a.pbrt", "Include \"b.pbrt\"\n");
  dir.write("b.pbrt", "Include \"a.pbrt\"\n");
  expect_render_failure(dir, dir.write("loop.pbrt", "Include \"a.pbrt\"\n"),
                        {"b.pbrt:1:", "recursive"});
  expect_render_failure(
      dir,
      dir.write("gone.pbrt",
                std::string(kPbrtHead) + "Shape \"plymesh\" \"string filename\" \"gone.ply\"\n"),
      {"gone.pbrt:5:", "'gone.ply' not found"});
  expect_render_failure(dir, dir.write("scene.fbx", "x"), {"scene.fbx", "unknown scene format"});
}

TEST(FormatsCli, UnsupportedPbrtDirectivesWarnAndTheSceneStillRenders) {
  TempDir dir;
  auto p = dir.write("warn.pbrt", std::string("Integrator \"volpath\"\n") + kPbrtHead +
                                      "LightSource \"point\" \"point3 from\" [0 0 2]\n"
                                      "Shape \"sphere\" \"float radius\" 0.5\n");
  CommandResult r =
      run_rll({"render", p.string(), "--spp", "1", "--quiet", "-o", (dir / "o.png").string()});
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("rll: warning: " + p.string() + ":1: Integrator is not supported"),
            std::string::npos)
      << r.output;
  EXPECT_TRUE(fs::exists(dir / "o.png"));
}

TEST(FormatsCli, ConvertWritesEachFormatAndTheResultRenders) {
  TempDir dir;
  for (const char* out : {"box.json", "box.gltf", "box.pbrt"}) {
    SCOPED_TRACE(out);
    CommandResult c = run_rll({"convert", "builtin:cornell-box", (dir / out).string()});
    EXPECT_EQ(c.exit_code, 0) << c.output;
    CommandResult r = run_rll({"render", (dir / out).string(), "--res", "8x8", "--spp", "1",
                               "--quiet", "-o", (dir / "o.png").string()});
    EXPECT_EQ(r.exit_code, 0) << r.output;
  }
  EXPECT_TRUE(fs::exists(dir / "box.obj"));
  EXPECT_TRUE(fs::exists(dir / "box_mesh0.ply"));
  // Back again: the pbrt copy converts to JSON + OBJ.
  CommandResult back =
      run_rll({"convert", (dir / "box.pbrt").string(), (dir / "again.json").string()});
  EXPECT_EQ(back.exit_code, 0) << back.output;
  EXPECT_TRUE(fs::exists(dir / "again.obj"));
  // A mesh without lights converts (only rendering needs a light).
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.triangles = {{0, 1, 2}};
  auto ply = dir.write("tri.ply", ply_bytes(m, PlyEncoding::Ascii));
  CommandResult mesh = run_rll({"convert", ply.string(), (dir / "tri.json").string()});
  EXPECT_EQ(mesh.exit_code, 0) << mesh.output;
}

TEST(FormatsCli, ConvertErrors) {
  TempDir dir;
  expect_clean_failure({"convert", (dir / "none.pbrt").string(), (dir / "x.json").string()},
                       {"none.pbrt", "not found"});
  expect_clean_failure({"convert", "builtin:cornell-box", (dir / "x.fbx").string()},
                       {"x.fbx", ".json"});
  expect_clean_failure({"convert", "builtin:cornell-box", (dir / "no/such/x.json").string()},
                       {"does not exist"});
  expect_clean_failure({"convert", "builtin:cornell-box"}, {"output"});
  EXPECT_FALSE(fs::exists(dir / "x.json"));
}
