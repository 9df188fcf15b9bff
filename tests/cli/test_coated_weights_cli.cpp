// `rll render --set coated.weights=pbrt` (issue 42): a bad value is refused before anything is
// rendered or written, naming the key and its choices, given as --set or in a sampler spec; the
// option changes the render, and a spec carrying it renders what --set renders.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>

#include "rll/core/image.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;
namespace fs = std::filesystem;

namespace {

// A rough coateddiffuse floor lit by a small sphere: next-event estimation carries nearly all of
// its light, where pbrt-v4's weight shows most (as on killeroo-simple).
const char* kCoatScene = R"(LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" 40
Film "rgb" "integer xresolution" 16 "integer yresolution" 16
WorldBegin
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [40 40 40]
  Translate 1.5 1.5 2
  Shape "sphere" "float radius" 0.25
AttributeEnd
Material "coateddiffuse" "rgb reflectance" [0.5 0.5 0.5] "float roughness" 0.15
Shape "trianglemesh" "integer indices" [0 1 2 2 3 0] "point3 P" [-3 -3 0 3 -3 0 3 3 0 -3 3 0]
)";

CommandResult render_coat(const TempDir& dir, const fs::path& out, std::vector<std::string> extra) {
  const fs::path scene = dir.write("coat.pbrt", kCoatScene);
  std::vector<std::string> args = {"render",  scene.string(), "--spp",     "16",
                                   "--quiet", "-o",           out.string()};
  args.insert(args.end(), extra.begin(), extra.end());
  return run_rll(args);
}

bool same_pixels(const Image& a, const Image& b) {
  return a.pixel_count() == b.pixel_count() &&
         std::memcmp(a.pixels().data(), b.pixels().data(), a.pixel_count() * sizeof(Rgb)) == 0;
}

}  // namespace

TEST(CoatedWeightsCli, BadValueIsRefusedNamingTheKeyAndItsChoices) {
  TempDir dir;
  const fs::path out = dir / "x.exr";
  for (const std::vector<std::string>& extra :
       {std::vector<std::string>{"--set", "coated.weights=pbrt-v4"},
        std::vector<std::string>{"--set", "coated.weights=Unbiased"},
        std::vector<std::string>{"--sampler", "power:coated.weights=mis"}}) {
    const CommandResult r = render_coat(dir, out, extra);
    SCOPED_TRACE(extra.back() + "\n" + r.output);
    EXPECT_GE(r.exit_code, 1);
    EXPECT_LT(r.exit_code, 128);
    expect_mentions(r.output, {"coated.weights", "unbiased", "pbrt"});
    EXPECT_FALSE(fs::exists(out));
  }
}

TEST(CoatedWeightsCli, PbrtWeightsBrightenTheRoughCoatAndASpecCarriesThem) {
  TempDir dir;
  const fs::path plain = dir / "plain.exr", set = dir / "set.exr", spec = dir / "spec.exr";
  ASSERT_EQ(render_coat(dir, plain, {"--sampler", "power"}).exit_code, 0);
  ASSERT_EQ(render_coat(dir, set, {"--sampler", "power", "--set", "coated.weights=pbrt"}).exit_code,
            0);
  ASSERT_EQ(render_coat(dir, spec, {"--sampler", "power:coated.weights=pbrt"}).exit_code, 0);
  const Image a = read_image(plain), b = read_image(set), c = read_image(spec);
  // The same paths (the weight draws no number), pbrt's f() higher where the base's light leaves
  // through the rough coat.
  EXPECT_GT(image_mean(b), 1.03 * image_mean(a))
      << "coated.weights=pbrt did not reach the renderer: " << image_mean(b) << " against "
      << image_mean(a);
  EXPECT_TRUE(same_pixels(b, c));
}
