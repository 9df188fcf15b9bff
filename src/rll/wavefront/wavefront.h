// The wavefront path tracer: paths in flight as structure-of-arrays state in a fixed budget of
// slots, advanced one bounce at a time by stages (camera rays, closest hit, emission and MIS,
// next-event set-up, shadow rays, its finish, rewards, BSDF sampling, accumulation), each a
// host_parallel_for over its own queue. It calls the megakernel's per-vertex functions
// (render/path_vertex.h) in the megakernel's order, so a path's radiance is the same to the bit.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>

#include "rll/accel/accel.h"
#include "rll/lights/light_sampler.h"
#include "rll/render/film.h"
#include "rll/render/integrator.h"
#include "rll/render/render.h"
#include "rll/scene/scene.h"
#include "rll/wavefront/stages.h"

namespace rll {

// What the wavefront renderer traces rays with on the CPU: Embree (the CPU's tracer), or rll's own
// BVH (bvh/traverse.h), the traversal a GPU runs, so that the CPU renders exactly what the GPU's
// code does.
enum class WavefrontTracer { Embree, Bvh };

struct WavefrontSettings {
  // Paths in flight at once: the state of each slot takes under 1 KB, allocated once per render.
  uint32_t path_slots = 1u << 15;
  WavefrontTracer tracer = WavefrontTracer::Embree;
  // When set, the times of the render are added to it (the clock is read only then).
  WavefrontTimes* times = nullptr;
};

// As render() (render/render.h), with the wavefront renderer: the same pass loop, the same
// samples of each pixel in the same order, so the film is the same to the bit whatever the thread
// count (for a sampler that learns nothing within a pass, the same as render()'s).
RenderProgress render_wavefront(
    const Scene& scene, const Accel& accel, LightSampler& sampler,
    const IntegratorSettings& integrator, Film& film, const RenderSettings& settings,
    const std::atomic<bool>* cancel = nullptr,
    const std::function<void(const RenderProgress&, const Film&)>& after_pass = {},
    const WavefrontSettings& wavefront = {});

}  // namespace rll
