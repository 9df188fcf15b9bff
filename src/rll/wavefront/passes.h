// A render's passes as the wavefront renderer runs them on any device: each pass's items in
// batches of the driver's path slots (wavefront/driver.h), inside the pass loop every renderer
// shares (run_passes, render/render.h).
#pragma once

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <functional>

#include "rll/core/error.h"
#include "rll/render/film.h"
#include "rll/render/integrator.h"
#include "rll/render/render.h"
#include "rll/scene/scene.h"
#include "rll/wavefront/kernels.h"

namespace rll {

// The path slots of a render: at most `path_slots` (at least one), and no more than the first
// pass can fill.
inline size_t wavefront_slot_count(uint32_t path_slots, const Film& film, int spp) {
  if (path_slots < 1) fail("the wavefront renderer needs at least one path slot");
  const size_t pixels = size_t(film.width()) * film.height();
  return std::min<size_t>(path_slots, pixels * size_t(std::clamp(spp, 1, 1 << 10)));
}

// What every stage of a render reads, on either device: `scene_view`, `film`, `sobol`, `tracer` and
// `sampler` in the memory of the device that runs the stages.
template <typename Tracer, typename Sampler>
WavefrontKernels<Tracer, Sampler> wavefront_kernels(const Scene& scene, const SceneView& scene_view,
                                                    const IntegratorSettings& integrator,
                                                    const FilmView& film, const SobolView& sobol,
                                                    const Tracer& tracer, const Sampler& sampler) {
  WavefrontKernels<Tracer, Sampler> k;
  k.c = make_path_constants(scene, scene_view, integrator);
  k.camera = scene.camera;
  k.sobol = sobol;
  k.tracer = tracer;
  k.sampler = sampler;
  k.film = film;
  return k;
}

// Runs the passes with `driver`; `end_pass` between passes (the sampler's), `pass_done` after
// each pass's last batch, before the pass loop reads the film (a device copies its film back).
template <typename Driver>
RenderProgress run_wavefront_passes(
    const Scene& scene, Driver& driver, const std::function<void()>& end_pass,
    const std::function<void()>& pass_done, Film& film, const RenderSettings& settings,
    const std::atomic<bool>* cancel,
    const std::function<void(const RenderProgress&, const Film&)>& after_pass) {
  const uint64_t pixels = uint64_t(film.width()) * film.height();
  auto pass = [&](int first, int count, uint64_t frame_seed, const PassStop& stop,
                  RayCounters& rays, uint64_t& nonfinite) {
    const uint64_t items = pixels * uint64_t(count);
    for (uint64_t item = 0; item < items && !stop(); item += driver.slots()) {
      WavefrontBatch b;
      b.first_item = item;
      b.n = uint32_t(std::min<uint64_t>(driver.slots(), items - item));
      b.count = count;
      b.first = first;
      b.frame_seed = frame_seed;
      b.first_sample = settings.first_sample;
      b.points = settings.points;
      const WavefrontTally t = driver.run_batch(b);
      rays.camera += b.n;
      rays.bounce += t.bounce;
      rays.shadow += t.shadow;
      rays.shadow_visible += t.shadow_visible;
      nonfinite += t.nonfinite;
    }
    pass_done();
  };
  return run_passes(scene, end_pass, film, settings, cancel, after_pass, pass);
}

}  // namespace rll
