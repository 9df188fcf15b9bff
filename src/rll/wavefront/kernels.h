// The wavefront renderer's stages as RLL_HD kernel bodies over flat data (DESIGN 6): each stage is
// one function of a slot (or a pixel), reading and writing the structure-of-arrays path state and
// pushing slots onto the next stage's queue. The CPU runs them through host_parallel_for
// (wavefront/driver.h with the host backend), a GPU through CUDA launches (cuda/wavefront.cu):
// the same functions. They call the megakernel's per-vertex functions (render/path_vertex.h) in
// the megakernel's order, so a path's radiance is the same to the bit on the CPU.
#pragma once

#include <cstdint>

#include "rll/bvh/traverse.h"
#include "rll/core/device.h"
#include "rll/core/rng.h"
#include "rll/core/sobol.h"
#include "rll/lights/light_dispatch.h"
#include "rll/render/film.h"
#include "rll/render/nee_draw.h"
#include "rll/render/path_vertex.h"
#include "rll/render/restir_pixel.h"
#include "rll/scene/camera.h"
#include "rll/wavefront/stages.h"

namespace rll {

// Path slots pushed by many threads at once; their order varies, what each slot holds does not.
struct WavefrontQueue {
  View<uint32_t> slots;
  uint32_t* size = nullptr;  // in the slot memory, so that the queue copies into a kernel by value
  RLL_HD void push(uint32_t slot) const { slots[atomic_add(size, 1u)] = slot; }
  RLL_HD uint32_t count() const { return atomic_load(size); }
};

// The queues of a bounce. Their sizes live in device memory, in two blocks of kWavefrontQueues
// words: the bounce's (its kNextRays word unused) and the next bounce's, whose kRays word is this
// bounce's kNextRays. The blocks change places every bounce, so that no size is copied or read
// between bounces: each bounce only clears the next one's block, and each stage is launched over
// the queue's capacity, its threads past the size returning at once.
enum WavefrontQueueId : uint32_t {
  kRays,
  kNextRays,
  kHits,
  kNee,
  kShadows,
  kBounces,
  kRestir,  // the paths at their ReSTIR vertex (render/restir.h; empty unless a restir sampler)
  kWavefrontQueues
};

// The state of the paths in flight, one element per slot in each array, but the next-event
// samples': `draws` per slot (nee_draws_per_vertex), sample j of slot i at i * draws + j.
struct PathSlots {
  View<SampleStream> stream;
  View<Ray> ray;
  View<Hit> hit;
  View<int> depth;
  // PathState, field by field.
  View<Rgb> L, beta;
  View<float> footprint, prev_dir_pdf, prev_bsdf_pdf;
  View<uint8_t> prev_delta;
  View<LightContext> prev_ctx;
  // The current vertex.
  View<SurfaceHit> surface;
  View<BsdfNumbers> numbers;
  View<Bsdf> bsdf;
  View<LightContext> ctx;
  // Its next-event samples (draw_nee): how many, and each one's.
  View<uint8_t> draws;
  View<SampledLight> light;
  View<NeeSetup> nee;
  View<float> scale;  // NeeDraw::scale
  View<uint8_t> occluded;
  View<NeeRecord> record;
  // rht's reservoirs (draws_several: render/rht_nee.h), one set per slot; none for other samplers.
  View<RhtReservoirMemory> rht;
  // Path-space filtering (render/psf.h): each path's cut; none unless the render filters.
  View<PsfCut> cut;
  // ReSTIR (render/restir.h): 0 before the path's ReSTIR vertex, 1 from it to the next vertex
  // (whose emission the BSDF ray found: restir_after_vertex), 2 after; none without ReSTIR.
  View<uint8_t> restir;

