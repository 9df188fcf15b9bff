// What the wavefront renderer asks of its device (issue 43), counted by the host backend, which
// runs the driver code the GPU runs: one host synchronisation per pass (no read between stages,
// bounces or batches), no allocation after the first pass, nor in a later render that keeps its
// memory (interactive's frames); the path slots sized to the work within the memory budget; and
// `rll render --wavefront --stats` and `rll interactive --stats` report them as device_work.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <cstring>
#include <nlohmann/json.hpp>

#include "rll/accel/accel.h"
#include "rll/core/memory_budget.h"
#include "rll/core/params.h"
#include "rll/wavefront/passes.h"
#include "rll/wavefront/wavefront.h"
#include "support/test_support.h"

using namespace rll;
using namespace rll::test;

namespace {

struct CountedRun {
  RenderProgress progress;
  WavefrontWork work;
  Image image;
};

CountedRun render_counted(const Scene& scene, const LightTree& tree, const Accel& accel,
                          const std::string& sampler_name,
                          IntegratorType type, int spp, uint32_t path_slots,
                          WavefrontMemory* memory = nullptr, LightSampler* sampler = nullptr) {
  Params params;
  std::unique_ptr<LightSampler> own;
  if (!sampler) {
    own = make_light_sampler(sampler_name, scene, tree, params, &accel);
    sampler = own.get();
  }
  IntegratorSettings is;
  is.type = type;
  Film film(scene.width, scene.height);
  RenderSettings rs;
  rs.spp = spp;
  WavefrontSettings ws;
  ws.path_slots = path_slots;
  CountedRun r;
  ws.work = &r.work;
  ws.memory = memory;
  r.progress = render_wavefront(scene, accel, *sampler, is, film, rs, nullptr, {}, ws);
  r.image = film.resolve();
  return r;
}

void expect_one_sync_per_pass(const CountedRun& r, const std::string& what) {
  SCOPED_TRACE(what);
  ASSERT_EQ(r.work.passes.size(), size_t(r.progress.passes));
  ASSERT_GE(r.work.passes.size(), 2u);
  for (size_t p = 0; p < r.work.passes.size(); ++p) {
    const DeviceWork& w = r.work.passes[p];
    EXPECT_EQ(w.syncs, 1u) << "pass " << p;
    EXPECT_GT(w.launches, 0u) << "pass " << p;
    // The host's memory is the host's: nothing is copied.
    EXPECT_EQ(w.bytes_to_host, 0u) << "pass " << p;
    EXPECT_EQ(w.bytes_to_device, 0u) << "pass " << p;
    if (p == 0) {
      EXPECT_GT(w.allocations, 0u) << "the render's memory is taken in its first pass";
    } else {
      EXPECT_EQ(w.allocations, 0u) << "pass " << p;
    }
  }
}

// Many batches per pass (300 slots for 12x9 pixels of up to 4 samples) and one batch per pass
// (the slots sized to the work), path and direct, a sampler that learns (rll: its rewards stage
// runs) and one that does not: always one synchronisation per pass, whatever the bounces and
// batches, and the slots' memory taken once.
TEST(WavefrontDeviceWork, OneSyncPerPassAndNoAllocationAfterTheFirst) {
  Scene scene = small_builtin_scene("cornell-boxes-room", 12, 9);
  const LightTree tree = build_light_tree(scene);
  const Accel accel(scene.mesh);
  for (const char* sampler : {"power", "rll"})
    for (const IntegratorType type : {IntegratorType::Path, IntegratorType::Direct})
      for (const uint32_t slots : {300u, 0u}) {
        const std::string what =
            fmt::format("{} {} {} slots", sampler, integrator_name(type), slots);
        const CountedRun r = render_counted(scene, tree, accel, sampler, type, 12, slots);
        expect_one_sync_per_pass(r, what);
        if (slots == 0) {
          EXPECT_EQ(r.work.path_slots, 12u * 9u * 4u) << what;  // 4-spp passes
        }
      }
}

// A deep path (max depth 64, Russian roulette ends most paths long before): the bounces are
// launched without reading how many rays are left, still one synchronisation per pass.
TEST(WavefrontDeviceWork, DeepPathsStillOneSyncPerPass) {
  Scene scene = small_builtin_scene("glazed-room", 10, 8);
  const LightTree tree = build_light_tree(scene);
  const Accel accel(scene.mesh);
  Params params;
  auto sampler = make_light_sampler("tree", scene, tree, params, &accel);
  IntegratorSettings is;
  is.max_depth = 64;
  Film film(scene.width, scene.height);
  RenderSettings rs;
  rs.spp = 6;
  WavefrontSettings ws;
  ws.path_slots = 50;
  WavefrontWork work;
  ws.work = &work;
  const RenderProgress p = render_wavefront(scene, accel, *sampler, is, film, rs, nullptr, {}, ws);
  ASSERT_EQ(work.passes.size(), size_t(p.passes));
  for (const DeviceWork& w : work.passes) EXPECT_EQ(w.syncs, 1u);
  EXPECT_GT(p.rays.bounce, p.rays.camera) << "the paths bounced";
}

// Renders that keep their memory (interactive's frames, a session's renders): none allocates
// after the first render, and the image is the one a fresh render gives, to the bit (the reused
// slots hold the last render's paths, which no stage reads).
TEST(WavefrontDeviceWork, KeptMemoryTakesNothingNewAndChangesNoBit) {
  Scene scene = small_builtin_scene("cornell-boxes-room", 12, 9);
  const LightTree tree = build_light_tree(scene);
  const Accel accel(scene.mesh);
  WavefrontMemory memory;
  const CountedRun fresh = render_counted(scene, tree, accel, "rll", IntegratorType::Path, 8, 0);
  const CountedRun first = render_counted(scene, tree, accel, "rll", IntegratorType::Path, 8, 0, &memory);
  EXPECT_GT(first.work.passes.front().allocations, 0u);
  EXPECT_GT(memory.bytes(), 0u);
  // Another sampler and integrator into the same memory (whose slots hold rll's paths now), then
  // rll again.
  render_counted(scene, tree, accel, "power", IntegratorType::Direct, 4, 0, &memory);
  const CountedRun again = render_counted(scene, tree, accel, "rll", IntegratorType::Path, 8, 0, &memory);
  for (const DeviceWork& w : again.work.passes) {
    EXPECT_EQ(w.allocations, 0u);
    EXPECT_EQ(w.syncs, 1u);
  }
  for (const CountedRun* r : {&first, &again})
    EXPECT_EQ(std::memcmp(r->image.pixels().data(), fresh.image.pixels().data(),
                          fresh.image.pixel_count() * sizeof(Rgb)),
              0);
}

// The slots: as many as the largest pass has paths, a 1080p frame at 1 spp at most (32,768 on
// the CPU), within the budget given, at most path_slots where set; a budget without room for one
// slot is refused with the sizes named.
TEST(WavefrontDeviceWork, SlotsSizedToTheWorkWithinTheBudget) {
  const size_t slot = wavefront_slot_bytes();
  EXPECT_GT(slot, 200u);
  EXPECT_LT(slot, 2048u);
  const size_t big = size_t(1) << 40;
  RenderSettings rs;  // passes of 1, 1, 2, 2, 4, 4, 8, 8, ... spp
  rs.spp = 64;
  const Film small(64, 48), hd(1920, 1080), k4(3840, 2160);
  EXPECT_EQ(wavefront_slot_count(0, small, rs, big), 64u * 48u * 8u);
  EXPECT_EQ(wavefront_slot_count(0, small, rs, big, kHostMaxPathSlots), 64u * 48u * 8u);
  EXPECT_EQ(wavefront_slot_count(0, hd, rs, big, kHostMaxPathSlots), kHostMaxPathSlots);
  EXPECT_EQ(wavefront_slot_count(0, hd, rs, big), kMaxPathSlots);
  EXPECT_EQ(wavefront_slot_count(0, k4, rs, big), kMaxPathSlots);
  EXPECT_EQ(kMaxPathSlots, 1920u * 1080u);
  EXPECT_EQ(wavefront_slot_count(1000, small, rs, big), 1000u);
  EXPECT_EQ(wavefront_slot_count(0, hd, rs, 1000 * slot + slot / 2), 1000u);
  rs.spp = 16;  // passes of 1, 1, 2, 2, 4, 4 and 2 spp: no more than the largest pass needs
  EXPECT_EQ(wavefront_slot_count(0, small, rs, big), 64u * 48u * 4u);
  rs.spp = 3;  // 1, 1, 1
  EXPECT_EQ(wavefront_slot_count(0, small, rs, big), 64u * 48u);
  rs.spp = kUnlimitedSpp;  // a time budget's render
  EXPECT_EQ(wavefront_slot_count(0, small, rs, big), 64u * 48u * 8u);
  rs.pass_spp = rs.max_pass_spp = 1;  // interactive's frames
  rs.spp = 40;
  EXPECT_EQ(wavefront_slot_count(0, small, rs, big), 64u * 48u);
  const std::string e = error_of([&] { wavefront_slot_count(0, small, rs, slot - 1); });
  expect_mentions(e, {"path slots", "bytes"});
}

// `rll render --wavefront --stats`: the path slots and a device_work entry per pass, each with
// one synchronisation and, after the first, no allocation.
TEST(WavefrontDeviceWork, RenderStatsReportDeviceWorkPerPass) {
  TempDir dir;
  const auto stats = dir / "stats.json";
  const CommandResult r = run_rll(
      {"render", "builtin:cornell-boxes-room", "--wavefront", "--sampler", "rll", "--res", "16x12",
       "--spp", "8", "--quiet", "-o", (dir / "a.exr").string(), "--stats", stats.string()},
      120);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(read_text(stats));
  ASSERT_TRUE(j.contains("device_work")) << j.dump(2);
  const nlohmann::json& work = j["device_work"];
  ASSERT_EQ(work.size(), 5u) << "passes of 1, 1, 2, 2 and 2 spp";
  for (size_t p = 0; p < work.size(); ++p) {
    EXPECT_EQ(work[p]["syncs"], 1) << p;
    EXPECT_GT(work[p]["launches"].get<int>(), 0) << p;
    if (p > 0) {
      EXPECT_EQ(work[p]["allocations"], 0) << p;
    }
    EXPECT_EQ(work[p]["bytes_to_host"], 0) << p;
    EXPECT_EQ(work[p]["bytes_to_device"], 0) << p;
  }
  EXPECT_GT(work[0]["allocations"].get<int>(), 0);
  EXPECT_EQ(j["path_slots"]["count"], 16 * 12 * 2);
  EXPECT_EQ(j["path_slots"]["bytes"].get<size_t>(), 16 * 12 * 2 * wavefront_slot_bytes());
  EXPECT_GT(j["path_slots"]["budget_bytes"].get<size_t>(), j["path_slots"]["bytes"].get<size_t>());
}

// `rll interactive --stats`: one entry per frame, one synchronisation each, no allocation after
// the first frame (the session keeps the slots' memory).
TEST(WavefrontDeviceWork, InteractiveStatsReportDeviceWorkPerFrame) {
  TempDir dir;
  const auto stats = dir / "stats.json";
  const CommandResult r =
      run_rll({"interactive", "builtin:cornell-boxes-room", "--sampler", "rll", "--res", "16x12",
               "--frames", "4", "--quiet", "--stats", stats.string()},
              120);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(read_text(stats));
  ASSERT_TRUE(j.contains("device_work")) << j.dump(2);
  const nlohmann::json& work = j["device_work"];
  ASSERT_EQ(work.size(), 4u);
  for (size_t f = 0; f < work.size(); ++f) {
    EXPECT_EQ(work[f]["syncs"], 1) << f;
    if (f > 0) {
      EXPECT_EQ(work[f]["allocations"], 0) << f;
    }
  }
  EXPECT_EQ(j["path_slots"]["count"], 16 * 12);
}

}  // namespace
