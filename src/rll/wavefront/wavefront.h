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
#include <string>
#include <vector>

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

// The memory of the path slots, kept from render to render by whoever holds it (a session, for
// `rll interactive`'s frames): a render given it takes its arrays from it and allocates nothing
// where the last render's arrays fit.
class WavefrontMemory {
 public:
  WavefrontMemory() = default;
  WavefrontMemory(const WavefrontMemory&) = delete;
  WavefrontMemory& operator=(const WavefrontMemory&) = delete;
  ~WavefrontMemory();
  size_t bytes() const;

  // The arrays, in the order a render takes them (wavefront.cpp's host backend).
  struct Block {
    void* data = nullptr;
    size_t bytes = 0, align = 0;
  };
  std::vector<Block> blocks;
};

// What a render's device did (--stats): its path slots and what they take, and one DeviceWork
// per pass (per frame in `rll interactive`), added to `passes` render after render.
struct WavefrontWork {
  size_t path_slots = 0;
  size_t slot_bytes = 0;    // the path slots' memory: their state and their places in the queues
  size_t budget_bytes = 0;  // what they could take (the share of the memory budget)
  std::vector<DeviceWork> passes;
};

struct WavefrontSettings {
  // Paths in flight at once, at most; 0 (the default) sizes them to the work: as many as the
  // largest pass has paths, up to a 1080p frame at 1 spp (about 2M) on the GPU and 32,768 on the
  // CPU (kHostMaxPathSlots), within a quarter of the memory budget (a slot takes under 1 KB).
  // Taken once per render; a pass takes its paths in batches of this many.
  uint32_t path_slots = 0;
  WavefrontTracer tracer = WavefrontTracer::Embree;
  // When set, the times of the render are added to it (the clock is read only then).
  WavefrontTimes* times = nullptr;
  // When set, the render's path slots and device work are recorded there.
  WavefrontWork* work = nullptr;
  // When set, the path slots' memory is taken from it and left there for the next render.
  WavefrontMemory* memory = nullptr;
  // The GPU's film (cuda/wavefront.h): whether the caller's after_pass reads the film (it is then
  // copied to the host before each after_pass; otherwise only at the end of the render).
  bool after_pass_reads_film = true;
  // The GPU's film: it stays on the device after the render, the host's film not brought up to
  // date, and the next render into the same film continues from the device's (interactive's
  // frames); GpuRenderer::download_film brings the host's up to date.
  bool film_stays_on_device = false;
  // The CPU's: the path-space filter's temporal reuse keeps its cells there from render to
  // render (render/psf.h; without it, no sample blends another's). The GPU keeps its own.
  PsfHistory* psf_history = nullptr;
  // The CPU's: ReSTIR's vertex records and final reservoirs of the last sample, kept there from
  // render to render (render/restir.h), so that a render that follows a frame reuses them
  // (temporal reuse across frames); without it, a render starts afresh. The GPU keeps its own,
  // one for the last restir spec rendered (`restir_spec`: another spec starts it afresh).
  RestirHistory* restir_history = nullptr;
  std::string restir_spec;
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