  // Takes every array from `take(count, tag)`, a function of the memory that holds them (host or
  // device) called as take.template operator()<T>(n); `draws` next-event samples per slot; the
  // cuts where `filters`; rht's reservoirs where `reservoirs`.
  template <typename Take>
  static PathSlots make(Take& take, size_t n, size_t draws, bool filters = false,
                        bool restir = false, bool reservoirs = false) {
    PathSlots p;
    p.stream = take.template operator()<SampleStream>(n);
    p.ray = take.template operator()<Ray>(n);
    p.hit = take.template operator()<Hit>(n);
    p.depth = take.template operator()<int>(n);
    p.L = take.template operator()<Rgb>(n);
    p.beta = take.template operator()<Rgb>(n);
    p.footprint = take.template operator()<float>(n);
    p.prev_dir_pdf = take.template operator()<float>(n);
    p.prev_bsdf_pdf = take.template operator()<float>(n);
    p.prev_delta = take.template operator()<uint8_t>(n);
    p.prev_ctx = take.template operator()<LightContext>(n);
    p.surface = take.template operator()<SurfaceHit>(n);
    p.numbers = take.template operator()<BsdfNumbers>(n);
    p.bsdf = take.template operator()<Bsdf>(n);
    p.ctx = take.template operator()<LightContext>(n);
    p.draws = take.template operator()<uint8_t>(n);
    p.light = take.template operator()<SampledLight>(n * draws);
    p.nee = take.template operator()<NeeSetup>(n * draws);
    p.scale = take.template operator()<float>(n * draws);
    p.occluded = take.template operator()<uint8_t>(n * draws);
    p.record = take.template operator()<NeeRecord>(n * draws);
    if (filters) p.cut = take.template operator()<PsfCut>(n);
    if (restir) p.restir = take.template operator()<uint8_t>(n);
    if (reservoirs) p.rht = take.template operator()<RhtReservoirMemory>(n);
    return p;
  }

  RLL_HD PathState load(uint32_t i) const {
    PathState s;
    s.L = L[i];
    s.beta = beta[i];
    s.footprint = footprint[i];
    s.prev_dir_pdf = prev_dir_pdf[i];
    s.prev_bsdf_pdf = prev_bsdf_pdf[i];
    s.prev_delta = prev_delta[i] != 0;
    s.prev_ctx = prev_ctx[i];
    return s;
  }
  RLL_HD void store(uint32_t i, const PathState& s) const {
    L[i] = s.L;
    beta[i] = s.beta;
    footprint[i] = s.footprint;
    prev_dir_pdf[i] = s.prev_dir_pdf;
    prev_bsdf_pdf[i] = s.prev_bsdf_pdf;
    prev_delta[i] = s.prev_delta;
    prev_ctx[i] = s.prev_ctx;
  }
};

// Counts of a batch, added to by the stages with integer atomics.
struct WavefrontTally {
  uint64_t bounce = 0, shadow = 0, shadow_visible = 0, nonfinite = 0;
  PsfCounts filter;  // path-space filtering's batches, cells and cut paths
};

// The batch of paths a launch works on: items [first_item, first_item + n) of a pass, item k being
// sample first_sample + (k % count) of pixel k / count (each pixel's samples in order).
struct WavefrontBatch {
  uint64_t first_item = 0;
  uint32_t n = 0;
  int count = 1;            // samples per pixel in this pass
  int first = 0;            // the pass's first sample of each pixel
  uint64_t frame_seed = 0;  // as run_passes derives it
  uint64_t first_sample = 0;
  PointSet points = PointSet::Sobol;

