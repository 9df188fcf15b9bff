// Hardening III, the samplers' part, through the program: a pbrt image area light whose uvs tile
// its image a thousand times loads in seconds (it hung in the exact integration of its split), and
// the oracle's in-range settings that plan hours of shadow rays are refused with the keys named
// (they ran for minutes with no word).
#include <gtest/gtest.h>

#include "rll/core/image.h"
#include "rll/core/rng.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;

namespace {

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

}  // namespace

TEST(Hardening3SamplersCli, PbrtImageAreaLightTiledAThousandTimesLoadsInSeconds) {
  TempDir dir;
  Image tile(256, 256);
  Pcg32 rng(3);
  for (size_t i = 0; i < tile.pixel_count(); ++i)
    tile[i] = Rgb(rng.next_float(), rng.next_float(), rng.next_float());
  write_image(dir / "tile.exr", tile);
  const auto scene = dir.write(
      "tiled.pbrt",
      "LookAt 0 0 5  0 0 0  0 1 0\n"
      "Camera \"perspective\" \"float fov\" 45\n"
      "WorldBegin\n"
      "AttributeBegin\n"
      "AreaLightSource \"diffuse\" \"string filename\" \"tile.exr\"\n"
      "Shape \"trianglemesh\" \"point3 P\" [ -1 -1 0  1 -1 0  1 1 0  -1 1 0 ] \"point2 uv\" "
      "[ 0 0  1000 0  1000 1000  0 1000 ] \"integer indices\" [ 0 1 2  0 2 3 ]\n"
      "AttributeEnd\n"
      "Shape \"trianglemesh\" \"point3 P\" [ -3 -3 -1  3 -3 -1  3 3 -1  -3 3 -1 ] "
      "\"integer indices\" [ 0 1 2  0 2 3 ]\n");
  double wall = 0;
  const CommandResult r =
      run_rll({"render", scene.string(), "--res", "16x16", "--spp", "1", "--sampler", "power",
               "--quiet", "-o", (dir / "out.exr").string()},
              300, &wall);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_LT(wall, 120.0);  // about 5 s of work (hours before), on a loaded machine
  EXPECT_TRUE(contains(r.output, "64 x 64 points")) << r.output;
  EXPECT_GT(image_mean(read_image(dir / "out.exr")), 0);
}

TEST(Hardening3SamplersCli, OracleSettingsPlanningHoursAreRefusedNamingTheKeys) {
  TempDir dir;
  double wall = 0;
  const CommandResult r =
      run_rll({"render", "builtin:cornell-boxes-room", "--res", "32x32", "--spp", "1", "--sampler",
               "oracle", "--set", "oracle.points=4096", "--set", "oracle.rays=4096", "--quiet",
               "-o", (dir / "out.exr").string()},
              300, &wall);
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_LT(wall, 120.0);  // refused after discovery (hours of shadow rays before)
  for (const char* part :
       {"shadow rays", "oracle.points=4096", "oracle.rays=4096", "lower oracle.points"})
    EXPECT_TRUE(contains(r.output, part)) << part << " not in: " << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "out.exr"));
}

// The probe's case through the program: an area light of L 3e38 (a power of 4.7e38 per triangle,
// beyond a float) beside an ordinary lamp, facing a wall. Its sums turned to inf and every pmf to
// NaN: power, tree and ltc rendered the wall black, rht, rll and the oracle dimmed. Now each gives
// the wall about what uniform (which never weighs power) gives, and the light is named.
TEST(Hardening3SamplersCli, HugePowerAreaLightGivesALitImageUnderEverySampler) {
  TempDir dir;
  const auto scene = dir.write(
      "huge.pbrt",
      "LookAt 0 0 5  0 0 0  0 1 0\n"
      "Camera \"perspective\" \"float fov\" 45\n"
      "WorldBegin\n"
      "Shape \"trianglemesh\" \"point3 P\" [ -2 -1 0  2 -1 0  2 1 0  -2 1 0 ] "
      "\"integer indices\" [ 0 1 2  0 2 3 ]\n"
      "AttributeBegin\n"
      "AreaLightSource \"diffuse\" \"rgb L\" [ 40 40 40 ]\n"
      "Shape \"trianglemesh\" \"point3 P\" [ -1.5 -0.25 1  -1 -0.25 1  -1 0.25 1  -1.5 0.25 1 ] "
      "\"integer indices\" [ 0 2 1  0 3 2 ]\n"
      "AttributeEnd\n"
      "AttributeBegin\n"
      "AreaLightSource \"diffuse\" \"rgb L\" [ 3e38 3e38 3e38 ]\n"
      "Shape \"trianglemesh\" \"point3 P\" [ 0.5 -0.5 0.5  1.5 -0.5 0.5  1.5 0.5 0.5  0.5 0.5 0.5 "
      "] "
      "\"integer indices\" [ 0 2 1  0 3 2 ]\n"
      "AttributeEnd\n");
  double uniform = 0;
  for (const char* sampler :
       {"uniform", "power", "tree", "fermat", "ltc", "rht", "rll", "oracle"}) {
    SCOPED_TRACE(sampler);
    const auto out = dir / (std::string(sampler) + ".exr");
    const CommandResult r = run_rll({"render", scene.string(), "--res", "32x24", "--spp", "8",
                                     "--sampler", sampler, "--quiet", "-o", out.string()},
                                    300);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_TRUE(contains(r.output, "more power than a float holds")) << r.output;
    const Image img = read_image(out);
    double left = 0;  // the wall's left half: lit by both lights, by the huge one far more
    for (int y = 0; y < img.height(); ++y)
      for (int x = 0; x < img.width() / 2; ++x) left += img.at(x, y).y;
    left /= double(img.height() * (img.width() / 2));
    if (std::string(sampler) == "uniform") uniform = left;
    EXPECT_GT(uniform, 1e34);
    EXPECT_GT(left, 0.5 * uniform);
    EXPECT_LT(left, 2 * uniform);
  }
}
