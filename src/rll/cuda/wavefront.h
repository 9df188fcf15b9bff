// The wavefront renderer on the GPU (`rll render --device cuda`): the stages of wavefront/kernels.h
// launched by CUDA through the driver the CPU runs (wavefront/driver.h), rays traced by rll's own
// BVH (bvh/traverse.h), the scene, BVH and Sobol' tables in device memory, the light sampler's
// tables mirrored there. Plain C++: callers need no nvcc. Where CUDA is not built or no usable GPU
// is present, constructing a GpuRenderer throws rll::Error saying why.
#pragma once

#include <atomic>
#include <cstddef>
#include <functional>
#include <memory>
#include <string>

#include "rll/core/error.h"

#include "rll/lights/light_sampler.h"
#include "rll/render/film.h"
#include "rll/render/integrator.h"
#include "rll/render/render.h"
#include "rll/scene/scene.h"
#include "rll/wavefront/wavefront.h"

namespace rll::cuda {

// Throws rll::Error naming `label` (the sampler as the user gave it) unless the sampler has a
// device version (sampler_view() not the host kind: ltc has none).
inline void require_device_version(const LightSampler& sampler, const std::string& label) {
  const SamplerKind kind = sampler.sampler_view().kind;
  if (kind == SamplerKind::None || kind == SamplerKind::Host)
    fail(
        "sampler '{}' has no device version: --device cuda renders with uniform, power, tree, "
        "rll, fermat, rht and oracle (use --device cpu for it)",
        label);
}

class GpuRenderer {
 public:
  // Checks for a GPU (require_gpu), builds rll's BVH over the scene's mesh on the host and uploads
  // the scene, the BVH and the Sobol' tables.
  explicit GpuRenderer(const Scene& scene);
  ~GpuRenderer();
  GpuRenderer(const GpuRenderer&) = delete;
  GpuRenderer& operator=(const GpuRenderer&) = delete;

  // After the scene's vertices or lights moved (an animated scene's next frame): refits the BVH
  // and uploads the scene and the BVH again.
  void update(const Scene& scene);
  // Device memory in bytes: what is held between renders (scene, BVH, tables) and the most the
  // last render took besides (path slots, film, the sampler's tables).
  size_t device_bytes() const;
  // The device memory of the path-space filter's second table of cells (psf.temporal), what
  // temporal reuse adds (--stats' temporal_bytes); 0 before a render made it.
  size_t psf_temporal_bytes() const;
  // The GPU's name, as CUDA gives it.
  const std::string& device_name() const;

  // As render_wavefront (wavefront/wavefront.h) on the GPU; throws rll::Error for a sampler
  // without a device version (require_device_version). rll's and fermat's learning state stays
  // on the device (a learner, LightSampler::resident_learner(), lent to the device's copy that
  // this renderer owns: cuda/device_rll.cuh), its end of pass runs there; another sampler's tables
  // are uploaded at the start (it learns nothing within a pass). One host synchronisation per pass
  // (the read of its counts); the film comes back to the host, through pinned memory, in that wait,
  // only where the host reads it: after the last pass, and before each after_pass where
  // `wavefront.after_pass_reads_film` (unless `wavefront.film_stays_on_device`: see there). The
  // path slots, the film and the events are kept from render to render. `wavefront.tracer` is
  // ignored (the GPU traces with rll's BVH); `wavefront.times` receives the stages' times by CUDA
  // events, read once per pass; `wavefront.work` the slots and the device work per pass.
  RenderProgress render(
      const Scene& scene, LightSampler& sampler, const IntegratorSettings& integrator, Film& film,
      const RenderSettings& settings, const std::atomic<bool>* cancel = nullptr,
      const std::function<void(const RenderProgress&, const Film&)>& after_pass = {},
      const WavefrontSettings& wavefront = {});

  // Brings `film` up to date from the device where the last render left it there
  // (WavefrontSettings::film_stays_on_device); else nothing. A film left there must be read
  // (or rendered into again with film_stays_on_device) before the host changes it.
  void download_film(Film& film);

  struct Impl;

 private:
  std::unique_ptr<Impl> m_impl;
};

}  // namespace rll::cuda
