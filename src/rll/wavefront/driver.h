// The wavefront renderer's loop over a batch of paths, written once for every device: the stages
// of wavefront/kernels.h launched over their queues, bounce after bounce, then the accumulation.
// As pbrt-v4's wavefront, nothing is read back between stages: the queues' sizes live on the
// device, every stage is launched over its queue's capacity (the threads past the size return at
// once), the bounces are launched up to the integrator's maximum depth (Russian roulette empties
// the queues; the kernels see it), and the counts of the pass (the tally) are summed on the device
// over its batches and read once, at its end: one host synchronisation per pass.
//
// A backend provides:
//   template <class T> View<T> take(size_t n)         memory for n elements, kept with it
//   template <class Body> void launch(size_t n, const Body& body)      body(i) for i in [0, n)
//   template <class Body> void launch_queue(const WavefrontQueue& q, uint32_t upper,
//                                           const Body& body)   body(q.slots[k]) for k < q.count()
//   void zero(void* p, size_t bytes)                   in order with the launches, no wait
//   bool may_hold(const uint32_t* size)   false only where the queue is known to be empty without
//                                         waiting (the host reads its memory; a GPU says true)
//   template <class T> T read(const T* p)               one value (waits for the launches)
//   template <class Fn> void timed(WavefrontStage s, const Fn& fn)   times what fn launches
#pragma once

#include <cstddef>
#include <cstdint>
#include <utility>

#include "rll/wavefront/kernels.h"
#include "rll/wavefront/stages.h"

namespace rll {

// The bytes of one path slot with `draws` next-event samples (nee_draws_per_vertex): its state
// (PathSlots, with rht's reservoirs where `reservoirs`: draws_several) and its place in each queue
// (`draws` places in the shadow rays', one in ReSTIR's where `restir`). What the slot count is
// chosen from (wavefront_slot_count, wavefront/passes.h).
inline size_t wavefront_slot_bytes(size_t draws = 1, bool restir = false, bool reservoirs = false) {
  size_t bytes = 0;
  auto count = [&]<typename T>(size_t n) {
    bytes += n * sizeof(T);
    return View<T>{};
  };
  PathSlots::make(count, 1, draws, false, restir, reservoirs);
  return bytes + (kWavefrontQueues - 2 + draws + (restir ? 1 : 0)) * sizeof(uint32_t);
}

template <typename Backend, typename Tracer>
class WavefrontDriver {
 public:
  using Kernels = WavefrontKernels<Tracer>;

  // `k` holds the scene, camera, tables, tracer, sampler and film; the driver adds the path slots,
  // queues and tally, n_slots of each, taken from the backend once. With `frames` (the filter's
  // temporal reuse, render/psf.h: its two tables in the backend's memory, kept by the caller from
  // render to render), the filter's cells are theirs; `follows_frame` as RenderSettings'. With
  // `restir` (ReSTIR's history, render/restir.h, kept by the caller), its vertex records and
  // final reservoirs are theirs, and a render that follows a frame reuses the last one's.
  WavefrontDriver(Backend& backend, const Kernels& k, size_t n_slots,
                  PsfFrameCells* frames = nullptr, bool follows_frame = false,
                  RestirFrames* restir = nullptr)
      : m_backend(backend),
        m_k(k),
        m_slots(n_slots),
        m_frames(frames),
        m_follows(follows_frame),
        m_restir(restir) {
    auto take = [&]<typename T>(size_t n) { return m_backend.template take<T>(n); };
    m_k.draws = uint32_t(nee_draws_per_vertex(m_k.sampler));
    m_k.p =
        PathSlots::make(take, n_slots, m_k.draws, filters(), restirs(), draws_several(m_k.sampler));
    for (uint32_t q = 0; q < kWavefrontQueues; ++q)
      m_k.queue_slots[q] =
          m_backend.template take<uint32_t>(q == kShadows                ? n_slots * m_k.draws
                                            : q == kRestir && !restirs() ? 1
                                                                         : n_slots);
    m_sizes = m_backend.template take<uint32_t>(2 * kWavefrontQueues).data;
    m_k.tally = m_backend.template take<WavefrontTally>(1).data;
    if (filters()) {
      // Path-space filtering: a sample of every pixel at a time (render/psf.h).
      const size_t pixels = m_k.film.count.size, cells = psf_capacity(pixels);
      if (m_frames && m_frames->pixels != pixels) m_frames = nullptr;  // (not this film's)
      if (!m_frames) {
        m_k.psf_table.keys = m_backend.template take<uint64_t>(cells);
        m_k.psf_table.sums = m_backend.template take<ExactSum>(6 * cells);
        m_k.psf_table.used = m_backend.template take<uint32_t>(1).data;
      }
      m_k.psf_records = m_backend.template take<PsfRecord>(pixels);
    }
    if (restirs()) {
      // ReSTIR: a sample of every pixel at a time (render/restir.h).
      const size_t pixels = m_k.film.count.size;
      if (m_restir && m_restir->pixels != pixels) m_restir = nullptr;  // (not this film's)
      if (!m_restir) {
        for (int i = 0; i < 2; ++i) {
          m_own_restir.vertex[i] = m_backend.template take<RestirVertex>(pixels);
          m_own_restir.bsdf[i] = m_backend.template take<Bsdf>(pixels);
          m_own_restir.final_[i] = m_backend.template take<Reservoir>(pixels);
        }
        m_own_restir.pixels = pixels;
        m_restir = &m_own_restir;
      }
      m_k.restir.reservoir = m_backend.template take<Reservoir>(pixels);
      m_k.restir.kept = m_backend.template take<RestirKept>(pixels);
      m_k.restir.pixel = m_backend.template take<RestirPixel>(pixels);
      m_k.restir.width = m_k.film.width;
      m_k.restir.height = int(pixels / size_t(m_k.film.width));
    }
  }

