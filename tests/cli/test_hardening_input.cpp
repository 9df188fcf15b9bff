// The `rll` program on hostile or degenerate scene input (issue 13): a file the scene includes is
// not replayed into the terminal, bytes from files are escaped in messages, a folder, an empty
// GLB or a glTF buffer of the wrong size is named for what it is, an image header's size claim
// is checked before memory is taken for it, and a scene that can only render black is refused.
#include <ImfChannelList.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <gtest/gtest.h>

#include <filesystem>

#include "support/test_support.h"

using namespace rll::test;
namespace fs = std::filesystem;

namespace {

const char* kPbrtHead =
    "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"\n"
    "Film \"rgb\" \"integer xresolution\" [ 8 ] \"integer yresolution\" [ 8 ]\nWorldBegin\n";
const char* kPbrtLitQuad =
    "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [ 1 1 1 ]\n"
    "Shape \"bilinearmesh\" \"point3 P\" [ -1 -1 0 1 -1 0 -1 1 0 1 1 0 ] "
    "\"integer indices\" [ 0 1 2 3 ]\nAttributeEnd\n";

bool has_control_bytes(const std::string& s) {
  for (char c : s)
    if ((static_cast<unsigned char>(c) < 0x20 && c != '\n') || c == 0x7f) return true;
  return false;
}

}  // namespace

TEST(HardeningInput, AnIncludedFileThatIsNotPbrtIsNotEchoed) {
  TempDir dir;
  // Like Include "/etc/passwd": the first line of the included file must stay out of the output.
  dir.write("secret.txt", "root-SECRET-LINE:x:0:0:\x1b[31mred\nsecond line\n");
  auto scene = dir.write("scene.pbrt", std::string(kPbrtHead) + "\nInclude \"secret.txt\"\n");
  const std::string out =
      render_refused(dir, scene, {"scene.pbrt:6: Include: ", "secret.txt:1", "not a pbrt file"});
  EXPECT_EQ(out.find("SECRET"), std::string::npos) << out;
  EXPECT_FALSE(has_control_bytes(out)) << out;
}

TEST(HardeningInput, ErrorsInsideAnIncludedFileNameTheIncludingLine) {
  TempDir dir;
  dir.write("part.pbrt", "Translate 0 0 0\nScale 1 2 bogus\n");
  auto scene = dir.write("scene.pbrt", std::string(kPbrtHead) + "Include \"part.pbrt\"\n");
  render_refused(dir, scene, {"scene.pbrt:5: Include: ", "part.pbrt:2:", "'bogus'"});
}

TEST(HardeningInput, ControlBytesFromSceneFilesAreEscaped) {
  TempDir dir;
  // An escape sequence (clear screen; pbrt's tokens end at the '[') and a bell in a token, in
  // pbrt, OBJ and PLY headers.
  auto pbrt = dir.write("bad.pbrt", std::string(kPbrtHead) + "Translate 0 0 1\x1b\x07[2J\n");
  std::string out = render_refused(dir, pbrt, {"bad.pbrt:5:", "'1\\x1b\\x07'"});
  EXPECT_FALSE(has_control_bytes(out)) << out;
  auto obj = dir.write("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 \x1b]0;title\x07\nf 1 2 3\n");
  out = render_refused(dir, obj, {"bad.obj:3:", "\\x1b]0;title\\x07"});
  EXPECT_FALSE(has_control_bytes(out)) << out;
  auto ply = dir.write("bad.ply", "ply\nformat ascii 1.0\nelement vertex 3\x1b[5m\nend_header\n");
  out = render_refused(dir, ply, {"bad.ply:3:", "\\x1b[5m"});
  EXPECT_FALSE(has_control_bytes(out)) << out;
  // Warnings quote file content too.
  auto warned = dir.write("warned.pbrt",
                          std::string("Camera \"odd\x1b[2J\x07\"\nWorldBegin\n") + kPbrtLitQuad);
  auto r = run_rll({"render", warned.string(), "-o", (dir / "w.png").string(), "--spp", "1"});
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("warning: " + warned.string() + ":1: Camera \"odd\\x1b[2J\\x07\""),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(has_control_bytes(r.output)) << r.output;
  // A long token is cut, not replayed whole.
  auto longer = dir.write(
      "long.pbrt", std::string(kPbrtHead) + "Translate 0 0 " + std::string(5000, '7') + "x\n");
  out = render_refused(dir, longer, {"long.pbrt:5:", "..."});
  EXPECT_LT(out.size(), 1000u) << out;
}

TEST(HardeningInput, AFolderGivenAsATextureIsNamedAsAFolder) {
  TempDir dir;
  fs::create_directory(dir / "wood.png");
  auto json = dir.write("scene.json",
                        R"({"materials": {"m": {"albedo": [1, 1, 1], "texture": "wood.png"}},
  "shapes": [{"type": "quad", "origin": [0, 0, 0], "edge1": [1, 0, 0], "edge2": [0, 1, 0],
              "material": "m"}],
  "lights": [{"type": "point", "position": [0, 0, 1], "intensity": [1, 1, 1]}]})");
  render_refused(dir, json, {"scene.json", "/materials/m", "'wood.png' is a folder, not a file"});
  auto pbrt = dir.write("scene.pbrt", std::string(kPbrtHead) +
                                          "Texture \"t\" \"spectrum\" \"imagemap\" "
                                          "\"string filename\" \"wood.png\"\n" +
                                          kPbrtLitQuad);
  render_refused(dir, pbrt, {"scene.pbrt:5:", "'wood.png' is a folder, not a file"});
  dir.write("a.mtl", "newmtl m\nKd 1 1 1\nmap_Kd wood.png\n");
  auto obj = dir.write("a.obj", "mtllib a.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m\nf 1 2 3\n");
  render_refused(dir, obj, {"a.mtl", "'wood.png' is a folder, not a file"});
}

