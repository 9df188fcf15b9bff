// Light transport: `direct` (next-event estimation) and `path` (NEE + BSDF sampling with MIS,
// Russian roulette). Both ask the light sampler for every light choice and feed it rewards.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "rll/accel/accel.h"
#include "rll/core/param_table.h"
#include "rll/core/rng.h"
#include "rll/lights/light_sampler.h"
#include "rll/render/film.h"
#include "rll/render/path_vertex.h"
#include "rll/render/psf.h"
#include "rll/render/restir.h"
#include "rll/scene/scene.h"
#include "rll/scene/scene_view.h"

namespace rll {

class Params;

struct IntegratorSettings {
  IntegratorType type = IntegratorType::Path;
  int max_depth = 5;  // path: bounces; 1 = direct light only
  LightStrategy strategy = LightStrategy::Mis;
  int rr_depth = 3;        // Russian roulette from this bounce on
  int nee_candidates = 1;  // resampled next-event estimation's M (docs/nee.md)
  // nee.target=learnt: its target carries the sampler's learnt factor (nee_target)
  bool nee_learnt_target = false;
  // nee.draw=cluster: candidates 2..M from the first one's cluster (docs/nee.md)
  bool nee_cluster = false;
  // coated.weights: CoatedDiffuse's MIS weight in eval() (scene/bsdf.h); pbrt only to match
  // pbrt-v4's images (docs/materials.md)
  CoatedWeights coated_weights = CoatedWeights::Unbiased;
  PsfSettings psf;        // --filter psf and its psf.* keys (render/psf.h)
  RestirSettings restir;  // a restir sampler's restir.* keys (render/restir.h)
  // The error budget's studies of rll (rll.ideal_point, rll.ideal_bsdf; lights/rll_settings.h,
  // RllStudy), the megakernel's alone: points on the chosen light per next-event sample, and BSDF
  // directions whose MIS-weighted emission replaces the path's own BSDF ray's; 0: off.
  uint32_t ideal_point = 0, ideal_bsdf = 0;
};

// Parses --integrator and the integrator's `--set` keys (path.strategy, path.rr_depth,
// nee.candidates, nee.target, nee.draw, coated.*), and with `filter` (--filter: none or psf) the
// filter's (psf.*, make_psf_settings); with `restir` (a restir sampler renders) ReSTIR's (restir.*,
// make_restir_settings), which are left unread otherwise.
IntegratorSettings make_integrator_settings(const std::string& name, int max_depth,
                                            const Params& params,
                                            const std::string& filter = "none",
                                            bool restir = false);
// The coated.* keys (core/param_table.h): coated.weights=unbiased|pbrt.
const std::vector<ParamSpec<IntegratorSettings>>& coated_params();
const char* integrator_name(IntegratorType t);
const char* strategy_name(LightStrategy s);

// Rays traced by one worker; summed after each tile.
struct RayCounters {
  uint64_t camera = 0, bounce = 0, shadow = 0;
  // Light samples whose shadow ray reached the light (traced, unoccluded; one facing away from
  // the point reaches nothing): over `shadow`, the visible-sample ratio (Kvasnica & Havran).
  uint64_t shadow_visible = 0;
  uint64_t total() const { return camera + bounce + shadow; }
  double visible_ratio() const {
    return shadow > 0 ? double(shadow_visible) / double(shadow) : 0.0;
  }
  RayCounters& operator+=(const RayCounters& o) {
    camera += o.camera;
    bounce += o.bounce;
    shadow += o.shadow;
    shadow_visible += o.shadow_visible;
    return *this;
  }
};

class Integrator {
 public:
  Integrator(const Scene& scene, const Accel& accel, LightSampler& sampler,
             IntegratorSettings settings);
  // Radiance along a camera ray; `stream` supplies the per-sample random numbers. With `camera`,
  // also what the camera vertex saw of the light sampler (the per-pixel diagnostics); the
  // radiance is the same with or without. With `cut` (path-space filtering, render/psf.h), the
  // path is cut where psf_cuts_here says: `cut` then holds the cut and the radiance returned is
  // what the path gathered after it.
  Rgb li(const Ray& camera_ray, SampleStream& stream, RayCounters& counters,
         CameraVertexSample* camera = nullptr, PsfCut* cut = nullptr) const;
  const IntegratorSettings& settings() const { return m_settings; }
  // The sampler's view again, after a change to it (its end of pass, lights_changed, load_state).
  void sampler_changed() { m_view = m_sampler.sampler_view(); }
  const PathConstants& constants() const { return m_constants; }

 private:
  // The next-event estimate at a vertex: its contribution (MIS-weighted for `path`), already
  // divided by the light pmf, before the path throughput: the samples of draw_nee
  // (render/nee_draw.h), one (resampled from nee.candidates) or a multi-sample sampler's several
  // (rht), each with a shadow ray. With `split` (a path-space filter's cut that splits,
  // psf_splits), the diffuse share of each sample only, its glossy share added to split->before.
  Rgb sample_light(const LightContext& ctx, const Bsdf& bsdf, const Vec3& wo, int depth,
                   const Rgb& beta, SampleStream& stream, RayCounters& counters,
                   CameraVertexSample* camera, PsfCut* split = nullptr) const;
  // rll.ideal_point: the next-event sample `d` with its light's contribution averaged over
  // ideal_point points on it, each with its shadow ray (the MIS weights as for one point).
  NeeResult ideal_point_nee(const NeeDraw& d, const LightContext& ctx, const Bsdf& bsdf,
                            const Vec3& wo, const Rgb& beta, Vec2 shift,
                            RayCounters& counters) const;
  // rll.ideal_bsdf: the BSDF side of MIS at a vertex, the emission that BSDF rays find weighted
  // against light sampling, averaged over ideal_bsdf directions (before the path throughput).
  Rgb ideal_bsdf_side(const LightContext& ctx, const Bsdf& bsdf, const SurfaceHit& sh,
                      const Vec3& wo, const BsdfNumbers& u, RayCounters& counters) const;

  const Scene& m_scene;
  const Accel& m_accel;
  LightSampler& m_sampler;
  IntegratorSettings m_settings;
  SamplerView m_view;  // the sampler as the dispatch reads it (light_dispatch.h)
  SceneData m_data;    // the hot data the functions below read, as flat views
  PathConstants m_constants;
};

// Throws rll::Error where the settings do not fit the sampler (nee.candidates above 1 with a
// sampler that resamples its own candidates, rht) or the renderer (the megakernel's studies,
// rll.ideal_point and ideal_bsdf, which the Integrator checks itself); every other renderer asks.
void check_nee_settings(const IntegratorSettings& settings, const SamplerView& view,
                        const std::string& name);

// The integrator's settings and the scene's views as every path vertex reads them.
PathConstants make_path_constants(const Scene& scene, const SceneView& view,
                                  const IntegratorSettings& settings);

}  // namespace rll
