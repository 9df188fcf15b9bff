// One scene written by rll as JSON + OBJ, as glTF and as pbrt renders to the same image: the
// relMSE between renders of two formats (independent seeds) is that between two renders of one
// format, up to noise, and the per-pixel difference has mean zero.
#include <gtest/gtest.h>

#include "rll/eval/metrics.h"
#include "rll/scene/builtin.h"
#include "rll/io/load.h"
#include "rll/io/save.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;

TEST(FormatRender, JsonGltfAndPbrtCopiesOfASceneRenderAlike) {
  TempDir dir;
  // The Cornell box (diffuse walls, a metal block, a one-sided area light) and a point light.
  Scene original = make_builtin_scene("cornell-box");
  original.source = "builtin:cornell-box";
  original.lights.push_back(make_point_light(Vec3(0.3f, 0.7f, 0.6f), Rgb(0.3f, 0.2f, 0.1f)));
  original.width = 40;
  original.height = 30;
  original.finalize();
  save_json_scene(original, dir / "box.json");
  EXPECT_TRUE(save_gltf_scene(original, dir / "box.gltf").empty());
  EXPECT_TRUE(save_pbrt_scene(original, dir / "box.pbrt").empty());
  LoadOptions options;
  options.width = original.width;
  options.height = original.height;
  options.print_warnings = false;
  RenderRequest request;
  request.spp = 96;
  request.integrator.max_depth = 3;

  request.seed = 1;
  const Image reference = render_scene(load_scene((dir / "box.json").string(), options), request);
  request.seed = 2;
  const Image same = render_scene(load_scene((dir / "box.json").string(), options), request);
  const double noise = relmse(same, reference);
  ASSERT_GT(noise, 0);
  for (const char* file : {"box.gltf", "box.pbrt"}) {
    SCOPED_TRACE(file);
    const Scene s = load_scene((dir / file).string(), options);
    EXPECT_EQ(s.mesh.triangle_count(), original.mesh.triangle_count());
    EXPECT_EQ(s.lights.size(), original.lights.size());
    request.seed = 3;  // independent of both renders above
    const Image img = render_scene(s, request);
    const double r = relmse(img, reference);
    // Independent renders of equal scenes: equal expected relMSE. A wrong material, light or
    // camera adds its bias squared on top of the noise.
    EXPECT_LT(r, 1.25 * noise) << "relMSE " << r << " vs noise " << noise;
    EXPECT_GT(r, 0.8 * noise) << "relMSE " << r << " vs noise " << noise;
    const Estimate d = difference_estimate(img, same);
    EXPECT_LT(std::abs(d.mean), 4 * d.stderr_ + 1e-6) << d.mean << " +- " << d.stderr_;
  }
}
