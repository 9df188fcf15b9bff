// What the GPU wavefront asks of the device (issue 43), counted by the CUDA backend: one host
// synchronisation per pass for a sampler whose end of pass is the host's (power, tree), no
// cudaMalloc after the first pass nor in a later render, the film copied to the host once, at the
// render's end (or not at all while it stays on the device between interactive's frames), and a
// film kept on the device gives the image to the bit that renders without keeping give.
#include <gtest/gtest.h>

#include <cstring>

#include "rll/accel/accel.h"
#include "rll/core/params.h"
#include "rll/cuda/wavefront.h"
#include "rll/wavefront/kernels.h"
#include "rll/wavefront/wavefront.h"
#include "support/test_support.h"

namespace rll {
namespace {

bool same_bits(const Image& a, const Image& b) {
  return a.pixel_count() == b.pixel_count() &&
         std::memcmp(a.pixels().data(), b.pixels().data(), a.pixel_count() * sizeof(Rgb)) == 0;
}

TEST(GpuDeviceWork, OneSyncPerPassAndTheFilmCopiedOnceAtTheEnd) {
  Scene scene = test::small_builtin_scene("cornell-boxes-room", 64, 48);
  const LightTree tree = build_light_tree(scene);
  const Accel accel(scene.mesh);
  cuda::GpuRenderer gpu(scene);
  for (const char* name : {"power", "tree"}) {
    SCOPED_TRACE(name);
    auto sampler = make_light_sampler(name, scene, tree, Params{}, &accel);
    Film film(scene.width, scene.height);
    RenderSettings rs;
    rs.spp = 12;
    WavefrontWork work;
    WavefrontSettings ws;
    ws.work = &work;
    const RenderProgress p =
        gpu.render(scene, *sampler, IntegratorSettings{}, film, rs, nullptr, {}, ws);
    ASSERT_EQ(work.passes.size(), size_t(p.passes));
    const uint64_t film_bytes = uint64_t(scene.width) * scene.height * (3 * 8 + 4);
    for (size_t i = 0; i < work.passes.size(); ++i) {
      const DeviceWork& w = work.passes[i];
      EXPECT_EQ(w.syncs, 1u) << "pass " << i;
      if (i > 0) {
        EXPECT_EQ(w.allocations, 0u) << "pass " << i;
      }
      if (i + 1 < work.passes.size()) {
        EXPECT_EQ(w.bytes_to_host, sizeof(WavefrontTally)) << "pass " << i << ": only its counts";
      } else {
        EXPECT_EQ(w.bytes_to_host, sizeof(WavefrontTally) + film_bytes) << "the last pass";
      }
    }
    EXPECT_EQ(film.min_count(), 12u);
  }
}

// Interactive's frames: a static scene's film stays on the device from frame to frame; no
// allocation in a later frame, nothing of the film copied until it is read, and the same image as
// one render of the same passes.
TEST(GpuDeviceWork, FramesKeepTheFilmOnTheDeviceWithTheSameImage) {
  Scene scene = test::small_builtin_scene("cornell-boxes-room", 64, 48);
  const LightTree tree = build_light_tree(scene);
  const Accel accel(scene.mesh);
  cuda::GpuRenderer gpu(scene);
  RenderSettings rs;
  rs.pass_spp = rs.max_pass_spp = 1;
  auto one = make_light_sampler("power", scene, tree, Params{}, &accel);
  Film whole(scene.width, scene.height);
  rs.spp = 4;
  gpu.render(scene, *one, IntegratorSettings{}, whole, rs);

  auto frames = make_light_sampler("power", scene, tree, Params{}, &accel);
  Film film(scene.width, scene.height);
  WavefrontWork work;
  WavefrontSettings ws;
  ws.work = &work;
  ws.film_stays_on_device = true;
  for (int f = 0; f < 4; ++f) {
    rs.spp = f + 1;
    gpu.render(scene, *frames, IntegratorSettings{}, film, rs, nullptr, {}, ws);
  }
  ASSERT_EQ(work.passes.size(), 4u);
  const uint64_t film_bytes = uint64_t(scene.width) * scene.height * (3 * 8 + 4);
  for (size_t f = 0; f < 4; ++f) {
    EXPECT_EQ(work.passes[f].syncs, 1u) << f;
    EXPECT_EQ(work.passes[f].bytes_to_host, sizeof(WavefrontTally)) << f;
    if (f > 0) {
      EXPECT_EQ(work.passes[f].allocations, 0u) << f;
      EXPECT_LT(work.passes[f].bytes_to_device, film_bytes) << f << ": the film is not uploaded";
    }
  }
  EXPECT_EQ(film.min_count(), 0u) << "the host's film is not read back between frames";
  gpu.download_film(film);
  EXPECT_EQ(film.min_count(), 4u);
  EXPECT_TRUE(same_bits(film.resolve(), whole.resolve()));
}

}  // namespace
}  // namespace rll
