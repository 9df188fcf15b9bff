// ReSTIR DI's steps (render/restir.h, docs/restir.md) as RLL_HD functions over the path constants
// and flat views: the candidates at the ReSTIR vertex, visibility, temporal and spatial reuse and
// the final shading, which wavefront/kernels.h runs on the CPU and cuda/wavefront.cu on the GPU.
#pragma once

#include <cmath>
#include <cstdint>

#include "rll/core/device.h"
#include "rll/core/rng.h"
#include "rll/core/sampling.h"
#include "rll/render/film.h"
#include "rll/render/path_vertex.h"
#include "rll/render/restir.h"

namespace rll {

// The point of sample y on a triangle light.
RLL_HD inline Vec3 restir_point(const Light& l, const RestirSample& y) {
  return l.p0 + (l.p1 - l.p0) * y.b1 + (l.p2 - l.p0) * y.b2;
}

// The sample of a point `point` drawn on light `index`: on a triangle its barycentrics.
RLL_HD inline RestirSample restir_sample_of(const Light& l, uint32_t index, const Vec3& point) {
  RestirSample y;
  y.light = index;
  if (l.type != LightType::Triangle) return y;
  const Vec3 e1 = l.p1 - l.p0, e2 = l.p2 - l.p0, d = point - l.p0;
  const float d11 = dot(e1, e1), d12 = dot(e1, e2), d22 = dot(e2, e2);
  const float d1 = dot(d, e1), d2 = dot(d, e2), den = d11 * d22 - d12 * d12;
  if (den > 0) {
    y.b1 = clamp((d22 * d1 - d12 * d2) / den, 0.0f, 1.0f);
    y.b2 = clamp((d11 * d2 - d12 * d1) / den, 0.0f, 1.0f - y.b1);
  }
  return y;
}

// Sample y seen from a receiver (point p, its Bsdf, wo): f * Le * |cos| * G, the unshadowed
// contribution in the area measure of the light (the measure every receiver shares; a point or
// directional light's is its own: G = 1, Le its intensity / d^2 or irradiance), its luminance
// p_hat (the target), the density in that measure with which the source's light draws the point
// from p (pdf_li times the Jacobian; 1 for a Dirac light), and the shadow ray.
struct RestirTarget {
  Rgb f{0};
  float p_hat = 0;
  float point_pdf = 0;
  Ray shadow;
};

RLL_HD inline RestirTarget restir_target(const PathConstants& c, const RestirSample& y,
                                         const Bsdf& bsdf, const Vec3& p, const Vec3& wo) {
  RestirTarget t;
  if (y.light == kRestirNoLight || y.light >= c.scene.lights.size) return t;
  const Light& light = c.scene.lights[y.light];
  LightLiSample ls;
  float G = 1, point_pdf = 1;
  if (light.type == LightType::Triangle) {
    if (!(light.area > 0)) return t;
    const Vec3 point = restir_point(light, y), d = point - p;
    const float d2 = length_sq(d);
    if (!(d2 > 0)) return t;
    ls.dist = std::sqrt(d2);
    ls.wi = d / ls.dist;
    ls.point = point;
    const float cos_l = std::abs(dot(light.n, ls.wi));
    ls.L = emitted_radiance(light, -ls.wi);
    if (light.textured && !is_black(ls.L))
      ls.L = emission_at(c.scene, c.scene.materials[c.scene.mesh.material[light.triangle]],
                         triangle_uv(c.scene.mesh, light.triangle, point));
    ls.pdf = 1;
    G = cos_l / d2;
    point_pdf = pdf_li(light, p, point) * G;
  } else {
    ls = sample_li(c.scene, light, p, Vec2{0.5f, 0.5f});  // (a Dirac light's own point)
  }
  if (!(ls.pdf > 0) || !(G > 0) || is_black(ls.L)) return t;
  const Rgb f = bsdf.eval(wo, ls.wi) * (absdot(ls.wi, bsdf.shading_normal()) * G) * ls.L;
  const float p_hat = luminance(f);
  if (!(p_hat > 0) || !std::isfinite(p_hat)) return t;
  t.f = f;
  t.p_hat = p_hat;
  t.point_pdf = point_pdf;
  t.shadow =
      shadow_ray_to_light(p, bsdf.geometric_normal(), light, ls, c.scene_center, c.scene_radius);
  return t;
}

// Streams one weighted sample into reservoir r (weighted reservoir sampling with number u);
// true where it became the kept one.
RLL_HD inline bool restir_stream(Reservoir& r, const RestirSample& y, float p_hat, float w,
                                 float u) {
  if (!(w > 0) || !std::isfinite(w)) return false;
  r.w_sum += w;
  if (u * r.w_sum >= w) return false;
  r.y = y;
  r.p_hat = p_hat;
  return true;
}

// The unbiased contribution weight W = w_sum / (Z p_hat), 0 where nothing is kept.
RLL_HD inline float restir_weight(const Reservoir& r, float Z) {
  if (!(r.p_hat > 0) || !(Z > 0) || !(r.w_sum > 0)) return 0;
  const float W = r.w_sum / (Z * r.p_hat);
  return std::isfinite(W) ? W : 0;
}

// The initial reservoir at the ReSTIR vertex: M candidates drawn by `sample(u)` (the source's
// sample_light at the vertex's light context), each with resampling weight
// w = p_hat / (pmf x point_pdf), the target over the candidate's density in the area measure
// (= luminance of the unshadowed f Le cos / pdf(y | light), over the pmf: resampled NEE's
// resample_weight without MIS). Numbers from the pixel's stream at kRestirBase.
struct RestirDraw {
  Reservoir r;
  RestirKept kept;
};
template <class SampleLight>
RLL_HD inline RestirDraw restir_candidates(const PathConstants& c, const LightContext& ctx,
                                           const Bsdf& bsdf, const Rgb& beta, SampleStream& stream,
                                           const SampleLight& sample) {
  RestirDraw d;
  Reservoir& r = d.r;
  for (int i = 0; i < c.restir.candidates; ++i) {
    stream.seek(kRestirBase + kRestirCandidateDims * uint32_t(i));
    const double u_light = stream.next_double();
    const Vec2 u_pos = stream.next2();
    const float u_keep = stream.next();
    r.M += 1;
    const SampledLight sl = sample(u_light);
    if (!(sl.pmf > 0)) continue;
    const Light& light = c.scene.lights[sl.light];
    const LightLiSample ls = sample_li(c.scene, light, ctx.p, u_pos);
    if (!(ls.pdf > 0)) continue;
    const RestirSample y = restir_sample_of(light, sl.light, ls.point);
    const RestirTarget t = restir_target(c, y, bsdf, ctx.p, ctx.wo);
    if (!(t.p_hat > 0 && t.point_pdf > 0)) continue;
    const float q = sl.pmf * t.point_pdf;
    if (restir_stream(r, y, t.p_hat, t.p_hat / q, u_keep)) {
      d.kept.light = sl;
      d.kept.record.unoccluded = t.p_hat / t.point_pdf;  // luminance(f Le cos / pdf(y | light))
      d.kept.record.estimate = d.kept.record.unoccluded;
      d.kept.record.mis_weight = 1;
      d.kept.record.max_rgb = max_component(beta * t.f) / t.point_pdf;
    }
  }
  r.W = restir_weight(r, r.M);
  return d;
}

// Whether two ReSTIR vertices are alike enough to reuse each other's reservoirs: normals within
// restir.normal, distances to the camera within restir.depth of the receiver's.
RLL_HD inline bool restir_similar(const RestirConstants& k, const RestirVertex& a,
                                  const RestirVertex& b) {
  if (!a.valid || !b.valid) return false;
  if (dot(a.ctx.ns, b.ctx.ns) < k.cos_normal && length_sq(a.ctx.ns) > 0) return false;
  return std::abs(a.depth - b.depth) <= k.depth * a.depth;
}

// The pixel (x, y) where world point p lies in `camera`'s film of width x height; false outside.
RLL_HD inline bool restir_reproject(const Camera& camera, const Vec3& p, int width, int height,
                                    uint64_t& pixel) {
  float x = 0, y = 0;
  if (!camera.raster(p, x, y)) return false;
  if (!(x >= 0 && y >= 0 && x < float(width) && y < float(height))) return false;
  pixel = uint64_t(int(y)) * uint64_t(width) + uint64_t(int(x));
  return true;
}

// Reservoir `from` (of a domain whose vertex record is `v` with its Bsdf), combined into `n` at
// the receiver (vertex `at` with `bsdf`): its weight p_hat_at(y) W M (Bitterli 2020's Alg. 4/6).
RLL_HD inline void restir_combine(const PathConstants& c, Reservoir& n, const Reservoir& from,
                                  float M, const RestirVertex& at, const Bsdf& bsdf, float u) {
  n.M += M;
  if (!(from.W > 0)) return;
  const RestirTarget t = restir_target(c, from.y, bsdf, at.ctx.p, at.ctx.wo);
  restir_stream(n, from.y, t.p_hat, t.p_hat * from.W * M, u);
}

// Alg. 6's Z for sample y: the M of each domain i (domain(i, vertex, Bsdf, M); false: none; i = 0
// the receiver's own) whose surface could have drawn y, its target with visibility (a shadow ray
// from that surface, counted in `rays`). A receiver that does not see y gets Z = 0 (W = 0, as
// visibility reuse's: every reservoir reused later then covers its own sample, which Z counts
// on). One call of the tracer in one loop, so that the GPU keeps one traversal stack in the
// frame (tests/unit/kernel_budgets.h).
template <class Tracer, class Domain>
RLL_HD inline float restir_z(const PathConstants& c, const Tracer& tracer, const RestirSample& y,
                             int domains, const Domain& domain, uint64_t& rays) {
  float Z = 0;
  for (int i = 0; i < domains; ++i) {
    const RestirVertex* v = nullptr;
    const Bsdf* bsdf = nullptr;
    float M = 0;
    if (!domain(i, v, bsdf, M)) continue;
    const RestirTarget t = restir_target(c, y, *bsdf, v->ctx.p, v->ctx.wo);
    const bool seen = t.p_hat > 0 && (++rays, !tracer.shadow(t.shadow));
    if (seen)
      Z += M;
    else if (i == 0)
      return 0;
  }
  return Z;
}

// The pixel's stream, keyed by (pixel, sample), at dimension `dim`.
template <class Sobol>
RLL_HD inline SampleStream restir_stream_at(const Sobol& sobol, const RestirBuffers& b,
                                            uint64_t pixel, uint32_t dim) {
  SampleStream s(sobol, b.frame_seed, pixel, b.sample, b.points);
  s.seek(dim);
  return s;
}

// Visibility reuse: the initial reservoir's kept sample gets its shadow ray; occluded: W = 0. A
// learning source records the kept candidate with the ray's verdict (as resampled NEE does).
// Returns the rays traced (0 or 1) and sets `visible`.
template <class Tracer>
RLL_HD inline uint64_t restir_visibility(const PathConstants& c, const Tracer& tracer,
                                         const RestirBuffers& b, uint64_t pixel, bool& visible,
                                         NeeRecord& record) {
  visible = false;
  const RestirVertex& v = b.vertex[pixel];
  if (!v.valid) return 0;
  Reservoir& r = b.reservoir[pixel];
  record = b.kept[pixel].record;
  if (!(r.W > 0)) return 0;
  const RestirTarget t = restir_target(c, r.y, b.bsdf[pixel], v.ctx.p, v.ctx.wo);
  visible = t.p_hat > 0 && !tracer.shadow(t.shadow);
  if (!visible) {
    r.W = 0;
    record.estimate = 0;
    record.max_rgb = 0;
  }
  return 1;
}

// Temporal reuse: the pixel's reservoir and the sample before's at the pixel where the vertex
// reprojects (by the camera of the sample before), where the two vertices are alike; the one
// before's M capped at history x candidates. Returns the shadow rays traced.
template <class Tracer, class Sobol>
RLL_HD inline uint64_t restir_temporal(const PathConstants& c, const Tracer& tracer,
                                       const Sobol& sobol, const RestirBuffers& b, uint64_t pixel) {
  const RestirConstants& k = c.restir;
  const RestirVertex& v = b.vertex[pixel];
  if (!k.temporal || !b.has_prev || !v.valid) return 0;
  uint64_t q = 0;
  if (!restir_reproject(b.prev_camera, v.ctx.p, b.width, b.height, q)) return 0;
  const RestirVertex& pv = b.prev_vertex[q];
  if (!restir_similar(k, v, pv)) return 0;
  const Reservoir own = b.reservoir[pixel];
  const Reservoir prev = b.prev_final[q];
  const float prev_M = prev.M < k.history_cap ? prev.M : k.history_cap;
  SampleStream u = restir_stream_at(sobol, b, pixel, kRestirTemporalDim);
  Reservoir n;
  restir_combine(c, n, own, own.M, v, b.bsdf[pixel], 0.0f);  // (the first weighted is kept)
  restir_combine(c, n, prev, prev_M, v, b.bsdf[pixel], u.next());
  uint64_t rays = 0;
  float Z = n.M;
  if (k.unbiased && n.p_hat > 0)
    Z = restir_z(
        c, tracer, n.y, 2,
        [&](int i, const RestirVertex*& dv, const Bsdf*& db, float& M) {
          dv = i == 0 ? &v : &pv;
          db = i == 0 ? &b.bsdf[pixel] : &b.prev_bsdf[q];
          M = i == 0 ? own.M : prev_M;
          return true;
        },
        rays);
  n.W = restir_weight(n, Z);
  b.reservoir[pixel] = n;
  return rays;
}

// Spatial reuse's neighbour j of the pixel: a pixel drawn in a disk of restir.radius pixels with
// the numbers at its own dimensions (3 each: the offset, the keep), so that Alg. 6's Z draws the
// same neighbours again rather than keep a list in the GPU's stack frame; false where it is off
// the film, the pixel itself or not alike.
template <class Sobol>
RLL_HD inline bool restir_neighbour(const RestirConstants& k, const Sobol& sobol,
                                    const RestirBuffers& b, uint64_t pixel, int j, uint32_t& q,
                                    float& u_keep) {
  SampleStream u = restir_stream_at(sobol, b, pixel, kRestirSpatialBase + 3 * uint32_t(j));
  const Vec2 d = sample_uniform_disk_concentric(u.next2());
  u_keep = u.next();
  const int px = int(pixel % uint64_t(b.width)), py = int(pixel / uint64_t(b.width));
  const int qx = px + int(std::floor(d.x * k.radius + 0.5f));
  const int qy = py + int(std::floor(d.y * k.radius + 0.5f));
  if (qx < 0 || qy < 0 || qx >= b.width || qy >= b.height || (qx == px && qy == py)) return false;
  q = uint32_t(qy) * uint32_t(b.width) + uint32_t(qx);
  return restir_similar(k, b.vertex[pixel], b.vertex[q]);
}

// Spatial reuse: up to restir.spatial neighbours (restir_neighbour), those alike the pixel's
// vertex combined with its own (read from the sample's reservoirs, written to the final ones,
// so that no pixel reads one being written). Returns the shadow rays traced.
template <class Tracer, class Sobol>
RLL_HD inline uint64_t restir_spatial(const PathConstants& c, const Tracer& tracer,
                                      const Sobol& sobol, const RestirBuffers& b, uint64_t pixel) {
  const RestirConstants& k = c.restir;
  const RestirVertex& v = b.vertex[pixel];
  const Reservoir own = b.reservoir[pixel];
  if (!v.valid || k.spatial <= 0) {
    b.final_[pixel] = own;
    return 0;
  }
  Reservoir n;
  restir_combine(c, n, own, own.M, v, b.bsdf[pixel], 0.0f);
  for (int j = 0; j < k.spatial; ++j) {
    uint32_t q = 0;
    float u_keep = 0;
    if (!restir_neighbour(k, sobol, b, pixel, j, q, u_keep)) continue;
    const Reservoir& r = b.reservoir[q];
    restir_combine(c, n, r, r.M, v, b.bsdf[pixel], u_keep);
  }
  uint64_t rays = 0;
  float Z = n.M;
  if (k.unbiased && n.p_hat > 0)
    Z = restir_z(
        c, tracer, n.y, 1 + k.spatial,
        [&](int i, const RestirVertex*& dv, const Bsdf*& db, float& M) {
          uint32_t q = uint32_t(pixel);
          float u_keep = 0;
          if (i > 0 && !restir_neighbour(k, sobol, b, pixel, i - 1, q, u_keep)) return false;
          dv = &b.vertex[q];
          db = &b.bsdf[q];
          M = b.reservoir[q].M;
          return true;
        },
        rays);
  n.W = restir_weight(n, Z);
  b.final_[pixel] = n;
  return rays;
}

// The pixel's film sample: what the rest of its path brought back plus the ReSTIR vertex's
// throughput x f Le G V W of its final reservoir (one more shadow ray). `shadow` and `visible`
// count the ray; false where the sample was not finite (the film gets 0, as every renderer's).
template <class Tracer>
RLL_HD inline bool restir_shade(const PathConstants& c, const Tracer& tracer,
                                const RestirBuffers& b, const FilmView& film, uint64_t pixel,
                                uint64_t& shadow, uint64_t& visible) {
  const RestirPixel& px = b.pixel[pixel];
  if (!px.reached) return true;
  Rgb L = px.L;
  const RestirVertex& v = b.vertex[pixel];
  Reservoir& r = b.final_[pixel];
  if (v.valid && r.W > 0) {
    const RestirTarget t = restir_target(c, r.y, b.bsdf[pixel], v.ctx.p, v.ctx.wo);
    if (t.p_hat > 0) ++shadow;
    if (t.p_hat > 0 && !tracer.shadow(t.shadow)) {
      ++visible;
      L += v.beta * t.f * r.W;
    } else {
      // The next sample reuses it with W = 0 where it is not seen (its target p_hat V): with
      // Alg. 6's Z, a reused reservoir whose own surface does not see its sample would count
      // none of its M (a firefly, and a bias).
      r.W = 0;
    }
  }
  const bool finite = is_finite(L);
  film.add(size_t(pixel), finite ? L : Rgb(0));
  return finite;
}

// The emission a BSDF ray that left the ReSTIR vertex finds: ReSTIR owns the direct light there
// (as Bitterli 2020), so emission its source could have drawn (pmf > 0) weighs 0, and the rest
// (a light the source never draws) counts in full.
RLL_HD inline void restir_after_vertex(HitEmission& e, float light_pmf) {
  if (!e.needs_light_pmf) return;
  if (light_pmf > 0)
    e.counts = false;
  else
    e.needs_light_pmf = false;
}

}  // namespace rll
