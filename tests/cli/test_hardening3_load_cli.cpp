// The `rll` program on the scene and image inputs of issue 42: each is refused with a message
// naming the file and what is wrong, a clean exit code and no image written.
#include <gtest/gtest.h>

#include <filesystem>

#include "rll/core/image.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;
namespace fs = std::filesystem;

namespace {

// `rll render <scene> -o <dir>/out.exr`: a clean failure naming `mentions`, no image written.
void expect_refused(const TempDir& dir, const fs::path& scene,
                    std::initializer_list<std::string> mentions) {
  render_refused(dir, scene, mentions, "out.exr");
}

const char* kHead =
    "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"\n"
    "Film \"rgb\" \"integer xresolution\" [ 8 ] \"integer yresolution\" [ 8 ]\nWorldBegin\n";
const char* kQuad = "Shape \"bilinearmesh\" \"point3 P\" [ -1 -1 0 1 -1 0 -1 1 0 1 1 0 ]\n";

}  // namespace

TEST(Hardening3LoadCli, AnEnvironmentMapWithANegativeTexelIsRefused) {
  TempDir dir;
  Image map(4, 4, Rgb(1));
  map.at(2, 3) = Rgb(0.5f, -0.25f, 1);
  write_image(dir / "env.exr", map);
  const auto scene = dir.write(
      "env.pbrt",
      std::string(kHead) + "LightSource \"infinite\" \"string filename\" \"env.exr\"\n" + kQuad);
  expect_refused(dir, scene,
                 {"env.pbrt:5", "LightSource \"infinite\"", "texel (2, 3) is (0.5, -0.25, 1)"});
}

TEST(Hardening3LoadCli, ATextureWhoseHeaderClaimsMoreThanItsDataIsRefused) {
  // A PNG of a few hundred bytes claiming 16384 x 16384 pixels, as an area light's image.
  TempDir dir;
  Image small(2, 2, Rgb(1));
  write_image(dir / "small.png", small);
  std::string png = read_text(dir / "small.png");
  ASSERT_GT(png.size(), 24u);
  // IHDR's width and height (bytes 16 to 23) raised to 16384; stb_image reads no CRC.
  for (int i : {16, 20}) png.replace(size_t(i), 4, std::string("\x00\x00\x40\x00", 4));
  dir.write("lamp.png", png);
  const auto scene = dir.write(
      "lamp.pbrt", std::string(kHead) +
                       "AreaLightSource \"diffuse\" \"string filename\" \"lamp.png\"\n" + kQuad);
  expect_refused(dir, scene, {"lamp.pbrt:5", "lamp.png", "16384x16384", "IDAT"});
}