  // Whether a restir sampler renders: its passes then run a sample of every pixel at a time, as
  // the filter's.
  bool restirs() const { return m_k.c.restir.on; }
  // Whether the passes run a sample of every pixel at a time, begin_sample() before and
  // end_sample() after each.
  bool per_sample() const { return filters() || restirs(); }
  void begin_sample() {
    if (filters()) begin_filter_batch();
    if (restirs()) begin_restir_sample();
  }
  // `sample` the sample index (RenderSettings::first_sample + the pass's sample) and the pass's
  // frame_seed and points: the keys of the pixels' streams.
  void end_sample(uint64_t sample, uint64_t frame_seed, PointSet points) {
    if (filters()) resolve_filter();
    if (restirs()) resolve_restir(sample, frame_seed, points);
  }

  // The sample's vertex records and final reservoirs are the history's other half; the half the
  // last sample filled is the one temporal reuse reads, where this render follows it (an earlier
  // sample of this render, or a frame where the render follows one).
  void begin_restir_sample() {
    const RestirFrames& f = *m_restir;
    const int next = 1 - f.last;
    RestirBuffers& b = m_k.restir;
    b.vertex = f.vertex[next];
    b.bsdf = f.bsdf[next];
    b.final_ = f.final_[next];
    b.prev_vertex = f.vertex[f.last];
    b.prev_bsdf = f.bsdf[f.last];
    b.prev_final = f.final_[f.last];
    b.prev_camera = f.camera;
    b.has_prev = f.holds && (m_restir_samples > 0 || m_follows);
    m_backend.timed(WavefrontStage::RestirCandidates, [&] {
      m_backend.zero(b.vertex.data, b.vertex.size * sizeof(RestirVertex));
      m_backend.zero(b.pixel.data, b.pixel.size * sizeof(RestirPixel));
    });
  }
  // After the batches of a sample: visibility, temporal and spatial reuse, shading, each launched
  // over the pixels.
  void resolve_restir(uint64_t sample, uint64_t frame_seed, PointSet points) {
    m_k.restir.sample = sample;
    m_k.restir.frame_seed = frame_seed;
    m_k.restir.points = points;
    const size_t pixels = m_k.restir.pixel.size;
    pixel_step<WavefrontStage::RestirVisibility>(pixels);
    pixel_step<WavefrontStage::RestirTemporal>(pixels);
    pixel_step<WavefrontStage::RestirSpatial>(pixels);
    pixel_step<WavefrontStage::RestirShade>(pixels);
    m_restir->last = 1 - m_restir->last;
    m_restir->holds = true;
    m_restir->camera = m_k.camera;
    ++m_restir_samples;
  }
  // Launches ReSTIR's step S over the pixels. (Public: CUDA's extended lambdas may not live in
  // private member functions.)
  template <WavefrontStage S>
  void pixel_step(size_t pixels) {
    m_backend.timed(S, [&] {
      const Kernels k = m_k;
      m_backend.launch(pixels, [k] RLL_HD(size_t pixel) {
        if constexpr (S == WavefrontStage::RestirVisibility)
          k.restir_visibility_stage(uint64_t(pixel));
        else if constexpr (S == WavefrontStage::RestirTemporal)
          k.restir_temporal_stage(uint64_t(pixel));
        else if constexpr (S == WavefrontStage::RestirSpatial)
          k.restir_spatial_stage(uint64_t(pixel));
        else
          k.restir_shade_stage(uint64_t(pixel));
      });
    });
  }