TEST(HardeningInput, EmptyAndTruncatedGlbSayWhatTheyAre) {
  TempDir dir;
  render_refused(dir, dir.write("empty.glb", ""), {"empty.glb", "empty file"});
  render_refused(dir, dir.write("short.glb", std::string("glTF\x02\0\0\0", 8)),
                 {"short.glb", "not a GLB", "12-byte header"});
  render_refused(dir, dir.write("text.glb", "{\"asset\": {\"version\": \"2.0\"}}"),
                 {"text.glb", "not a GLB", "'glTF'"});
  render_refused(dir, dir.write("empty.gltf", ""), {"empty.gltf", "empty file"});
}

TEST(HardeningInput, GltfBufferOfTheWrongSizeGivesSizesNotTheWholeUri) {
  TempDir dir;
  // 4000 base64 characters decode to 3000 bytes; the buffer claims 12.
  const std::string payload(4000, 'A');
  auto gltf = dir.write(
      "scene.gltf",
      R"({"asset": {"version": "2.0"}, "buffers": [{"byteLength": 12, "uri": "data:application/octet-stream;base64,)" +
          payload + R"("}]})");
  const std::string out =
      render_refused(dir, gltf,
                     {"scene.gltf", "buffer 0 (byteLength 12)", "4037 characters",
                      "decodes to 3000 bytes", "data:application/octet-stream;base"});
  EXPECT_LT(out.size(), 600u) << out;
}

TEST(HardeningInput, ExrSkyClaimingAHugeSizeIsRefusedBeforeAllocating) {
  TempDir dir;
  {
    Imf::Header header(100000, 100000);
    header.compression() = Imf::ZIP_COMPRESSION;
    for (const char* c : {"R", "G", "B"}) header.channels().insert(c, Imf::Channel(Imf::HALF));
    Imf::OutputFile file((dir / "sky.exr").c_str(), header);  // no pixels written
  }
  auto json = dir.write("scene.json",
                        R"({"shapes": [{"type": "quad", "origin": [0, 0, 0], "edge1": [1, 0, 0],
  "edge2": [0, 1, 0]}], "sky": {"type": "dome", "image": "sky.exr"}})");
  const std::string out =
      render_refused(dir, json, {"/sky/image", "sky.exr", "100000x100000 pixels", "at most"});
  EXPECT_EQ(out.find("bad_alloc"), std::string::npos) << out;
}

TEST(HardeningInput, ZeroPowerLightsCountAsNoLights) {
  TempDir dir;
  const std::string quad = R"({"type": "quad", "origin": [0, 0, 0], "edge1": [1, 0, 0],
  "edge2": [0, 1, 0]})";
  // A zero emission is refused as "no lights"; a zero-intensity point light, a zero-irradiance
  // directional light and a zero-L pbrt area light must be too.
  render_refused(dir,
                 dir.write("emission.json", R"({"shapes": [{"type": "quad", "origin": [0, 0, 0],
  "edge1": [1, 0, 0], "edge2": [0, 1, 0], "material": {"emission": [0, 0, 0]}}]})"),
                 {"emission.json", "no lights"});
  render_refused(dir, dir.write("point.json", R"({"shapes": [)" + quad + R"(], "lights": [
  {"type": "point", "position": [0, 0, 1], "intensity": [0, 0, 0]},
  {"type": "directional", "direction": [0, 0, 1], "irradiance": [0, 0, 0]}]})"),
                 {"point.json", "no lights", "2 light sources emit nothing"});
  render_refused(
      dir,
      dir.write("point.pbrt", std::string(kPbrtHead) + "LightSource \"point\" \"rgb I\" [ 0 0 0 ]\n"
                                                       "Shape \"sphere\"\n"),
      {"point.pbrt", "no lights", "1 light source emits nothing"});
  // With one light that emits, the zero ones are harmless.
  auto ok = run_rll({"render",
                     dir.write("mixed.json", R"({"shapes": [)" + quad + R"(],
  "lights": [{"type": "point", "position": [0, 0, 1], "intensity": [0, 0, 0]},
             {"type": "point", "position": [0, 0, 1], "intensity": [1, 1, 1]}]})")
                         .string(),
                     "-o", (dir / "mixed.png").string(), "--quiet", "--spp", "1", "--res", "8x8"});
  EXPECT_EQ(ok.exit_code, 0) << ok.output;
}

TEST(HardeningInput, GeometryScaledToNothingIsRefused) {
  TempDir dir;
  // (pbrt and JSON transforms that flatten a shape are refused as singular where they are given.)
  // Every face of the mesh is a line.
  auto obj = dir.write("line.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\nf 3 2 1\n");
  render_refused(dir, obj, {"line.obj", "all 2 triangles have zero area", "scaled to nothing"});
  auto json = dir.write("scene.json", R"({"shapes": [{"file": "line.obj"}],
  "lights": [{"type": "point", "position": [0, 0, 1], "intensity": [1, 1, 1]}]})");
  render_refused(dir, json, {"scene.json", "all 2 triangles have zero area"});
}
