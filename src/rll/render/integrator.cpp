#include "rll/render/integrator.h"

#include <bit>

#include "rll/core/error.h"
#include "rll/core/hash.h"
#include "rll/core/params.h"
#include "rll/core/sampling.h"
#include "rll/scene/bsdf.h"
#include "rll/scene/interaction.h"

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

IntegratorSettings make_integrator_settings(const std::string& name, int max_depth,
                                            const Params& params) {
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
  return s;
}

// A shading point along a path.
struct Integrator::Vertex {
  LightContext ctx;
  Vec3 wo;
  const Bsdf* bsdf;
  int depth;
};

Integrator::Integrator(const Scene& scene, const Accel& accel, LightSampler& sampler,
                       IntegratorSettings settings)
    : m_scene(scene),
      m_accel(accel),
      m_sampler(sampler),
      m_settings(settings),
      m_learns(sampler.learns()),
      m_prepares(sampler.prepares()),
      m_data(scene),
      m_view(m_data.view()) {}

namespace {
// Each decision of a path has a fixed dimension of the sample: the pixel position takes the first
// two, then every vertex the next kVertexDims, so that with Sobol' points a decision is stratified
// over a pixel's samples whatever the earlier vertices drew (pairs drawn together are adjacent).
constexpr uint32_t kCameraDims = 2;
enum VertexDim : uint32_t {
  kLightChoice,
  kLightPoint,
  kLightPoint2,
  kLobe,
  kDirection,
  kDirection2,
  kPrepare,
  kRoulette,
  kVertexDims
};
inline void seek(SampleStream& stream, int depth, VertexDim d) {
  stream.seek(kCameraDims + uint32_t(depth) * kVertexDims + d);
}
}  // namespace

Rgb Integrator::sample_light(const Vertex& v, const Rgb& beta, SampleStream& stream,
                             RayCounters& counters, bool mis) const {
  seek(stream, v.depth, kLightChoice);
  double u_light = stream.next_double();
  Vec2 u_pos = stream.next2();
  SampledLight sl = m_sampler.sample(v.ctx, u_light);
  if (sl.pmf <= 0) return Rgb(0);
  const Light& light = m_view.lights[sl.light];
  LightLiSample ls = sample_li(light, v.ctx.p, u_pos);
  Rgb contribution(0), unoccluded(0);
  if (ls.pdf > 0) {
    Rgb f = v.bsdf->eval(v.wo, ls.wi) * absdot(ls.wi, v.bsdf->shading_normal());
    if (!is_black(f)) {
      unoccluded = f * ls.L / ls.pdf;
      Ray shadow;
      if (std::isfinite(ls.dist)) {
        Vec3 ny = light.type == LightType::Triangle ? light.n : Vec3(0);
        shadow = spawn_ray_to(v.ctx.p, v.bsdf->geometric_normal(), ls.point, ny);
      } else {  // a directional light: test the scene's bounding sphere only, never the sky dome
        shadow = spawn_ray(v.ctx.p, v.bsdf->geometric_normal(), ls.wi,
                           length(v.ctx.p - m_scene.bounds.center()) + 1.01f * m_scene.radius);
      }
      ++counters.shadow;
      if (!is_black(unoccluded) && !m_accel.occluded(shadow)) contribution = unoccluded;
    }
  }
  float w = 1;
  if (mis && !light.is_delta() && !is_black(contribution)) {
    float bsdf_pdf = v.bsdf->pdf(v.wo, ls.wi);
    w = power_heuristic(sl.pmf * ls.pdf, bsdf_pdf);
  }
  if (m_learns) {
    NeeRecord r;
    r.estimate = luminance(contribution);
    r.unoccluded = luminance(unoccluded);
    r.mis_weight = w;
    r.max_rgb = max_component(beta * contribution) * w;
    m_sampler.record(v.ctx, sl, r);
  }
  if (is_black(contribution)) return contribution;
  return contribution * (w / sl.pmf);
}

