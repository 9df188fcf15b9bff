#include <gtest/gtest.h>

#include <fstream>

#include "rll/core/error.h"
#include "rll/eval/reference.h"
#include "rll/io/load.h"
#include "rll/session/session.h"
#include "support/test_support.h"

using namespace rll;
namespace fs = std::filesystem;

namespace {
Scene small_box() {
  return load_scene("builtin:cornell-box", {8, 8});
}
}  // namespace

TEST(ReferenceCache, SceneHashIsStableAndSeesEveryChange) {
  const Scene base = small_box();
  const uint64_t h = base.fingerprint();
  EXPECT_EQ(small_box().fingerprint(), h);

  Scene moved = small_box();
  moved.mesh.positions[0].x += 1e-3f;
  EXPECT_NE(moved.fingerprint(), h);

  Scene brighter = small_box();
  bool changed = false;
  for (auto& m : brighter.materials)
    if (m.is_emissive()) m.emission = m.emission * 2.0f, changed = true;
  ASSERT_TRUE(changed);
  EXPECT_NE(brighter.fingerprint(), h);

  Scene rougher = small_box();
  rougher.materials[0].roughness += 0.1f;
  EXPECT_NE(rougher.fingerprint(), h);

  Scene camera = small_box();
  camera.camera.fov += 1;
  EXPECT_NE(camera.fingerprint(), h);

  EXPECT_NE(load_scene("builtin:cornell-box", {8, 6}).fingerprint(), h);

  Scene renamed = small_box();
  renamed.materials[0].name += "-renamed";  // names do not change the image
  EXPECT_EQ(renamed.fingerprint(), h);
}

TEST(ReferenceCache, SettingsHashSeesIntegratorChanges) {
  IntegratorSettings a;
  IntegratorSettings b = a;
  b.max_depth += 1;
  IntegratorSettings c = a;
  c.type = IntegratorType::Direct;
  IntegratorSettings d = a;
  d.strategy = LightStrategy::Nee;
  EXPECT_EQ(integrator_settings_hash(a), integrator_settings_hash(IntegratorSettings{}));
  EXPECT_NE(integrator_settings_hash(a), integrator_settings_hash(b));
  EXPECT_NE(integrator_settings_hash(a), integrator_settings_hash(c));
  EXPECT_NE(integrator_settings_hash(a), integrator_settings_hash(d));
}

TEST(ReferenceCache, FindsTheEntryWithMostSamplesAboveTheMinimum) {
  test::TempDir tmp;
  ReferenceCache cache(tmp / "cache");
  const ReferenceKey key{1, 2}, other{3, 2};
  EXPECT_FALSE(cache.find(key, 1).has_value());  // no folder yet
  auto store = [&](const ReferenceKey& k, int spp, uint64_t seed, float value) {
    ReferenceInfo info;
    info.scene = k == key ? "builtin:x" : "builtin:y";  // one scene would replace the other
    info.sampler = "power";
    info.spp = spp;
    info.seed = seed;
    return cache.store(k, Image(2, 2, Rgb(value)), info);
  };
  store(key, 64, 7, 1.0f);
  store(key, 256, 8, 2.0f);
  store(other, 1024, 7, 3.0f);

  auto hit = cache.find(key, 100);
  ASSERT_TRUE(hit.has_value());
  EXPECT_EQ(hit->spp, 256);
  EXPECT_EQ(read_image(hit->image)[0].x, 2.0f);
  EXPECT_EQ(cache.find(key, 10)->spp, 256);  // the best one, not just any
  EXPECT_FALSE(cache.find(key, 257).has_value());
  EXPECT_EQ(cache.find(key, 10, [](uint64_t s) { return s != 8; })->spp, 64);
  EXPECT_EQ(cache.find(other, 1)->spp, 1024);

  // A damaged entry is skipped, not an error.
  std::ofstream(cache.dir() / (key.hex() + "-512spp-seed9.json")) << "{ not json";
  std::ofstream(cache.dir() / (key.hex() + "-512spp-seed9.exr")) << "nope";
  EXPECT_EQ(cache.find(key, 10)->spp, 256);
}

TEST(ReferenceCache, StoringANewVersionOfASceneDropsTheOldOnes) {
  test::TempDir tmp;
  ReferenceCache cache(tmp.path());
  ReferenceInfo info;
  info.scene = "/scenes/room.obj";
  info.spp = 16;
  const ReferenceKey v1{1, 9}, v2{2, 9}, other_settings{1, 5};
  cache.store(v1, Image(2, 2), info);
  cache.store(other_settings, Image(2, 2), info);
  ReferenceInfo other_scene = info;
  other_scene.scene = "/scenes/hall.obj";
  cache.store(ReferenceKey{7, 9}, Image(2, 2), other_scene);
  cache.store(v2, Image(2, 2), info);
  EXPECT_FALSE(cache.find(v1, 1).has_value());
  EXPECT_FALSE(fs::exists(tmp / (v1.hex() + "-16spp-seed0.exr")));
  EXPECT_TRUE(cache.find(v2, 1).has_value());
  EXPECT_TRUE(cache.find(other_settings, 1).has_value());  // another integrator: still valid
  EXPECT_TRUE(cache.find(ReferenceKey{7, 9}, 1).has_value());
}

TEST(ReferenceCache, ObtainRendersOnceThenReuses) {
  test::TempDir tmp;
  ReferenceCache cache(tmp.path());
  SessionSettings ss;
  ss.scene = "builtin:cornell-box";
  ss.resolution = "8x8";
  ss.integrator = "direct";
  RenderSession session(ss);
  ReferenceRequest req;
  req.spp = 4;
  ObtainedReference first = obtain_reference(session, cache, req, false);
  EXPECT_FALSE(first.from_cache);
  EXPECT_TRUE(first.complete);
  EXPECT_EQ(first.info.spp, 4);
  ObtainedReference second = obtain_reference(session, cache, req, false);
  EXPECT_TRUE(second.from_cache);
  EXPECT_EQ(second.info.image, first.info.image);
  for (size_t i = 0; i < first.image.pixel_count(); ++i)
    ASSERT_EQ(first.image[i].y, second.image[i].y);
  req.force = true;
  EXPECT_FALSE(obtain_reference(session, cache, req, false).from_cache);
}

// A cache folder reached through a link to nothing (or with a file in its place) is refused by
// name, before any render: not "File exists", and nothing is made at the link's target.
TEST(ReferenceCache, FolderThroughADanglingLinkIsRefusedByName) {
  test::TempDir tmp;
  fs::create_symlink(tmp / "nowhere", tmp / "link");
  ReferenceCache through_link(tmp / "link" / "refs");
  try {
    through_link.check_writable();
    FAIL() << "a cache folder under a dangling link was accepted";
  } catch (const Error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("reference cache folder"), std::string::npos) << m;
    EXPECT_NE(m.find("symbolic link"), std::string::npos) << m;
    EXPECT_EQ(m.find("File exists"), std::string::npos) << m;
  }
  EXPECT_THROW(through_link.store(ReferenceKey{1, 2}, Image(2, 2), ReferenceInfo{}), Error);
  EXPECT_FALSE(fs::exists(tmp / "nowhere"));

  std::ofstream(tmp / "file") << "x";
  ReferenceCache under_file(tmp / "file");
  try {
    under_file.check_writable();
    FAIL() << "a cache folder that is a file was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("in the way"), std::string::npos) << e.what();
  }
}