  RLL_HD uint64_t pixel_of(uint32_t slot) const { return (first_item + slot) / uint64_t(count); }
  // The pixels the batch touches: [first_pixel(), first_pixel() + pixels()).
  RLL_HD uint64_t first_pixel() const { return first_item / uint64_t(count); }
  RLL_HD uint64_t pixels() const { return n == 0 ? 0 : pixel_of(n - 1) - first_pixel() + 1; }
};

// Tracing by rll's own BVH (bvh/traverse.h): what a GPU runs, and what the CPU can run to test it.
struct BvhTracer {
  BvhView bvh;
  RLL_HD bool closest(const Ray& ray, Hit& hit) const { return intersect(bvh, ray, hit); }
  RLL_HD bool shadow(const Ray& ray) const { return occluded(bvh, ray); }
};

// Everything a stage reads, by value into every launch: the scene and integrator (PathConstants),
// the camera, the Sobol' tables, a tracer, the light sampler's view (lights/light_dispatch.h, in
// the memory of the device that runs the stages), the path slots, the queues, the tally and the
// film. Tracer is the CPU's or the device's (AccelTracer, BvhTracer).
template <typename Tracer>
struct WavefrontKernels {
  PathConstants c;
  Camera camera;
  SobolView sobol;
  Tracer tracer;
  SamplerView sampler;
  PathSlots p;
  uint32_t draws = 1;  // next-event samples per slot (nee_draws_per_vertex)
  View<uint32_t> queue_slots[kWavefrontQueues];  // kShadows holds sample indices
  uint32_t* queue_sizes = nullptr;               // this bounce's block (kWavefrontQueues words)
  uint32_t* next_queue_sizes = nullptr;          // the next bounce's
  WavefrontTally* tally = nullptr;               // the pass's counts, summed over its batches
  FilmView film;
  // Path-space filtering (render/psf.h; c.psf.on): the batch's cells, and a record per pixel.
  PsfTableView psf_table;
  View<PsfRecord> psf_records;
  PsfTableView psf_last;  // temporal reuse: the last sample's cells, where this one blends them
  // ReSTIR (render/restir.h; c.restir.on): the sample's per-pixel arrays, and the batch's first
  // item (its pixel: a ReSTIR render's batches hold one sample of each pixel).
  RestirBuffers restir;
  uint64_t batch_first = 0;

  RLL_HD WavefrontQueue queue(WavefrontQueueId q) const {
    return {queue_slots[q], q == kNextRays ? &next_queue_sizes[kRays] : &queue_sizes[q]};
  }

  // Camera rays: slot i starts item first_item + i and joins the ray queue (in slot order; the
  // queue's size is the batch's, written by the first slot so that the host writes nothing).
  RLL_HD void camera_stage(const WavefrontBatch& b, uint32_t i) const {
    if (i == 0) queue_sizes[kRays] = b.n;
    const uint64_t item = b.first_item + i, pixel = item / uint64_t(b.count);
    const int s = b.first + int(item % uint64_t(b.count));
    SampleStream stream(sobol, b.frame_seed, pixel, b.first_sample + uint64_t(s), b.points);
    const uint64_t width = uint64_t(film.width);
    p.ray[i] = camera_ray(camera, int(pixel % width), int(pixel / width), stream);
    p.stream[i] = stream;
    p.depth[i] = 0;
    p.store(i, start_path(c));
    if (c.psf.on) p.cut[i] = PsfCut{};
    if (c.restir.on) p.restir[i] = 0;
    queue_slots[kRays][i] = i;
  }

  // Closest hit of each ray; hits that matter join the hit queue.
  RLL_HD void closest_hit_stage(uint32_t i) const {
    Hit hit;
    if (!tracer.closest(p.ray[i], hit) || !hit_matters(c, hit, p.depth[i])) return;
    p.hit[i] = hit;
    queue(kHits).push(i);
  }