Rgb Integrator::li(const Ray& camera_ray, SampleStream& stream, RayCounters& counters) const {
  const LightStrategy strategy = m_settings.strategy;
  const bool mis = strategy == LightStrategy::Mis;
  const int max_depth = m_settings.type == IntegratorType::Direct ? 1 : m_settings.max_depth;
  const float pixel_angle = m_scene.camera.pixel_angle();

  Rgb L(0), beta(1);
  Ray ray = camera_ray;
  // Footprint: R_k = R_{k-1} + t / sqrt(p_prev |cos|), with the camera's p_prev = 1/pixel_angle^2.
  float footprint = 0, prev_dir_pdf = 1 / (pixel_angle * pixel_angle);
  LightContext prev_ctx;
  float prev_bsdf_pdf = 0;
  bool prev_delta = false;  // the last bounce was a Dirac lobe: no light sampling competed
  ++counters.camera;
  for (int depth = 0;; ++depth) {
    Hit hit;
    if (!m_accel.intersect(ray, hit)) break;
    // Past the last vertex a hit only matters if it is an emitter (MIS of the BSDF ray).
    if (depth >= max_depth && m_view.mesh.light[hit.tri] < 0) break;
    SurfaceHit sh = make_surface_hit(m_view.mesh, hit);
    Vec3 wo = -ray.d;

    if (sh.light >= 0) {
      Rgb Le = emitted_radiance(m_view.lights[sh.light], wo);
      if (!is_black(Le)) {
        if (depth == 0 || strategy == LightStrategy::Bsdf || prev_delta) {
          L += beta * Le;
        } else if (mis) {
          float light_pdf = m_sampler.pmf(prev_ctx, uint32_t(sh.light)) *
                            pdf_li(m_view.lights[sh.light], prev_ctx.p, sh.p);
          L += beta * Le * power_heuristic(prev_bsdf_pdf, light_pdf);
        }
      }
    }
    if (depth >= max_depth) break;

    const MaterialData& mat = m_view.materials[sh.material];
    // The BSDF's own numbers, drawn here (their values depend on the dimension only) so that
    // the walk of a stochastic BSDF (CoatedDiffuse) can be seeded from them.
    seek(stream, depth, kLobe);
    const float u_lobe = stream.next();
    const Vec2 u_dir = stream.next2();
    const uint64_t bsdf_seed =
        mix64(std::bit_cast<uint32_t>(u_lobe) | uint64_t(std::bit_cast<uint32_t>(u_dir.x)) << 32) ^
        mix64(std::bit_cast<uint32_t>(u_dir.y) + 0x9e3779b97f4a7c15ull * uint64_t(depth + 1));
    Bsdf bsdf(mat, albedo_at(m_view, sh), sh.ns, sh.ng, wo, roughness_at(m_view, sh), bsdf_seed);
    if (bsdf.is_black()) break;

    float cos_in = std::max(1e-2f, absdot(wo, sh.ng));
    footprint += hit.t / std::sqrt(prev_dir_pdf * cos_in);
    Vertex v;
    v.ctx.p = sh.p;
    v.ctx.n = bsdf.geometric_normal();
    v.ctx.ns = bsdf.shading_normal();
    v.ctx.wo = wo;
    v.ctx.glossy = mat.type != MaterialType::Diffuse;
    v.ctx.footprint = footprint;
    if (bsdf.has_transmission()) {
      // Light reaches a transmissive surface from both sides: no normal, so that no sampler
      // culls the lights behind it.
      v.ctx.n = Vec3(0);
      v.ctx.ns = Vec3(0);
    }
    v.wo = wo;
    v.bsdf = &bsdf;
    v.depth = depth;
    // A BSDF of Dirac lobes only (smooth glass, a thin pane) gets no light sample, as in pbrt-v4:
    // no shadow ray, no sampler record; the BSDF ray's light hit counts in full instead.
    const bool delta_only = bsdf.is_delta();
    if (m_prepares && !delta_only) {
      seek(stream, depth, kPrepare);
      m_sampler.prepare(v.ctx, stream.next());
    }

    if (strategy != LightStrategy::Bsdf && !delta_only)
      L += beta * sample_light(v, beta, stream, counters, mis);
    // The last vertex's BSDF ray only finds emission, which light sampling alone leaves out
    // (except through Dirac lobes, which light sampling never sees).
    const bool last = depth + 1 >= max_depth;
    if (last && strategy == LightStrategy::Nee && !bsdf.has_delta()) break;

    BsdfSample bs;
    if (!bsdf.sample(wo, u_lobe, u_dir, bs)) break;
    if (last && strategy == LightStrategy::Nee && !bs.delta) break;
    beta *= bs.f * (absdot(bs.wi, bsdf.shading_normal()) / bs.pdf);
    if (is_black(beta) || !is_finite(beta)) break;
    prev_ctx = v.ctx;
    prev_bsdf_pdf = bs.pdf;
    prev_delta = bs.delta;
    // A Dirac lobe does not widen the footprint: carry the previous density on.
    if (!bs.delta) prev_dir_pdf = bs.pdf;
    if (!last && depth + 1 >= m_settings.rr_depth) {
      float q = std::max(0.05f, 1 - max_component(beta));
      seek(stream, depth, kRoulette);
      if (stream.next() < q) break;
      beta /= 1 - q;
    }
    ray = spawn_ray(sh.p, sh.ng, bs.wi);
    ++counters.bounce;
  }
  return L;
}

}  // namespace rll