  // Whether the render filters its paths (--filter psf): its passes then run a sample of every
  // pixel at a time, begin_filter_batch() before and resolve_filter() after each.
  bool filters() const { return m_k.c.psf.on; }
  // Every cell free, every record empty (a stopped batch leaves pixels it did not reach empty).
  // With temporal reuse the two tables change places: the sample fills the one the sample before
  // blended, and blends the other where the render follows a frame.
  void begin_filter_batch() {
    if (m_frames) {
      m_k.psf_table = m_frames->next();
      m_blend = m_frames->blends(m_follows);
      m_k.psf_last = m_blend ? m_frames->previous() : PsfTableView{};
    }
    m_backend.timed(WavefrontStage::Accumulate, [&] {
      const PsfTableView& t = m_k.psf_table;
      m_backend.zero(t.keys.data, t.keys.size * sizeof(uint64_t));
      m_backend.zero(t.sums.data, t.sums.size * sizeof(ExactSum));
      m_backend.zero(t.used, sizeof(uint32_t));
      m_backend.zero(m_k.psf_records.data, m_k.psf_records.size * sizeof(PsfRecord));
    });
  }
  // After the batches of a sample: its cells blend the last sample's (temporal reuse), every cut
  // path gets its cell's mean; the cells are counted.
  void resolve_filter() {
    m_backend.timed(WavefrontStage::Accumulate, [&] {
      const Kernels k = m_k;
      if (m_blend)
        m_backend.launch(k.psf_table.keys.size,
                         [k] RLL_HD(size_t cell) { k.psf_blend_stage(uint64_t(cell)); });
      m_backend.launch(k.psf_records.size,
                       [k] RLL_HD(size_t pixel) { k.psf_resolve_stage(uint64_t(pixel)); });
      m_backend.launch(1, [k] RLL_HD(size_t) { k.psf_count_stage(); });
    });
    if (m_frames) m_frames->filled();
  }

  size_t slots() const { return m_slots; }
  // A sampler's view after the end of a pass (its tables may have moved).
  void set_sampler(const SamplerView& s) { m_k.sampler = s; }
  const Kernels& kernels() const { return m_k; }

  // Starts a pass: its counts from zero.
  void begin_pass() { m_backend.zero(m_k.tally, sizeof(WavefrontTally)); }

  // Runs every path of the batch to its end and adds them to the film and their counts to the
  // pass's; reads nothing back.
  void run_batch(const WavefrontBatch& b) {
    m_k.batch_first = b.first_item;
    m_k.queue_sizes = m_sizes;
    m_k.next_queue_sizes = m_sizes + kWavefrontQueues;
    m_backend.zero(m_sizes, 2 * kWavefrontQueues * sizeof(uint32_t));
    m_backend.timed(WavefrontStage::Camera, [&] {
      const Kernels k = m_k;
      const WavefrontBatch batch = b;
      m_backend.launch(b.n, [k, batch] RLL_HD(size_t i) { k.camera_stage(batch, uint32_t(i)); });
    });
    // Bounce d traces the rays of depth d; the last (d = max_depth) only finds the emission they
    // hit (the emission stage ends every path there).
    const int max_depth = m_k.c.max_depth;
    for (int depth = 0; depth <= max_depth; ++depth) {
      if (depth > 0) {
        // The next bounce's rays become this one's; the block the last bounce used is cleared
        // for the next.
        std::swap(m_k.queue_slots[kRays], m_k.queue_slots[kNextRays]);
        std::swap(m_k.queue_sizes, m_k.next_queue_sizes);
        if (!m_backend.may_hold(&m_k.queue_sizes[kRays])) break;
        m_backend.zero(m_k.next_queue_sizes, kWavefrontQueues * sizeof(uint32_t));
      }
      stage<WavefrontStage::ClosestHit>(kRays, b.n);
      stage<WavefrontStage::Emission>(kHits, b.n);
      if (depth == max_depth) break;
      if (restirs()) stage<WavefrontStage::RestirCandidates>(kRestir, b.n);
      stage<WavefrontStage::NeeSample>(kNee, b.n);
      stage<WavefrontStage::Shadow>(kShadows, b.n * m_k.draws);
      stage<WavefrontStage::NeeFinish>(kNee, b.n);
      if (m_k.sampler.learns) stage<WavefrontStage::Rewards>(kNee, b.n);
      stage<WavefrontStage::BsdfSample>(kBounces, b.n);
    }
    m_backend.timed(WavefrontStage::Accumulate, [&] {
      const Kernels k = m_k;
      const WavefrontBatch batch = b;
      m_backend.launch(b.pixels(),
                       [k, batch] RLL_HD(size_t j) { k.accumulate_stage(batch, uint64_t(j)); });
    });
  }

  // The pass's counts: the pass's one read that waits for the device.
  WavefrontTally end_pass() { return m_backend.read(m_k.tally); }

  // Launches stage S over the slots of queue `q` (at most `upper` of them). (Public: CUDA's
  // extended lambdas may not live in private member functions.)
  template <WavefrontStage S>
  void stage(WavefrontQueueId q, uint32_t upper) {
    if (!m_backend.may_hold(m_k.queue(q).size)) return;
    m_backend.timed(S, [&] {
      const Kernels k = m_k;
      m_backend.launch_queue(k.queue(q), upper, [k] RLL_HD(uint32_t i) { k.template run<S>(i); });
    });
  }

 private:
  Backend& m_backend;
  Kernels m_k;
  size_t m_slots;
  uint32_t* m_sizes = nullptr;        // the two blocks of queue sizes
  PsfFrameCells* m_frames = nullptr;  // temporal reuse's tables, where it is on
  bool m_follows = false;             // the render follows a frame
  bool m_blend = false;               // the sample in flight blends the last one's cells
  RestirFrames* m_restir = nullptr;   // ReSTIR's history, the caller's or m_own_restir
  RestirFrames m_own_restir;
  uint64_t m_restir_samples = 0;  // the samples this render resolved
};

}  // namespace rll
