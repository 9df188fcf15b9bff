// The work of one path vertex as RLL_HD functions over the scene's views and plain structs: the
// megakernel (Integrator::li) and the wavefront renderer (rll/wavefront) call the same ones, in the
// same order, so that they draw the same numbers and agree to the bit per path.
#pragma once

#include <bit>
#include <cmath>
#include <cstdint>

#include "rll/core/device.h"
#include "rll/core/hash.h"
#include "rll/core/rng.h"
#include "rll/core/sampling.h"
#include "rll/lights/light_context.h"
#include "rll/render/psf.h"
#include "rll/render/restir.h"
#include "rll/scene/bsdf.h"
#include "rll/scene/camera.h"
#include "rll/scene/interaction.h"
#include "rll/scene/scene_view.h"

namespace rll {

enum class IntegratorType { Direct, Path };
// Which estimators of direct light the path integrator combines (tests compare them).
enum class LightStrategy { Mis, Nee, Bsdf };

// Each decision of a path has a fixed dimension of the sample: the pixel position takes the first
// two, then every vertex the next kVertexDims, so that with Sobol' points a decision is stratified
// over a pixel's samples whatever the earlier vertices drew (pairs drawn together are adjacent).
inline constexpr uint32_t kCameraDims = 2;
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
RLL_HD inline uint32_t vertex_dimension(int depth, VertexDim d) {
  return kCameraDims + uint32_t(depth) * kVertexDims + d;
}
// The number of decision `d` at the vertex at `depth` (a learning sampler's prepare, Russian
// roulette): the stream continues at the decision's own dimension.
RLL_HD inline float vertex_number(SampleStream& stream, int depth, VertexDim d) {
  stream.seek(vertex_dimension(depth, d));
  return stream.next();
}

// The camera ray of pixel (x, y): a jitter inside the pixel, and a point on the lens drawn only for
// a thin lens, so that pinhole images keep their sample streams (and stay bit-identical).
RLL_HD inline Ray camera_ray(const Camera& camera, int x, int y, SampleStream& stream) {
  const Vec2 jitter = stream.next2();
  return camera.has_lens() ? camera.generate_ray(x + jitter.x, y + jitter.y, stream.next2())
                           : camera.generate_ray(x + jitter.x, y + jitter.y);
}

// The next-event sample's numbers: the light's choice (53 bits) and the point on it.
struct LightNumbers {
  double u_light = 0;
  Vec2 u_pos;
};
RLL_HD inline LightNumbers light_numbers(SampleStream& stream, int depth) {
  stream.seek(vertex_dimension(depth, kLightChoice));
  LightNumbers u;
  u.u_light = stream.next_double();
  u.u_pos = stream.next2();
  return u;
}

// What every vertex of every path of a render reads: the scene's views and the integrator's
// settings, flattened.
struct PathConstants {
  SceneView scene;
  Vec3 scene_center;  // of the scene's bounds: shadow rays to directional lights end past them
  float scene_radius = 1;
  float pixel_angle = 1;
  LightStrategy strategy = LightStrategy::Mis;
  int max_depth = 5;  // 1 for `direct`
  int rr_depth = 3;
  int nee_candidates = 1;  // resampled next-event estimation (docs/nee.md): 1 = one light sample
  bool nee_learnt_target = false;  // its target times the sampler's factor (nee_target)
  // nee.draw=cluster: candidates 1..M-1 come from candidate 0's cluster (sample_in_cluster)
  bool nee_cluster = false;
  CoatedWeights coated_weights = CoatedWeights::Unbiased;  // coated.weights (scene/bsdf.h)
  PsfConstants psf;        // path-space filtering (render/psf.h); off unless --filter psf
  RestirConstants restir;  // ReSTIR DI (render/restir.h); off unless a restir sampler renders
};

// What a path carries from one vertex to the next.
struct PathState {
  Rgb L{0}, beta{1};
  // Footprint: R_k = R_{k-1} + t / sqrt(p_prev |cos|), with the camera's p_prev = 1/pixel_angle^2.
  float footprint = 0, prev_dir_pdf = 1;
  LightContext prev_ctx;
  float prev_bsdf_pdf = 0;
  bool prev_delta = false;  // the last bounce was a Dirac lobe: no light sampling competed
};

RLL_HD inline PathState start_path(const PathConstants& c) {
  PathState s;
  s.prev_dir_pdf = 1 / (c.pixel_angle * c.pixel_angle);
  return s;
}

// Past the last vertex a hit only matters if it is an emitter (MIS of the BSDF ray).
RLL_HD inline bool hit_matters(const PathConstants& c, const Hit& hit, int depth) {
  return depth < c.max_depth || c.scene.mesh.light[hit.tri] >= 0;
}

// Emission found at a hit, before its MIS weight. `needs_light_pmf`: the caller asks the light
// sampler for pmf(prev_ctx, light) and passes it to add_emission; otherwise any pmf will do.
struct HitEmission {
  Rgb Le{0};
  bool counts = false;
  bool needs_light_pmf = false;
};

RLL_HD inline HitEmission hit_emission(const PathConstants& c, const PathState& s,
                                       const SurfaceHit& sh, const Vec3& wo, int depth) {
  HitEmission e;
  if (sh.light < 0) return e;
  e.Le = emitted_radiance(c.scene, c.scene.lights[sh.light], sh, wo);
  if (is_black(e.Le)) return e;
  if (depth == 0 || c.strategy == LightStrategy::Bsdf || s.prev_delta) {
    e.counts = true;
  } else if (c.strategy == LightStrategy::Mis) {
    e.counts = true;
    e.needs_light_pmf = true;
  }
  return e;
}

// Adds the emission to the path's radiance, MIS-weighted against light sampling at the previous
// vertex where it competed (`light_pmf`: the sampler's pmf of the light there).
RLL_HD inline void add_emission(const PathConstants& c, PathState& s, const SurfaceHit& sh,
                                const HitEmission& e, float light_pmf) {
  if (!e.counts) return;
  if (!e.needs_light_pmf) {
    s.L += s.beta * e.Le;
    return;
  }
  float light_pdf = light_pmf * pdf_li(c.scene.lights[sh.light], s.prev_ctx.p, sh.p);
  s.L += s.beta * e.Le * power_heuristic(s.prev_bsdf_pdf, light_pdf);
}

// The BSDF's own numbers, drawn at the vertex's dimensions (their values depend on the dimension
// only) so that the walk of a stochastic BSDF (CoatedDiffuse) can be seeded from them.
struct BsdfNumbers {
  float u_lobe = 0;
  Vec2 u_dir;
};
RLL_HD inline BsdfNumbers bsdf_numbers(SampleStream& stream, int depth) {
  stream.seek(vertex_dimension(depth, kLobe));
  BsdfNumbers u;
  u.u_lobe = stream.next();
  u.u_dir = stream.next2();
  return u;
}

RLL_HD inline Bsdf make_vertex_bsdf(const PathConstants& c, const SurfaceHit& sh, const Vec3& wo,
                                    const BsdfNumbers& u, int depth) {
  const uint64_t seed =
      mix64(std::bit_cast<uint32_t>(u.u_lobe) | uint64_t(std::bit_cast<uint32_t>(u.u_dir.x))
                                                    << 32) ^
      mix64(std::bit_cast<uint32_t>(u.u_dir.y) + 0x9e3779b97f4a7c15ull * uint64_t(depth + 1));
  return Bsdf(c.scene.materials[sh.material], albedo_at(c.scene, sh), sh.ns, sh.ng, wo,
              roughness_at(c.scene, sh), seed, c.coated_weights);
}

// Widens the footprint by the segment to this hit and returns the light sampler's context there.
RLL_HD inline LightContext make_vertex_context(const PathConstants& c, PathState& s,
                                               const SurfaceHit& sh, const Hit& hit, const Vec3& wo,
                                               const Bsdf& bsdf) {
  s.footprint = widen_footprint(s.footprint, hit.t, s.prev_dir_pdf, wo, sh.ng);
  LightContext ctx;
  ctx.p = sh.p;
  ctx.n = bsdf.geometric_normal();
  ctx.ns = bsdf.shading_normal();
  ctx.wo = wo;
  ctx.glossy = c.scene.materials[sh.material].type != MaterialType::Diffuse;
  ctx.footprint = s.footprint;
  if (bsdf.has_transmission()) {
    // Light reaches a transmissive surface from both sides: no normal, so that no sampler
    // culls the lights behind it.
    ctx.n = Vec3(0);
    ctx.ns = Vec3(0);
  }
  return ctx;
}

// A BSDF of Dirac lobes only (smooth glass, a thin pane) gets no light sample, as in pbrt-v4:
// no shadow ray, no sampler record; the BSDF ray's light hit counts in full instead.
RLL_HD inline bool samples_light(const PathConstants& c, const Bsdf& bsdf) {
  return c.strategy != LightStrategy::Bsdf && !bsdf.is_delta();
}

// A next-event sample after the light was chosen and a point on it drawn, before the shadow ray.
struct NeeSetup {
  Rgb unoccluded{0};  // f cos Le / pdf(y | light), as if nothing were in the way
  Vec3 wi;
  float light_pdf = 0;  // solid-angle pdf of the point given the light
  bool light_delta = false;
  bool counts_shadow_ray = false;  // the megakernel's ray counter counts it
  bool traces = false;             // the shadow ray must be traced (unoccluded is not black)
  Ray shadow;
};

// Whether a next-event sample's shadow ray reached its light: counted, traced and not occluded (a
// sample facing away from the point is never traced). RayCounters::shadow_visible counts these.
RLL_HD inline bool reaches_light(const NeeSetup& n, bool occluded) {
  return n.counts_shadow_ray && n.traces && !occluded;
}

RLL_HD inline NeeSetup nee_setup(const PathConstants& c, const LightContext& ctx, const Bsdf& bsdf,
                                 const Vec3& wo, uint32_t light_index, Vec2 u_pos) {
  NeeSetup n;
  const Light& light = c.scene.lights[light_index];
  n.light_delta = light.is_delta();
  LightLiSample ls = sample_li(c.scene, light, ctx.p, u_pos);
  n.light_pdf = ls.pdf;
  n.wi = ls.wi;
  if (!(ls.pdf > 0)) return n;
  Rgb f = bsdf.eval(wo, ls.wi) * absdot(ls.wi, bsdf.shading_normal());
  if (is_black(f)) return n;
  n.unoccluded = f * ls.L / ls.pdf;
  n.shadow = shadow_ray_to_light(ctx.p, bsdf.geometric_normal(), light, ls, c.scene_center,
                                 c.scene_radius);
  n.counts_shadow_ray = true;
  n.traces = !is_black(n.unoccluded);
  return n;
}

// The next-event sample after the shadow ray's verdict: its contribution (MIS-weighted when
// `mis`), already divided by the light pmf, before the path throughput, and what a learning
// sampler records of it.
struct NeeResult {
  Rgb value{0};
  NeeRecord record;
};

RLL_HD inline NeeResult nee_finish(const NeeSetup& n, bool occluded, const Bsdf& bsdf,
                                   const Vec3& wo, const Rgb& beta, float light_pmf, bool mis) {
  Rgb contribution(0);
  if (n.traces && !occluded) contribution = n.unoccluded;
  float w = 1;
  if (mis && !n.light_delta && !is_black(contribution)) {
    float bsdf_pdf = bsdf.pdf(wo, n.wi);
    w = power_heuristic(light_pmf * n.light_pdf, bsdf_pdf);
  }
  NeeResult r;
  r.record.estimate = luminance(contribution);
  r.record.unoccluded = luminance(n.unoccluded);
  r.record.mis_weight = w;
  r.record.max_rgb = max_component(beta * contribution) * w;
  r.value = is_black(contribution) ? contribution : contribution * (w / light_pmf);
  return r;
}

// Resampled next-event estimation (docs/nee.md): M candidates from the light sampler's own
// distribution, one kept by a weighted reservoir in proportion to its unshadowed contribution
// with the MIS weight folded in, one shadow ray for it.
inline constexpr int kMaxNeeCandidates = 64;
// Candidate 0 draws at the vertex's own light dimensions (so that M = 1 is one light sample as
// before, to the bit); candidates 1..M-1 each draw 4 numbers (light, point, keep) at dimensions
// of their own, far past any path's vertices (a Sobol' stream stratifies any dimension).
inline constexpr uint32_t kResampleBase = 1u << 24;
inline constexpr uint32_t kCandidateDims = 4;
RLL_HD inline uint32_t candidate_dimension(int depth, int candidate) {
  return kResampleBase + uint32_t(depth) * (kCandidateDims * (kMaxNeeCandidates - 1)) +
         kCandidateDims * uint32_t(candidate - 1);
}
struct CandidateNumbers {
  LightNumbers light;
  float u_keep = 0;  // the reservoir's draw: candidate 0 is kept whenever it weighs anything
};
RLL_HD inline CandidateNumbers candidate_numbers(SampleStream& stream, int depth, int candidate) {
  CandidateNumbers u;
  if (candidate == 0) {
    u.light = light_numbers(stream, depth);
    return u;
  }
  stream.seek(candidate_dimension(depth, candidate));
  u.light.u_light = stream.next_double();
  u.light.u_pos = stream.next2();
  u.u_keep = stream.next();
  return u;
}

// A candidate's resampling weight w = p_hat / q: the luminance of its unshadowed contribution
// f cos Le / pdf(y | light) with the light strategy's MIS weight (power heuristic of the source
// pdf pmf * pdf(y | light) against the BSDF's pdf), over its pmf.
RLL_HD inline float resample_weight(const NeeSetup& n, const Bsdf& bsdf, const Vec3& wo,
                                    float light_pmf, bool mis) {
  if (!n.traces) return 0;
  float m = 1;
  if (mis && !n.light_delta) m = power_heuristic(light_pmf * n.light_pdf, bsdf.pdf(wo, n.wi));
  const float w = luminance(n.unoccluded) * m / light_pmf;
  return w > 0 && std::isfinite(w) ? w : 0;
}

// What the reservoir kept: the candidate that gets the shadow ray, its weight and the sum of all
// weights. `light.pmf` is 0 where no candidate was drawn at all.
struct NeeChoice {
  NeeSetup setup;
  SampledLight light;
  float weight = 0;      // of the kept candidate (0: none weighs anything, nothing is traced)
  float weight_sum = 0;  // over all M candidates
};

// The number u in [0, 1) moved into stratum i of n: [i / n, (i + 1) / n).
RLL_HD inline double stratum(int i, int n, double u) {
  return std::min((double(i) + u) / double(n), 0x1.fffffffffffffp-1);
}

// Draws the M = c.nee_candidates candidates with `sample(u)` (the light sampler's
// sample(ctx, u)) and keeps one by streaming weighted reservoir sampling. With M = 1 the weight
// is not evaluated (it cancels): one light sample, as before resampling. With
// c.nee_learnt_target each weight is multiplied by `target(candidate)`, the sampler's learnt
// factor of the candidate (nee_target, lights/light_dispatch.h: the target p_hat times that
// factor; finish_nee_draw's ratio uses the same weights). With c.nee_cluster, candidates
// 1..M-1 are drawn by `in_cluster(kept, u)` from candidate 0's cluster (sample_in_cluster):
// given the cluster, all M are i.i.d. from the sampler's distribution over its lights, and each
// weight's pmf is the full one (the cluster's probability times the light's within it), so the
// ratio (sum w / M) / w_kept is that of resampling within the cluster (docs/nee.md).
template <class SampleLight, class InCluster, class Target>
RLL_HD inline NeeChoice resample_nee(const PathConstants& c, const LightContext& ctx,
                                     const Bsdf& bsdf, const Vec3& wo, SampleStream& stream,
                                     int depth, const SampleLight& sample,
                                     const InCluster& in_cluster, const Target& target) {
  NeeChoice ch;
  const bool mis = c.strategy == LightStrategy::Mis;
  for (int i = 0; i < c.nee_candidates; ++i) {
    const CandidateNumbers u = candidate_numbers(stream, depth, i);
    // From one cluster, the candidate kept so far stands for candidate 0 (the same record:
    // cluster, its probability, target; and pmf > 0): no copy of it is held (registers).
    const SampledLight sl =
        c.nee_cluster && i > 0
            ? in_cluster(ch.light, stratum(i - 1, c.nee_candidates - 1, u.light.u_light))
            : sample(u.light.u_light);
    if (!(sl.pmf > 0)) {
      if (c.nee_cluster && i == 0) break;  // no cluster to draw the others from
      continue;
    }
    const NeeSetup n = nee_setup(c, ctx, bsdf, wo, sl.light, u.light.u_pos);
    const float w = c.nee_candidates == 1 ? (n.traces ? 1.0f : 0.0f)
                    : c.nee_learnt_target ? resample_weight(n, bsdf, wo, sl.pmf, mis) * target(sl)
                                          : resample_weight(n, bsdf, wo, sl.pmf, mis);
    if (i == 0) {  // kept even at weight 0: a learning sampler records its zero
      ch.setup = n;
      ch.light = sl;
    }
    if (!(w > 0)) continue;
    ch.weight_sum += w;
    if (u.u_keep * ch.weight_sum < w) {
      ch.setup = n;
      ch.light = sl;
      ch.weight = w;
    }
  }
  if (!(ch.weight > 0)) ch.setup.traces = false;
  return ch;
}

// One next-event sample of a vertex as every sampler's draw yields it (render/nee_draw.h): the
// light sample before its shadow ray, the light with its pmf (the MIS weight's density), and the
// factor its contribution is scaled by after the shadow ray: resampled NEE's unbiased
// contribution weight's ratio (sum w / M) / w_kept, or rht's reservoirs' 1 / (P(first stage kept
// it) P(second stage kept it)); 1 for a plain light sample.
struct NeeDraw {
  NeeSetup setup;
  SampledLight light;
  float scale = 1;
};

// The last vertex's BSDF ray only finds emission, which light sampling alone leaves out (except
// through Dirac lobes, which light sampling never sees): false where the path ends before it.
RLL_HD inline bool continues_after_light(const PathConstants& c, const Bsdf& bsdf, int depth) {
  const bool last = depth + 1 >= c.max_depth;
  return !(last && c.strategy == LightStrategy::Nee && !bsdf.has_delta());
}

// Samples the BSDF, updates the throughput and what the next vertex needs of this one; false
// where the path ends. `roulette` tells whether Russian roulette is played next (survive()).
RLL_HD inline bool sample_bounce(const PathConstants& c, PathState& s, const Bsdf& bsdf,
                                 const LightContext& ctx, const SurfaceHit& sh, const Vec3& wo,
                                 const BsdfNumbers& u, int depth, Ray& next, bool& roulette) {
  const bool last = depth + 1 >= c.max_depth;
  BsdfSample bs;
  if (!bsdf.sample(wo, u.u_lobe, u.u_dir, bs)) return false;
  if (last && c.strategy == LightStrategy::Nee && !bs.delta) return false;
  s.beta *= bs.f * (absdot(bs.wi, bsdf.shading_normal()) / bs.pdf);
  if (is_black(s.beta) || !is_finite(s.beta)) return false;
  s.prev_ctx = ctx;
  s.prev_bsdf_pdf = bs.pdf;
  s.prev_delta = bs.delta;
  // A Dirac lobe does not widen the footprint: carry the previous density on.
  if (!bs.delta) s.prev_dir_pdf = bs.pdf;
  roulette = !last && depth + 1 >= c.rr_depth;
  next = spawn_ray(sh.p, sh.ng, bs.wi);
  return true;
}

// Path-space filtering (render/psf.h): whether a path not yet cut is cut at this vertex, reached
// by a segment of length t. As Fermat's psfpt: from vertex psf.depth on, where the bounce before
// was rough (sampled with a pdf below psf.max_prob: no Dirac lobe, no sharp glossy lobe; the
// camera's "bounce" to vertex 0 always counts as rough) and the segment at least psf.min_dist
// long; and (rll's) not at a vertex of Dirac lobes only, whose radiance is the one direction's,
// nor with psf.demodulate at one without a diffuse lobe (a conductor, rough glass: all glossy,
// which Fermat sends to the film; the path may be cut further along).
RLL_HD inline bool psf_cuts_here(const PathConstants& c, const PathState& s, const Bsdf& bsdf,
                                 float t, int depth) {
  const PsfConstants& f = c.psf;
  if (!f.on || depth < f.depth || bsdf.is_delta() || !(t >= f.min_dist)) return false;
  if (f.demodulate && bsdf.diffuse_part() == Bsdf::DiffusePart::None) return false;
  return depth == 0 || (!s.prev_delta && s.prev_bsdf_pdf < f.max_prob);
}

// Cuts the path at this vertex: its throughput and what it gathered so far, which the film takes
// unfiltered; what it gathers from here on is the radiance its cell averages (s.L starts again
// from 0). Its cell's key is psf_cut_key's, `pending` until then (the wavefront computes it in a
// later stage, where registers are to spare). Where the cut splits (psf_splits), its weight is the
// throughput times the diffuse albedo: the cell averages radiance divided by the albedo.
RLL_HD inline void psf_cut(const PathConstants& c, PathState& s, const Bsdf& bsdf, PsfCut& cut) {
  cut.key = kPsfKeyPending;
  cut.weight = psf_splits(c.psf, bsdf) ? s.beta * bsdf.diffuse_albedo() : s.beta;
  cut.before = s.L;
  s.L = Rgb(0);
}

// The footprint that sizes a cut's cell: Fermat's ray cone, whose spread at each bounce is that of
// a pdf of at least kPsfMinConePdf (about 10 degrees), where the footprint of rll's cells
// (`footprint`, widened by widen_footprint) takes the bounce's pdf as it is. At a cut the bounce
// before was rough (its pdf below psf.max_prob), so the two differ by that last segment's spread
// alone: a diffuse bounce widens rll's footprint by about t sqrt(pi / cos), ten times Fermat's
// cone, and cells that wide averaged the lit inside of a box with the dark room around it. The
// bounces before the cut's are taken as rll's: the same as Fermat's for a cut at depth 0 or 1
// (the default), and at deeper cuts wherever the bounces before were sharp (pdf 32 or more);
// rough bounces above psf.depth keep their wider spread there.
RLL_HD inline float psf_cut_footprint(float footprint, float t, float prev_dir_pdf, const Vec3& wo,
                                      const Vec3& ng) {
  // The segment's spread as widen_footprint added it, taken back, and added again capped.
  const float spread = widen_footprint(0.0f, t, prev_dir_pdf, wo, ng);
  return widen_footprint(std::max(footprint - spread, 0.0f), t,
                         std::max(prev_dir_pdf, float(kPsfMinConePdf)), wo, ng);
}

// The key of the cell of the path's cut at this vertex, jittered by numbers of its own;
// `footprint` is psf_cut_footprint's.
RLL_HD inline uint64_t psf_cut_key(const PathConstants& c, const LightContext& ctx,
                                   const Bsdf& bsdf, const Vec3& wo, float footprint, int depth,
                                   SampleStream& stream) {
  stream.seek(kPsfJitterDimension);
  float u[5];
  for (float& x : u) x = stream.next();
  return psf_key(c.psf, ctx.p, bsdf.shading_normal(), wo, footprint, depth, u);
}

// Russian roulette with the number drawn at the vertex's kRoulette dimension.
RLL_HD inline bool survive(PathState& s, float u) {
  float q = std::max(0.05f, 1 - max_component(s.beta));
  if (u < q) return false;
  s.beta /= 1 - q;
  return true;
}

}  // namespace rll