  // Emission and its MIS weight at the hit; the vertex's BSDF and light context.
  RLL_HD void emission_stage(uint32_t i) const {
    PathState s = p.load(i);
    const int depth = p.depth[i];
    const SurfaceHit sh = make_surface_hit(c.scene.mesh, p.hit[i]);
    const Vec3 wo = -p.ray[i].d;
    HitEmission e = hit_emission(c, s, sh, wo, depth);
    const float pmf = e.needs_light_pmf ? light_pmf(sampler, s.prev_ctx, uint32_t(sh.light)) : 0.0f;
    if (c.restir.on && p.restir[i] == 1) {  // the BSDF ray that left the ReSTIR vertex
      restir_after_vertex(e, pmf);
      p.restir[i] = 2;
    }
    add_emission(c, s, sh, e, pmf);
    if (depth >= c.max_depth) return p.store(i, s);
    SampleStream& stream = p.stream[i];
    const BsdfNumbers u = bsdf_numbers(stream, depth);
    const Bsdf* bsdf = new (&p.bsdf[i]) Bsdf(make_vertex_bsdf(c, sh, wo, u, depth));
    if (bsdf->is_black()) return p.store(i, s);
    LightContext ctx = make_vertex_context(c, s, sh, p.hit[i], wo, *bsdf);
    // (The cut's key is the BSDF sampling stage's: this stage is the one short of registers.)
    if (c.psf.on && p.cut[i].key == 0 && psf_cuts_here(c, s, *bsdf, p.hit[i].t, depth))
      psf_cut(c, s, *bsdf, p.cut[i]);
    if (sampler.prepares && !bsdf->is_delta())
      prepare_point(sampler, ctx, vertex_number(stream, depth, kPrepare));
    p.store(i, s);
    p.surface[i] = sh;
    p.numbers[i] = u;
    p.ctx[i] = ctx;
    if (samples_light(c, *bsdf)) {
      if (c.restir.on && p.restir[i] == 0) {  // the path's ReSTIR vertex: no next-event sample
        p.restir[i] = 1;
        queue(kRestir).push(i);
      } else {
        queue(kNee).push(i);
      }
    }
    queue(kBounces).push(i);
  }

  // Next-event estimation: the vertex's samples (draw_nee: one, resampled with nee.candidates > 1,
  // or a multi-sample sampler's several), each's light, point and unoccluded contribution; those
  // that trace join the shadow queue.
  RLL_HD void nee_sample_stage(uint32_t i) const {
    const LightContext& ctx = p.ctx[i];
    uint32_t n = 0;
    draw_nee(c, sampler, ctx, p.bsdf[i], -p.ray[i].d, p.stream[i], p.depth[i],
             p.rht.size > 0 ? &p.rht[i] : nullptr, [&](const NeeDraw& d) {
               const uint32_t j = i * draws + n++;
               p.light[j] = d.light;
               p.nee[j] = d.setup;
               p.scale[j] = d.scale;
               p.occluded[j] = 0;
               if (d.setup.counts_shadow_ray) atomic_add(&tally->shadow, uint64_t(1));
               if (d.setup.traces) queue(kShadows).push(j);
             });
    p.draws[i] = uint8_t(n);
  }

  // ReSTIR's candidates at the path's ReSTIR vertex (slot i holds the batch's pixel
  // batch_first + i): the pixel's initial reservoir, its vertex record and Bsdf.
  RLL_HD void restir_candidates_stage(uint32_t i) const {
    const uint64_t pixel = batch_first + i;
    const LightContext& ctx = p.ctx[i];
    const Bsdf& bsdf = p.bsdf[i];
    SampleStream stream = p.stream[i];  // (a copy: the path's own numbers stay where they are)
    const RestirDraw d = restir_candidates(c, ctx, bsdf, p.beta[i], stream,
                                           [&](double u) { return sample_light(sampler, ctx, u); });
    restir.reservoir[pixel] = d.r;
    restir.kept[pixel] = d.kept;
    RestirVertex v;
    v.ctx = ctx;
    v.beta = p.beta[i];
    v.depth = length(ctx.p - camera.position);
    v.valid = 1;
    restir.vertex[pixel] = v;
    new (&restir.bsdf[pixel]) Bsdf(bsdf);
  }

  // Shadow ray of next-event sample j.
  RLL_HD void shadow_stage(uint32_t j) const { p.occluded[j] = tracer.shadow(p.nee[j].shadow); }

