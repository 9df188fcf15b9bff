// A scene saved as JSON + OBJ and loaded back renders like the original: the same image for the
// same seed, and means that agree within a confidence bound for independent seeds.
#include <gtest/gtest.h>

#include "rll/scene/builtin.h"
#include "rll/io/load.h"
#include "rll/io/save.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;

TEST(SaveJsonRender, SavedBuiltinScenesRenderLikeTheOriginals) {
  for (const char* name : {"cornell-box", "arch-interior"}) {
    SCOPED_TRACE(name);
    TempDir dir;
    Scene original = make_builtin_scene(name);
    original.source = std::string("builtin:") + name;
    original.width = 48;
    original.height = 36;
    original.finalize();
    save_json_scene(original, dir / "saved.json");
    Scene loaded = load_scene((dir / "saved.json").string());
    EXPECT_EQ(loaded.mesh.triangle_count(), original.mesh.triangle_count());
    EXPECT_EQ(loaded.lights.size(), original.lights.size());
    EXPECT_EQ(loaded.sky_triangle_count, original.sky_triangle_count);

    RenderRequest request;
    request.spp = 8;
    request.seed = 7;
    Image a = render_scene(original, request);
    Image b = render_scene(loaded, request);
    // Same scene, same seed: the same image, pixel for pixel.
    ASSERT_EQ(a.pixel_count(), b.pixel_count());
    size_t differing = 0;
    for (size_t i = 0; i < a.pixel_count(); ++i) differing += !(a[i] == b[i]);
    EXPECT_EQ(differing, 0u);

    // Independent seeds: the means agree within 4 standard errors.
    request.seed = 8;
    Image c = render_scene(loaded, request);
    Estimate ea = block_estimate(a), ec = block_estimate(c);
    EXPECT_GT(ea.mean, 0);
    EXPECT_TRUE(agree(ea, ec)) << ea.mean << " +- " << ea.stderr_ << " vs " << ec.mean << " +- "
                               << ec.stderr_;
  }
}
