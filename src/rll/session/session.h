// What every render of one scene shares (the loaded scene, its light tree, its ray-tracing
// structure, the integrator settings and the `--set` parameters), and rendering it with any
// light sampler: the common ground of `rll render`, `rll reference` and `rll compare`.
// The session owns the light tree: it builds it once after loading, lends it to every sampler
// it makes (which must not outlive it) and refits it when an animated scene's lights move.
#pragma once

#include <atomic>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "rll/accel/accel.h"
#include "rll/core/params.h"
#include "rll/cuda/wavefront.h"
#include "rll/io/load.h"
#include "rll/lighttree/light_tree.h"
#include "rll/render/integrator.h"
#include "rll/render/render.h"
#include "rll/scene/scene.h"
#include "rll/wavefront/wavefront.h"

namespace rll {

// The samplers a session renders with, as `rll samplers` and Python's rll.samplers() list them:
// every light sampler (light_sampler_names()), then `restir` (ReSTIR DI over one's candidates,
// render/restir.h).
const std::vector<std::string>& sampler_names();

struct SessionSettings {
  std::string scene;       // a scene file or builtin:NAME
  std::string resolution;  // "WIDTHxHEIGHT", or empty for the scene's own
  std::string integrator = "path";
  int max_depth = 5;
  std::vector<std::string> set;  // key=value parameters for samplers and the integrator
  std::string points = "sobol";  // --points: sobol or independent
  bool wavefront = false;        // --wavefront: render with rll/wavefront instead of the megakernel
  std::string device = "cpu";    // --device: cpu, or cuda (the wavefront renderer on the GPU)
  std::string tracer = "embree";  // --tracer: the CPU wavefront's tracer, embree or bvh
  std::string filter = "none";    // --filter: none, or psf (path-space filtering, render/psf.h)
};

// Film size limits of --res: a larger film would exhaust the memory of most machines.
inline constexpr int kMaxFilmSide = 65536;
inline constexpr long long kMaxFilmPixels = 1ll << 28;

// Parses --res WIDTHxHEIGHT (empty: keep the scene's), each side a whole number within the
// limits above (no wrap-around); throws rll::Error naming the flag.
LoadOptions parse_resolution(const std::string& resolution);

class RenderSession {
 public:
  // Parses the parameters, loads and finalizes the scene, builds its light tree and its accel.
  explicit RenderSession(const SessionSettings& settings);

  Scene& scene() { return m_scene; }
  const Scene& scene() const { return m_scene; }
  // The light tree over scene().lights, in whose order the lights are.
  const LightTree& light_tree() const { return m_tree; }
  Accel& accel() { return *m_accel; }
  const IntegratorSettings& integrator() const { return m_integrator; }
  PointSet points() const { return m_points; }
  const SessionSettings& settings() const { return m_settings; }
  // The renderer that render() runs: "megakernel", "wavefront" (on the CPU; "wavefront-bvh" with
  // --tracer bvh) or "cuda-wavefront" (--stats and reports say it).
  const char* renderer_name() const;
  // What set the film's size, for messages: "--res WxH" or "the film of scene 'FILE'".
  std::string film_source() const;
  // rll::check_film_memory (render/film.h) for this scene's film at `bytes_per_pixel` (holding
  // what `kept` says); the constructor checks kRenderBytesPerPixel, commands that keep more a
  // pixel check again.
  void check_film_memory(double bytes_per_pixel, const std::string& kept = kRenderPixelText) const;
  // The GPU renderer of --device cuda, else null.
  const cuda::GpuRenderer* gpu() const { return m_gpu.get(); }

  // A fresh sampler (no learnt state) by name, its parameters from --set. A variant may carry
  // its own parameters after colons, keys prefixed with the sampler's name unless they hold a
  // dot: "rll:within=uniform:reward=fullpdf" is rll with rll.within and rll.reward set. The
  // integrator's keys are a variant's too ("tree:nee.candidates=4"): integrator_for reads them.
  // Name `restir` ("restir:source=rll:candidates=32") makes ReSTIR's source sampler
  // (restir.source, fresh, its own keys from --set), which render() then renders with ReSTIR
  // (render/restir.h) and the wavefront renderer.
  std::unique_ptr<LightSampler> make_sampler(const std::string& spec) const;
  // The integrator settings a sampler spec renders with: --set's, with the variant's own
  // integrator keys in their place, so that "tree" and "tree:nee.candidates=4" run side by side
  // in one interleaved compare.
  IntegratorSettings integrator_for(const std::string& spec) const;
  // Throws rll::Error naming every --set key that no sampler or integrator asked for, with the
  // keys it may have meant (or that its sampler is not the one rendered with); call it once
  // every sampler the command needs has been made.
  void check_params_used() const;