  // The next-event samples' contributions after their shadow rays' verdicts.
  RLL_HD void nee_finish_stage(uint32_t i) const {
    // (A cut at this vertex still has its key to come: psf_cut_key is the BSDF sampling stage's.)
    const bool split = c.psf.on && p.cut[i].key == kPsfKeyPending && psf_splits(c.psf, p.bsdf[i]);
    Rgb value(0);
    for (uint32_t j = i * draws, end = j + p.draws[i]; j < end; ++j) {
      NeeDraw d;
      d.setup = p.nee[j];
      d.light = p.light[j];
      d.scale = p.scale[j];
      const bool occluded = d.setup.traces && p.occluded[j] != 0;
      if (reaches_light(d.setup, occluded)) atomic_add(&tally->shadow_visible, uint64_t(1));
      const NeeResult r = finish_nee_draw(c, d, occluded, p.bsdf[i], -p.ray[i].d, p.beta[i]);
      p.record[j] = r.record;
      value += split
                   ? psf_split_nee(p.bsdf[i], -p.ray[i].d, d.setup.wi, p.beta[i], r.value, p.cut[i])
                   : r.value;
    }
    p.L[i] += p.beta[i] * value;
  }

  // Rewards to a learning sampler.
  RLL_HD void rewards_stage(uint32_t i) const {
    for (uint32_t j = i * draws, end = j + p.draws[i]; j < end; ++j)
      record_nee(sampler, p.ctx[i], p.light[j], p.record[j]);
  }

  // BSDF sampling, the throughput, Russian roulette: the next bounce's rays.
  RLL_HD void bsdf_sample_stage(uint32_t i) const {
    const int depth = p.depth[i];
    const Bsdf& bsdf = p.bsdf[i];
    const bool split = c.psf.on && p.cut[i].key == kPsfKeyPending && psf_splits(c.psf, bsdf);
    if (c.psf.on && p.cut[i].key == kPsfKeyPending)  // (the key of a cut at this vertex)
      p.cut[i].key = psf_cut_key(c, p.ctx[i], bsdf, -p.ray[i].d,
                                 psf_cut_footprint(p.ctx[i].footprint, p.hit[i].t,
                                                   p.prev_dir_pdf[i], -p.ray[i].d, p.surface[i].ng),
                                 depth, p.stream[i]);
    if (!continues_after_light(c, bsdf, depth)) return;
    PathState s = p.load(i);
    Ray next;
    bool roulette = false;
    if (!sample_bounce(c, s, bsdf, p.ctx[i], p.surface[i], -p.ray[i].d, p.numbers[i], depth, next,
                       roulette))
      return;
    if (roulette && !survive(s, vertex_number(p.stream[i], depth, kRoulette))) return;
    if (split) psf_split_bounce(bsdf, -p.ray[i].d, next.d, s.L, p.cut[i]);
    p.store(i, s);
    p.ray[i] = next;
    p.depth[i] = depth + 1;
    atomic_add(&tally->bounce, uint64_t(1));
    queue(kNextRays).push(i);
  }

  // Stage S (of the queue stages) for slot i.
  template <WavefrontStage S>
  RLL_HD void run(uint32_t i) const {
    if constexpr (S == WavefrontStage::ClosestHit)
      closest_hit_stage(i);
    else if constexpr (S == WavefrontStage::Emission)
      emission_stage(i);
    else if constexpr (S == WavefrontStage::NeeSample)
      nee_sample_stage(i);
    else if constexpr (S == WavefrontStage::Shadow)
      shadow_stage(i);
    else if constexpr (S == WavefrontStage::NeeFinish)
      nee_finish_stage(i);
    else if constexpr (S == WavefrontStage::Rewards)
      rewards_stage(i);
    else if constexpr (S == WavefrontStage::BsdfSample)
      bsdf_sample_stage(i);
    else if constexpr (S == WavefrontStage::RestirCandidates)
      restir_candidates_stage(i);
    else
      static_assert(S == WavefrontStage::BsdfSample, "not a queue stage");
  }

