#include "rll/render/integrator.h"

#include "rll/core/error.h"
#include "rll/core/params.h"
#include "rll/lights/light_dispatch.h"
#include "rll/lights/rll_study.h"
#include "rll/render/nee_draw.h"

namespace rll {

const char* integrator_name(IntegratorType t) {
  return t == IntegratorType::Direct ? "direct" : "path";
}

const char* strategy_name(LightStrategy s) {
  switch (s) {
    case LightStrategy::Mis:
      return "mis";
    case LightStrategy::Nee:
      return "nee";
    case LightStrategy::Bsdf:
      return "bsdf";
  }
  return "?";
}

const std::vector<ParamSpec<IntegratorSettings>>& coated_params() {
  // The order of the names is CoatedWeights' (the field holds the index).
  static const std::vector<ParamSpec<IntegratorSettings>> table = {
      choice_param("weights", {"unbiased", "pbrt"},
                   field<IntegratorSettings, &IntegratorSettings::coated_weights>()),
  };
  return table;
}

IntegratorSettings make_integrator_settings(const std::string& name, int max_depth,
                                            const Params& params, const std::string& filter,
                                            bool restir) {
  IntegratorSettings s;
  if (name == "direct")
    s.type = IntegratorType::Direct;
  else if (name == "path")
    s.type = IntegratorType::Path;
  else
    fail("unknown integrator '{}' (valid: direct, path)", name);
  if (max_depth < 1) fail("--max-depth must be at least 1 (got {})", max_depth);
  s.max_depth = max_depth;
  // Both integrators combine light and BSDF sampling by MIS unless told otherwise; `direct` is
  // `path` at depth 1 (as pbrt-v4's path integrator with maxdepth 1).
  const std::string key = s.type == IntegratorType::Path ? "path.strategy" : "direct.strategy";
  std::string st = params.get_choice(key, "mis", {"mis", "nee", "bsdf"});
  s.strategy = st == "mis"   ? LightStrategy::Mis
               : st == "nee" ? LightStrategy::Nee
                             : LightStrategy::Bsdf;
  if (s.type == IntegratorType::Path) {
    s.rr_depth = int(params.get_int("path.rr_depth", 3));
    if (s.rr_depth < 1) fail("--set path.rr_depth must be at least 1");
  }
  s.nee_candidates = int(params.get_int_in("nee.candidates", 1, 1, kMaxNeeCandidates));
  s.nee_learnt_target =
      params.get_choice("nee.target", "unshadowed", {"unshadowed", "learnt"}) == "learnt";
  s.nee_cluster = params.get_choice("nee.draw", "full", {"full", "cluster"}) == "cluster";
  // Read here by key, not by RllStudy's table (a sampler that is not rll must not take rll's
  // other study keys as read: make_light_sampler reads those), and only where given (so that
  // another sampler's command does not count rll.* keys as known).
  if (params.has("rll.ideal_point"))
    s.ideal_point = uint32_t(params.get_int_in("rll.ideal_point", 0, 0, 4096));
  if (params.has("rll.ideal_bsdf"))
    s.ideal_bsdf = uint32_t(params.get_int_in("rll.ideal_bsdf", 0, 0, 4096));
  read_params(coated_params(), params, "coated", s);
  s.psf = make_psf_settings(filter, s.type == IntegratorType::Direct ? 1 : s.max_depth,
                            s.type == IntegratorType::Path, params);
  if (restir) s.restir = make_restir_settings(params, filter);
  return s;
}

PathConstants make_path_constants(const Scene& scene, const SceneView& view,
                                  const IntegratorSettings& settings) {
  PathConstants c;
  c.scene = view;
  c.scene_center = scene.bounds.center();
  c.scene_radius = scene.radius;
  c.pixel_angle = scene.camera.pixel_angle();
  c.strategy = settings.strategy;
  c.max_depth = settings.type == IntegratorType::Direct ? 1 : settings.max_depth;
  c.rr_depth = settings.rr_depth;
  c.nee_candidates = settings.nee_candidates;
  c.nee_learnt_target = settings.nee_learnt_target;
  c.nee_cluster = settings.nee_cluster;
  c.coated_weights = settings.coated_weights;
  c.psf = make_psf_constants(settings.psf, scene.bounds);
  c.restir = make_restir_constants(settings.restir);
  return c;
}

namespace {
void check_candidates(const IntegratorSettings& settings, const SamplerView& view,
                      const std::string& name) {
  if (draws_several(view) && settings.nee_candidates != 1)
    fail("--set nee.candidates={}: sampler '{}' resamples its own candidates (leave it at 1)",
         settings.nee_candidates, name);
  if (!settings.nee_cluster) return;
  if (settings.nee_candidates < 2)
    fail(
        "--set nee.draw=cluster draws candidates 2..M from the first one's cluster: set "
        "nee.candidates above 1");
  if (view.kind == SamplerKind::Rll && !draws_clusters(view))
    fail(
        "--set nee.draw=cluster: with rll.defensive=tree a cluster's lights come from a mixture "
        "of two rules unless rll.within=tree; use one of those, or nee.draw=full");
  if (!draws_clusters(view))
    fail(
        "--set nee.draw=cluster: sampler '{}' does not draw a cluster first (rll, fermat and "
        "oracle do); use nee.draw=full",
        name);
}

// The error budget's studies of the megakernel (rll.ideal_point, ideal_bsdf): rll's (and the
// oracle's, which samples with rll.*), with one light sample a vertex.
void check_studies(const IntegratorSettings& settings, const std::string& name) {
  const char* key = settings.ideal_point > 0 ? "rll.ideal_point" : "rll.ideal_bsdf";
  if (settings.ideal_point == 0 && settings.ideal_bsdf == 0) return;
  if (name != "rll" && name != "oracle")
    fail("--set {}: a study setting of rll's error budget (docs/rll.md); sampler '{}' is not rll",
         key, name);
  if (settings.nee_candidates != 1)
    fail("--set {}: the study averages one light sample's points; leave nee.candidates at 1", key);
  if (settings.ideal_bsdf > 0 && settings.strategy != LightStrategy::Mis)
    fail("--set rll.ideal_bsdf: the BSDF side of MIS needs the mis strategy (the default)");
}
}  // namespace

void check_nee_settings(const IntegratorSettings& settings, const SamplerView& view,
                        const std::string& name) {
  check_candidates(settings, view, name);
  if (settings.ideal_point > 0 || settings.ideal_bsdf > 0)
    fail(
        "--set {}: a study setting of rll's error budget, on the CPU's megakernel only (leave out "
        "--wavefront and --device)",
        settings.ideal_point > 0 ? "rll.ideal_point" : "rll.ideal_bsdf");
}

Integrator::Integrator(const Scene& scene, const Accel& accel, LightSampler& sampler,
                       IntegratorSettings settings)
    : m_scene(scene),
      m_accel(accel),
      m_sampler(sampler),
      m_settings(settings),
      m_view(sampler.sampler_view()),
      m_data(scene),
      m_constants(make_path_constants(scene, m_data.view(), settings)) {
  check_candidates(settings, m_view, sampler.name());
  check_studies(settings, sampler.name());
}

NeeResult Integrator::ideal_point_nee(const NeeDraw& d, const LightContext& ctx, const Bsdf& bsdf,
                                      const Vec3& wo, const Rgb& beta, Vec2 shift,
                                      RayCounters& counters) const {
  const uint32_t n = m_settings.ideal_point;
  NeeResult sum;
  sum.record.mis_weight = 0;
  for (uint32_t i = 0; i < n; ++i) {
    const NeeSetup setup =
        nee_setup(m_constants, ctx, bsdf, wo, d.light.light, rotated_hammersley(i, n, shift));
    if (setup.counts_shadow_ray) ++counters.shadow;
    const bool occluded = setup.traces && m_accel.occluded(setup.shadow);
    if (reaches_light(setup, occluded)) ++counters.shadow_visible;
    NeeDraw one = d;
    one.setup = setup;
    const NeeResult r = finish_nee_draw(m_constants, one, occluded, bsdf, wo, beta);
    sum.value += r.value;
    sum.record.estimate += r.record.estimate;
    sum.record.unoccluded += r.record.unoccluded;
    sum.record.mis_weight += r.record.mis_weight;
    sum.record.max_rgb += r.record.max_rgb;
  }
  const float inv = 1.0f / float(n);
  sum.value *= inv;
  sum.record.estimate *= inv;
  sum.record.unoccluded *= inv;
  sum.record.mis_weight *= inv;
  sum.record.max_rgb *= inv;
  return sum;
}

Rgb Integrator::ideal_bsdf_side(const LightContext& ctx, const Bsdf& bsdf, const SurfaceHit& sh,
                                const Vec3& wo, const BsdfNumbers& u, RayCounters& counters) const {
  const PathConstants& c = m_constants;
  const uint32_t n = m_settings.ideal_bsdf;
  Rgb sum(0);
  for (uint32_t i = 0; i < n; ++i) {
    // The lobe's number rotated by the golden ratio, the direction's by a Hammersley point.
    const float x = u.u_lobe + 0.618034f * float(i);
    const float u_lobe = std::min(x - std::floor(x), 0x1.fffffep-1f);
    BsdfSample bs;
    // A Dirac lobe's emission is the path's own (it counts in full, nothing competed with it).
    if (!bsdf.sample(wo, u_lobe, rotated_hammersley(i, n, u.u_dir), bs) || bs.delta) continue;
    ++counters.bounce;
    Hit hit;
    if (!m_accel.intersect(spawn_ray(sh.p, sh.ng, bs.wi), hit)) continue;
    const SurfaceHit lh = make_surface_hit(c.scene.mesh, hit);
    if (lh.light < 0) continue;
    const Light& light = c.scene.lights[lh.light];
    const Rgb Le = emitted_radiance(c.scene, light, lh, -bs.wi);
    if (is_black(Le)) continue;
    const float light_pdf = light_pmf(m_view, ctx, uint32_t(lh.light)) * pdf_li(light, ctx.p, lh.p);
    sum += bs.f * Le *
           (absdot(bs.wi, bsdf.shading_normal()) / bs.pdf * power_heuristic(bs.pdf, light_pdf));
  }
  return sum / float(n);
}

Rgb Integrator::sample_light(const LightContext& ctx, const Bsdf& bsdf, const Vec3& wo, int depth,
                             const Rgb& beta, SampleStream& stream, RayCounters& counters,
                             CameraVertexSample* camera, PsfCut* split) const {
  Rgb sum(0);
  float pmf_sum = 0;
  int count = 0;
  draw_nee(m_constants, m_view, ctx, bsdf, wo, stream, depth, nullptr, [&](const NeeDraw& d) {
    NeeResult r;
    if (m_settings.ideal_point > 0) {
      // The draw's own point is the set's shift (the stream's numbers, by dimension).
      r = ideal_point_nee(d, ctx, bsdf, wo, beta, light_numbers(stream, depth).u_pos, counters);
    } else {
      if (d.setup.counts_shadow_ray) ++counters.shadow;
      const bool occluded = d.setup.traces && m_accel.occluded(d.setup.shadow);
      if (reaches_light(d.setup, occluded)) ++counters.shadow_visible;
      if (camera) {
        camera->shadow += d.setup.counts_shadow_ray;
        camera->visible += reaches_light(d.setup, occluded);
      }
      r = finish_nee_draw(m_constants, d, occluded, bsdf, wo, beta);
    }
    if (m_view.learns) record_nee(m_view, ctx, d.light, r.record);
    sum += split ? psf_split_nee(bsdf, wo, d.setup.wi, beta, r.value, *split) : r.value;
    pmf_sum += d.light.pmf;
    ++count;
  });
  if (camera && count > 0) {  // `probability`: the mean of its samples' pmfs
    camera->sampled = true;
    camera->light_pmf = pmf_sum / float(count);
  }
  return sum;
}

Rgb Integrator::li(const Ray& camera_ray, SampleStream& stream, RayCounters& counters,
                   CameraVertexSample* camera, PsfCut* cut) const {
  const PathConstants& c = m_constants;
  PathState s = start_path(c);
  Ray ray = camera_ray;
  ++counters.camera;
  for (int depth = 0;; ++depth) {
    Hit hit;
    if (!m_accel.intersect(ray, hit)) break;
    if (!hit_matters(c, hit, depth)) break;
    SurfaceHit sh = make_surface_hit(c.scene.mesh, hit);
    Vec3 wo = -ray.d;
    HitEmission e = hit_emission(c, s, sh, wo, depth);
    // rll.ideal_bsdf: the BSDF side of MIS was averaged at the vertex before (ideal_bsdf_side).
    if (e.needs_light_pmf && m_settings.ideal_bsdf > 0) e.counts = false;
    add_emission(c, s, sh, e,
                 e.needs_light_pmf ? light_pmf(m_view, s.prev_ctx, uint32_t(sh.light)) : 0.0f);
    if (depth >= c.max_depth) break;

    const BsdfNumbers u = bsdf_numbers(stream, depth);
    const Bsdf bsdf = make_vertex_bsdf(c, sh, wo, u, depth);
    if (bsdf.is_black()) break;
    LightContext ctx = make_vertex_context(c, s, sh, hit, wo, bsdf);
    PsfCut* split = nullptr;  // the cut at this vertex, where it splits its lobes (psf_splits)
    if (cut && cut->key == 0 && psf_cuts_here(c, s, bsdf, hit.t, depth)) {
      psf_cut(c, s, bsdf, *cut);
      if (psf_splits(c.psf, bsdf)) split = cut;
      cut->key = psf_cut_key(c, ctx, bsdf, wo,
                             psf_cut_footprint(ctx.footprint, hit.t, s.prev_dir_pdf, wo, sh.ng),
                             depth, stream);
    }
    const bool light = samples_light(c, bsdf);
    if (m_view.prepares && !bsdf.is_delta())
      prepare_point(m_view, ctx, vertex_number(stream, depth, kPrepare));
    CameraVertexSample* vertex = depth == 0 ? camera : nullptr;
    if (vertex) vertex->cell = ctx.cell;
    if (light)
      s.L += s.beta * sample_light(ctx, bsdf, wo, depth, s.beta, stream, counters, vertex, split);
    if (light && m_settings.ideal_bsdf > 0 && c.strategy == LightStrategy::Mis)
      s.L += s.beta * ideal_bsdf_side(ctx, bsdf, sh, wo, u, counters);
    if (!continues_after_light(c, bsdf, depth)) break;

    bool roulette = false;
    if (!sample_bounce(c, s, bsdf, ctx, sh, wo, u, depth, ray, roulette)) break;
    if (roulette && !survive(s, vertex_number(stream, depth, kRoulette))) break;
    if (split) psf_split_bounce(bsdf, wo, ray.d, s.L, *split);
    ++counters.bounce;
  }
  return s.L;
}

}  // namespace rll