  // Moves an animated scene to `frame` (lights switch and move), refits the ray tracer and the
  // light tree, and tells `sampler` (which keeps what it learnt). No-op for static scenes.
  void set_frame(int frame, LightSampler* sampler);

  using AfterPass = std::function<void(const RenderProgress&, const Film&)>;
  // Renders the current frame into `film` with `sampler` (with the session's --points, whatever
  // settings.points says), showing a progress bar labelled
  // `label` on a terminal when `show_progress`; `after_pass` as in render(). Unless cancelled,
  // at least one sample per pixel is taken, however short the time budget: a render never
  // ends as a black image of 0 spp. With `times`, the wavefront renderer adds its stage times
  // to it (the megakernel has no stages and leaves it as it is). With `integrator`, the
  // integrator settings of integrator_for(spec) instead of --set's.
  RenderProgress render(LightSampler& sampler, Film& film, const RenderSettings& settings,
                        const std::string& label, bool show_progress,
                        const std::atomic<bool>* cancel = nullptr, const AfterPass& after_pass = {},
                        WavefrontTimes* times = nullptr,
                        const IntegratorSettings* integrator = nullptr) const;

  // What the wavefront renderer's device did in the session's renders so far (--stats'
  // device_work): its path slots and one entry per pass.
  const WavefrontWork& wavefront_work() const { return m_wavefront_work; }
  // `rll interactive`'s frames: the GPU's film stays on the device from render to render (see
  // WavefrontSettings::film_stays_on_device) until read_film() brings the host's up to date.
  void keep_film_on_device(bool keep) { m_film_on_device = keep; }
  void read_film(Film& film) const;
  // The memory the path-space filter's temporal reuse keeps on the host for the next frame
  // (psf.temporal; render/psf.h), 0 before a render made it (--stats).
  size_t psf_history_bytes() const;
  // The memory ReSTIR's renders took on the CPU (each restir sampler's reservoirs and vertex
  // records: render/restir.h's kRestirBytesPerPixel a pixel), 0 before one rendered (--stats).
  size_t restir_bytes() const;
  // The restir samplers made, by spec, with their settings (--stats).
  std::map<std::string, RestirSettings> restir_made() const;

 private:
  std::unique_ptr<LightSampler> make_sampler_on_host(const std::string& spec) const;
  // --set's parameters with a variant's keys ("name:key=value:...") set; `name` the sampler's
  // name, `own` the keys as the spec wrote them.
  Params variant_params(const std::string& spec, std::string& name,
                        std::vector<std::string>& own) const;

  SessionSettings m_settings;
  Params m_params;
  Scene m_scene;
  LightTree m_tree;
  IntegratorSettings m_integrator;
  PointSet m_points = PointSet::Sobol;
  std::unique_ptr<Accel> m_accel;
  // --device cuda: the GPU renderer, and with it the device's copy of a learning sampler's state
  // (cuda/device_rll.cuh), kept between passes and renders; it hands the state back to its
  // sampler when it goes first (samplers made here must not outlive the session).
  std::unique_ptr<cuda::GpuRenderer> m_gpu;
  mutable std::vector<std::string> m_made;  // the samplers made, by name (for messages)
  // The CPU wavefront's path slots, kept from render to render, and what its renders did; a
  // render on another thread at the same time (Python) takes neither.
  mutable std::mutex m_wavefront_mutex;
  mutable WavefrontMemory m_wavefront_memory;
  mutable WavefrontWork m_wavefront_work;
  bool m_film_on_device = false;
  // The filter's temporal reuse on the CPU: its cells, kept from frame to frame (made at the first
  // render with psf.temporal); a render on another thread at the same time (Python) blends nothing.
  mutable std::mutex m_psf_mutex;
  mutable std::unique_ptr<PsfHistory> m_psf_history;
  // ReSTIR: the spec and integrator settings of each restir sampler made (by the source sampler
  // it made), and on the CPU each spec's history, kept from frame to frame (made at its first
  // render; by spec, so that the restir samplers of an interleaved compare keep theirs apart and
  // a fresh sampler of a spec finds its spec's).
  struct RestirMade {
    std::string spec;
    IntegratorSettings settings;
  };
  mutable std::mutex m_restir_mutex;
  mutable std::map<const LightSampler*, RestirMade> m_restir;
  mutable std::map<std::string, std::unique_ptr<RestirHistory>> m_restir_history;
};

}  // namespace rll