  // Accumulation of pixel first_pixel() + j of the batch: its samples in the batch, in their
  // order, so that the film's sums do not depend on the threads or the device.
  RLL_HD void accumulate_stage(const WavefrontBatch& b, uint64_t j) const {
    const uint64_t pixel = b.first_pixel() + j, count = uint64_t(b.count);
    if (c.psf.on) return psf_accumulate(pixel, uint32_t(pixel - b.first_item));
    if (c.restir.on) {  // (the film's sample is the shading's, after the pixels' reuse)
      restir.pixel[pixel] = RestirPixel{p.L[uint32_t(pixel - b.first_item)], 1u};
      return;
    }
    const uint64_t begin = pixel * count > b.first_item ? pixel * count : b.first_item;
    const uint64_t end_item = b.first_item + b.n, pixel_end = (pixel + 1) * count;
    const uint64_t end = pixel_end < end_item ? pixel_end : end_item;
    for (uint64_t item = begin; item < end; ++item) {
      Rgb L = p.L[uint32_t(item - b.first_item)];
      if (!is_finite(L)) {
        atomic_add(&tally->nonfinite, uint64_t(1));
        L = Rgb(0);
      }
      film.add(size_t(pixel), L);
    }
  }

  // A filtering render's batches hold one sample of each pixel (item = pixel): the end of the
  // pixel's path in `slot` (psf_end_path), its counts in the tally.
  RLL_HD void psf_accumulate(uint64_t pixel, uint32_t slot) const {
    const PsfEnd end =
        psf_end_path(c.psf, psf_table, film, psf_records, size_t(pixel), p.cut[slot], p.L[slot]);
    if (end == PsfEnd::NonFinite) atomic_add(&tally->nonfinite, uint64_t(1));
    if (end == PsfEnd::Filtered) atomic_add(&tally->filter.paths, uint64_t(1));
  }

  // After every path of the sample, with temporal reuse: its cell `cell` blends the last
  // sample's (psf_blend_cell), counted.
  RLL_HD void psf_blend_stage(uint64_t cell) const {
    if (psf_blend_cell(c.psf, psf_table, psf_last, size_t(cell)))
      atomic_add(&tally->filter.reused, uint64_t(1));
  }

  // After every path of the sample: pixel's cut path gets its cell's mean (psf_resolve_pixel).
  RLL_HD void psf_resolve_stage(uint64_t pixel) const {
    psf_resolve_pixel(c.psf, psf_table, film, psf_records, size_t(pixel));
  }

  // ReSTIR's steps over the pixels, after every path of the sample (render/restir_pixel.h), with
  // their shadow rays counted.
  RLL_HD void restir_visibility_stage(uint64_t pixel) const {
    bool visible = false;
    NeeRecord record;
    if (restir_visibility(c, tracer, restir, pixel, visible, record) > 0) {
      atomic_add(&tally->shadow, uint64_t(1));
      if (visible) atomic_add(&tally->shadow_visible, uint64_t(1));
    }
    const RestirKept& kept = restir.kept[pixel];
    if (sampler.learns && restir.vertex[pixel].valid && kept.light.pmf > 0)
      record_nee(sampler, restir.vertex[pixel].ctx, kept.light, record);
  }
  RLL_HD void restir_temporal_stage(uint64_t pixel) const {
    const uint64_t rays = restir_temporal(c, tracer, sobol, restir, pixel);
    if (rays > 0) atomic_add(&tally->shadow, rays);
  }
  RLL_HD void restir_spatial_stage(uint64_t pixel) const {
    const uint64_t rays = restir_spatial(c, tracer, sobol, restir, pixel);
    if (rays > 0) atomic_add(&tally->shadow, rays);
  }
  RLL_HD void restir_shade_stage(uint64_t pixel) const {
    uint64_t shadow = 0, visible = 0;
    if (!restir_shade(c, tracer, restir, film, pixel, shadow, visible))
      atomic_add(&tally->nonfinite, uint64_t(1));
    if (shadow > 0) atomic_add(&tally->shadow, shadow);
    if (visible > 0) atomic_add(&tally->shadow_visible, visible);
  }

  // ... and the sample's cells counted (one thread).
  RLL_HD void psf_count_stage() const {
    tally->filter.batches += 1;
    tally->filter.cells += *psf_table.used;
  }
};

}  // namespace rll
