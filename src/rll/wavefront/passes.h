// A render's passes as the wavefront renderer runs them on any device: each pass's items in
// batches of the driver's path slots (wavefront/driver.h), inside the pass loop every renderer
// shares (run_passes, render/render.h), with one host synchronisation per pass: the read of the
// pass's counts at its end.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <functional>
#include <vector>

#include "rll/core/error.h"
#include "rll/core/memory_budget.h"
#include "rll/render/film.h"
#include "rll/render/integrator.h"
#include "rll/render/render.h"
#include "rll/scene/scene.h"
#include "rll/wavefront/driver.h"
#include "rll/wavefront/kernels.h"
#include "rll/wavefront/wavefront.h"

namespace rll {

// The most path slots a render takes on the GPU: a 1080p frame at one sample per pixel, in one
// batch (what pbrt-v4's wavefront keeps in flight), about 2M slots.
inline constexpr size_t kMaxPathSlots = size_t(1920) * 1080;
// On the CPU: 32,768. A stop (Ctrl-C, the time budget) is seen between batches, which stay a
// fraction of a second long this way, and the CPU renders no faster with larger ones (a 640x480
// pass in one batch of 614,400 slots took the CPU time of 19 batches: bench/RESULTS.md) while a
// 1080p batch would hold 1.2 GB.
inline constexpr size_t kHostMaxPathSlots = size_t(1) << 15;

// The samples per pixel of a render's largest pass: run_passes' pass sizes (render/render.cpp)
// from the first sample on (a film that holds samples already only has smaller passes left).
inline int largest_pass_spp(const RenderSettings& s) {
  if (s.pass_spp < 1) return 1;
  const long long max_pass = std::max(s.pass_spp, s.max_pass_spp);
  long long largest = 1, first = 0;
  for (int passes = 0; first < s.spp; ++passes) {
    const long long size = std::min(max_pass, (long long)s.pass_spp << std::min(20, passes / 2));
    const long long count = std::min<long long>(size, s.spp - first);
    largest = std::max(largest, count);
    if (count == max_pass) break;  // (no pass is larger)
    first += count;
  }
  return int(largest);
}

// The path slots of a render: as many as its largest pass has paths, at most `max_slots` (the
// device's: kMaxPathSlots on the GPU, kHostMaxPathSlots on the CPU), at most `path_slots` where
// that is not 0, and as many as `budget_bytes` hold at wavefront_slot_bytes(draws, restir,
// reservoirs) each. Throws rll::Error if not one slot fits.
inline size_t wavefront_slot_count(uint32_t path_slots, const Film& film,
                                   const RenderSettings& settings, size_t budget_bytes,
                                   size_t max_slots = kMaxPathSlots, size_t draws = 1,
                                   bool restir = false, bool reservoirs = false) {
  const size_t pixels = size_t(film.width()) * film.height();
  size_t n = std::min(max_slots, pixels * size_t(largest_pass_spp(settings)));
  if (path_slots > 0) n = std::min<size_t>(n, path_slots);
  const size_t slot_bytes = wavefront_slot_bytes(draws, restir, reservoirs);
  const size_t fit = budget_bytes / slot_bytes;
  if (fit < 1)
    fail("the wavefront renderer's path slots take {} each, more than the {} they may use",
         format_bytes(double(slot_bytes)), format_bytes(double(budget_bytes)));
  return std::max<size_t>(1, std::min(n, fit));
}

// wavefront_slot_count for a render with `wavefront`'s settings, recorded in its work record
// (--stats' path_slots) where the caller keeps one.
inline size_t render_path_slots(const WavefrontSettings& wavefront, const Film& film,
                                const RenderSettings& settings, size_t budget_bytes,
                                size_t max_slots, size_t draws, bool restir = false,
                                bool reservoirs = false) {
  const size_t slots = wavefront_slot_count(wavefront.path_slots, film, settings, budget_bytes,
                                            max_slots, draws, restir, reservoirs);
  if (wavefront.work) {
    wavefront.work->path_slots = slots;
    wavefront.work->slot_bytes = slots * wavefront_slot_bytes(draws, restir, reservoirs);
    wavefront.work->budget_bytes = budget_bytes;
  }
  return slots;
}

// What every stage of a render reads, on either device: `scene_view`, `film`, `sobol`, `tracer` and
// `sampler` in the memory of the device that runs the stages.
template <typename Tracer>
WavefrontKernels<Tracer> wavefront_kernels(const Scene& scene, const SceneView& scene_view,
                                           const IntegratorSettings& integrator,
                                           const FilmView& film, const SobolView& sobol,
                                           const Tracer& tracer, const SamplerView& sampler) {
  WavefrontKernels<Tracer> k;
  k.c = make_path_constants(scene, scene_view, integrator);
  k.camera = scene.camera;
  k.sobol = sobol;
  k.tracer = tracer;
  k.sampler = sampler;
  k.film = film;
  return k;
}

// How the film of a device that keeps it in its own memory meets the pass loop (the GPU's; the
// host's film is the host's: leave these empty). `copy_film(last, complete)` runs after a pass's
// batches, before its one read: it queues a copy of the film to the host where the host is to
// read it (the caller's after_pass reads it; this is the render's `last` pass; a pass that was
// stopped before its end, not `complete`, must be copied) and says whether it did;
// `film_arrived()` runs after the read, which waited for that copy too. `start_min_count`: the
// fewest samples a pixel of the device's film holds at the start. Without them the host's film is
// read for its counts after every pass, as render() does.
struct WavefrontFilmHooks {
  std::function<bool(bool last, bool complete)> copy_film;
  std::function<void()> film_arrived;
  uint32_t start_min_count = 0;
};

// Runs the passes with `driver`; `end_pass` between passes (the sampler's). `device_work()` reads
// the backend's counters: where `work` is given, one entry per pass is added to it, what the
// device did from the pass's start (the render's, for the first) to the next pass's start (the
// end of the render, for the last).
template <typename Driver>
RenderProgress run_wavefront_passes(
    const Scene& scene, Driver& driver, const std::function<void()>& end_pass,
    const WavefrontFilmHooks& film_hooks, Film& film, const RenderSettings& settings,
    const std::atomic<bool>* cancel,
    const std::function<void(const RenderProgress&, const Film&)>& after_pass,
    const std::function<DeviceWork()>& device_work, const DeviceWork& render_start,
    std::vector<DeviceWork>* work) {
  const uint64_t pixels = uint64_t(film.width()) * film.height();
  const bool film_elsewhere = bool(film_hooks.copy_film);
  // The fewest samples per pixel of a film kept elsewhere, known without reading it: a whole pass
  // adds `count` to every pixel; a stopped one is the render's last, whose film the host reads.
  uint32_t min_count = film_hooks.start_min_count;
  DeviceWork mark = render_start;
  auto close_entry = [&] {
    if (!work) return;
    const DeviceWork now = device_work();
    work->push_back(now.since(mark));
    mark = now;
  };
  bool first_pass = true;
  // Samples [first, first + count) of every pixel, in batches of the driver's slots; true if
  // every one was taken (no stop came first).
  auto run_items = [&](int first, int count, uint64_t frame_seed, const PassStop& stop,
                       RayCounters& rays) {
    const uint64_t items = pixels * uint64_t(count);
    uint64_t item = 0;
    for (; item < items && !stop(); item += driver.slots()) {
      WavefrontBatch b;
      b.first_item = item;
      b.n = uint32_t(std::min<uint64_t>(driver.slots(), items - item));
      b.count = count;
      b.first = first;
      b.frame_seed = frame_seed;
      b.first_sample = settings.first_sample;
      b.points = settings.points;
      driver.run_batch(b);
      rays.camera += b.n;
    }
    return item >= items;
  };
  auto pass = [&](int first, int count, uint64_t frame_seed, const PassStop& stop,
                  RayCounters& rays, uint64_t& nonfinite, PsfCounts& filter) {
    if (!first_pass) close_entry();
    first_pass = false;
    driver.begin_pass();
    bool complete = true;
    if (!driver.per_sample()) {
      complete = run_items(first, count, frame_seed, stop, rays);
    } else {
      // Path-space filtering and ReSTIR: a sample of every pixel at a time, resolved before the
      // next sample's (render/psf.h, render/restir.h).
      for (int s = 0; s < count && complete; ++s) {
        if (stop.stopped()) {
          complete = false;
          break;
        }
        driver.begin_sample();
        complete = run_items(first + s, 1, frame_seed, stop, rays);
        driver.end_sample(settings.first_sample + uint64_t(first + s), frame_seed, settings.points);
      }
    }
    bool copied = false;
    if (film_elsewhere) {
      // The pass loop ends after this pass where it was stopped or reaches the spp.
      const bool last = !complete || stop.stopped() ||
                        uint64_t(min_count) + uint64_t(count) >= uint64_t(settings.spp);
      copied = film_hooks.copy_film(last, complete);
    }
    const WavefrontTally t = driver.end_pass();
    if (copied && film_hooks.film_arrived) film_hooks.film_arrived();
    rays.bounce += t.bounce;
    rays.shadow += t.shadow;
    rays.shadow_visible += t.shadow_visible;
    nonfinite += t.nonfinite;
    filter += t.filter;
    if (film_elsewhere)
      min_count = complete ? min_count + uint32_t(count) : film.min_count();  // (copied)
  };
  const RenderProgress progress =
      run_passes(scene, end_pass, film, settings, cancel, after_pass, pass,
                 film_elsewhere ? std::function<uint32_t()>([&] { return min_count; })
                                : std::function<uint32_t()>());
  if (!first_pass) close_entry();  // (a render with no pass to run has no entry)
  return progress;
}

}  // namespace rll
