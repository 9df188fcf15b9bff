#include "rll/wavefront/wavefront.h"

#include <algorithm>
#include <chrono>
#include <new>
#include <type_traits>
#include <vector>

#include "rll/core/device.h"
#include "rll/core/error.h"
#include "rll/render/path_vertex.h"
#include "rll/scene/scene_view.h"
#include "rll/wavefront/light_sampler_adapter.h"
#include "rll/wavefront/trace.h"

namespace rll {

namespace {

// The memory of the path slots: one block per array, taken once per render and freed with it.
class SlotMemory {
 public:
  SlotMemory() = default;
  SlotMemory(const SlotMemory&) = delete;
  SlotMemory& operator=(const SlotMemory&) = delete;
  ~SlotMemory() {
    for (const Block& b : m_blocks) ::operator delete(b.data, std::align_val_t(b.align));
  }
  // An array of n elements; default-constructed where T has a default constructor (a Bsdf has
  // none: its slot is constructed in place by the stage that builds it).
  template <typename T>
  View<T> take(size_t n) {
    static_assert(std::is_trivially_destructible_v<T>);
    void* p = ::operator new(n * sizeof(T), std::align_val_t(alignof(T)));
    m_blocks.push_back({p, alignof(T)});
    T* t = static_cast<T*>(p);
    if constexpr (std::is_default_constructible_v<T>)
      for (size_t i = 0; i < n; ++i) new (t + i) T();
    return {t, n};
  }

 private:
  struct Block {
    void* data;
    size_t align;
  };
  std::vector<Block> m_blocks;
};

// Path slots pushed by many threads at once; their order varies, what each slot holds does not.
struct Queue {
  View<uint32_t> slots;
  uint32_t* size;  // in the slot memory, so that the queue copies into a kernel by value
  void push(uint32_t slot) const { slots[atomic_add(size, 1u)] = slot; }
  uint32_t count() const { return atomic_load(size); }
  void clear() const { *size = 0; }
};

// The state of the paths in flight, one element per slot in each array.
struct Paths {
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
  // Its next-event sample.
  View<SampledLight> light;
  View<NeeSetup> nee;
  View<uint8_t> occluded;
  View<NeeRecord> record;

  Paths(SlotMemory& m, size_t n)
      : stream(m.take<SampleStream>(n)),
        ray(m.take<Ray>(n)),
        hit(m.take<Hit>(n)),
        depth(m.take<int>(n)),
        L(m.take<Rgb>(n)),
        beta(m.take<Rgb>(n)),
        footprint(m.take<float>(n)),
        prev_dir_pdf(m.take<float>(n)),
        prev_bsdf_pdf(m.take<float>(n)),
        prev_delta(m.take<uint8_t>(n)),
        prev_ctx(m.take<LightContext>(n)),
        surface(m.take<SurfaceHit>(n)),
        numbers(m.take<BsdfNumbers>(n)),
        bsdf(m.take<Bsdf>(n)),
        ctx(m.take<LightContext>(n)),
        light(m.take<SampledLight>(n)),
        nee(m.take<NeeSetup>(n)),
        occluded(m.take<uint8_t>(n)),
        record(m.take<NeeRecord>(n)) {}

  PathState load(uint32_t i) const {
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
  void store(uint32_t i, const PathState& s) const {
    L[i] = s.L;
    beta[i] = s.beta;
    footprint[i] = s.footprint;
    prev_dir_pdf[i] = s.prev_dir_pdf;
    prev_bsdf_pdf[i] = s.prev_bsdf_pdf;
    prev_delta[i] = s.prev_delta;
    prev_ctx[i] = s.prev_ctx;
  }
};

// Ray counts of a batch, added to by every stage with integer atomics.
struct RayTally {
  uint64_t bounce = 0, shadow = 0;
};

template <typename Body>
void for_queue(const Queue& q, const Body& body) {
  const View<uint32_t> slots = q.slots;
  host_parallel_for(q.count(), [&](size_t k) { body(slots[k]); });
}

double seconds_between(std::chrono::steady_clock::time_point a,
                       std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

// Runs `body`, adding its wall time to `stage` of `times` when there is a record to fill; without
// one it reads no clock.
template <typename Body>
void timed(WavefrontTimes* times, WavefrontStage stage, const Body& body) {
  if (!times) return body();
  const auto t0 = std::chrono::steady_clock::now();
  body();
  (*times)[stage] += seconds_between(t0, std::chrono::steady_clock::now());
}

}  // namespace

double WavefrontTimes::stages_sum() const {
  double sum = 0;
  for (double s : stage_seconds) sum += s;
  return sum;
}

RenderProgress render_wavefront(
    const Scene& scene, const Accel& accel, LightSampler& light_sampler,
    const IntegratorSettings& integrator, Film& film, const RenderSettings& settings,
    const std::atomic<bool>* cancel,
    const std::function<void(const RenderProgress&, const Film&)>& after_pass,
    const WavefrontSettings& wavefront) {
  if (wavefront.path_slots < 1) fail("the wavefront renderer needs at least one path slot");
  const auto t_start = std::chrono::steady_clock::now();
  WavefrontTimes* const times = wavefront.times;
  const SceneData data(scene);
  const PathConstants c = make_path_constants(scene, data.view(), integrator);
  WavefrontLightSampler sampler(light_sampler);
  const bool mis = c.strategy == LightStrategy::Mis;
  const int w = film.width();
  const size_t pixels = size_t(w) * film.height();

  // Everything the stages touch, allocated once here and reused by every batch and bounce.
  const size_t n_slots =
      std::min<size_t>(wavefront.path_slots, pixels * size_t(std::min(settings.spp, 1 << 10)));
  SlotMemory memory;
  const Paths p(memory, n_slots);
  const View<uint32_t> sizes = memory.take<uint32_t>(6);
  auto make_queue = [&](int i) { return Queue{memory.take<uint32_t>(n_slots), &sizes[i]}; };
  Queue rays = make_queue(0), next_rays = make_queue(1);
  const Queue hits = make_queue(2), nee = make_queue(3), shadows = make_queue(4),
              bounces = make_queue(5);
  const View<RayTally> tally = memory.take<RayTally>(1);

  auto pass = [&](int first, int count, uint64_t frame_seed, const PassStop& stop,
                  RayCounters& pass_rays, uint64_t& pass_nonfinite) {
    const size_t items = pixels * size_t(count);
    for (size_t batch = 0; batch < items && !stop(); batch += n_slots) {
      const uint32_t n = uint32_t(std::min(n_slots, items - batch));
      tally[0] = RayTally{};

      // Camera rays: item `batch + i` is sample first + (item % count) of pixel item / count, so
      // that each pixel's samples reach the film in the megakernel's order.
      timed(times, WavefrontStage::Camera, [&] {
        host_parallel_for(n, [&](size_t i) {
          const size_t item = batch + i, pixel = item / size_t(count);
          const int s = first + int(item % size_t(count));
          SampleStream stream(frame_seed, pixel, settings.first_sample + uint64_t(s),
                              settings.points);
          p.ray[i] = camera_ray(scene, int(pixel % size_t(w)), int(pixel / size_t(w)), stream);
          p.stream[i] = stream;
          p.depth[i] = 0;
          p.store(uint32_t(i), start_path(c));
          rays.slots[i] = uint32_t(i);
        });
      });
      *rays.size = n;

      while (rays.count() > 0) {
        hits.clear();
        nee.clear();
        shadows.clear();
        bounces.clear();
        next_rays.clear();

        // Closest hit.
        timed(times, WavefrontStage::ClosestHit, [&] {
          for_queue(rays, [&](uint32_t i) {
            Hit hit;
            if (!trace_closest(accel, p.ray[i], hit) || !hit_matters(c, hit, p.depth[i])) return;
            p.hit[i] = hit;
            hits.push(i);
          });
        });

        // Emission and its MIS weight at the hit; the vertex's BSDF and light context.
        timed(times, WavefrontStage::Emission, [&] {
          for_queue(hits, [&](uint32_t i) {
            PathState s = p.load(i);
            const int depth = p.depth[i];
            const SurfaceHit sh = make_surface_hit(c.scene.mesh, p.hit[i]);
            const Vec3 wo = -p.ray[i].d;
            const HitEmission e = hit_emission(c, s, sh, wo, depth);
            add_emission(c, s, sh, e,
                         e.needs_light_pmf ? sampler.pmf(s.prev_ctx, uint32_t(sh.light)) : 0.0f);
            if (depth >= c.max_depth) return p.store(i, s);
            SampleStream& stream = p.stream[i];
            const BsdfNumbers u = bsdf_numbers(stream, depth);
            const Bsdf* bsdf = new (&p.bsdf[i]) Bsdf(make_vertex_bsdf(c, sh, wo, u, depth));
            if (bsdf->is_black()) return p.store(i, s);
            LightContext ctx = make_vertex_context(c, s, sh, p.hit[i], wo, *bsdf);
            if (sampler.prepares() && !bsdf->is_delta())
              sampler.prepare(ctx, vertex_number(stream, depth, kPrepare));
            p.store(i, s);
            p.surface[i] = sh;
            p.numbers[i] = u;
            p.ctx[i] = ctx;
            if (samples_light(c, *bsdf)) nee.push(i);
            bounces.push(i);
          });
        });

        // Next-event estimation: the light, the point on it, the unoccluded contribution.
        timed(times, WavefrontStage::NeeSample, [&] {
          for_queue(nee, [&](uint32_t i) {
            const LightNumbers u = light_numbers(p.stream[i], p.depth[i]);
            const SampledLight sl = sampler.sample(p.ctx[i], u.u_light);
            p.light[i] = sl;
            if (sl.pmf <= 0) return;
            const NeeSetup setup =
                nee_setup(c, p.ctx[i], p.bsdf[i], -p.ray[i].d, sl.light, u.u_pos);
            p.nee[i] = setup;
            p.occluded[i] = 0;
            if (setup.counts_shadow_ray) atomic_add(&tally[0].shadow, uint64_t(1));
            if (setup.traces) shadows.push(i);
          });
        });

        // Shadow rays.
        timed(times, WavefrontStage::Shadow, [&] {
          for_queue(shadows,
                    [&](uint32_t i) { p.occluded[i] = trace_shadow(accel, p.nee[i].shadow); });
        });

        // The next-event sample's contribution after the shadow ray's verdict.
        timed(times, WavefrontStage::NeeFinish, [&] {
          for_queue(nee, [&](uint32_t i) {
            const SampledLight& sl = p.light[i];
            Rgb value(0);
            if (sl.pmf > 0) {
              const NeeResult r = nee_finish(p.nee[i], p.nee[i].traces && p.occluded[i] != 0,
                                             p.bsdf[i], -p.ray[i].d, p.beta[i], sl.pmf, mis);
              p.record[i] = r.record;
              value = r.value;
            }
            p.L[i] += p.beta[i] * value;
          });
        });

        // Rewards to a learning sampler.
        if (sampler.learns())
          timed(times, WavefrontStage::Rewards, [&] {
            for_queue(nee, [&](uint32_t i) {
              if (p.light[i].pmf > 0) sampler.record(p.ctx[i], p.light[i], p.record[i]);
            });
          });

        // BSDF sampling, the throughput, Russian roulette: the next bounce's rays.
        timed(times, WavefrontStage::BsdfSample, [&] {
          for_queue(bounces, [&](uint32_t i) {
            const int depth = p.depth[i];
            const Bsdf& bsdf = p.bsdf[i];
            if (!continues_after_light(c, bsdf, depth)) return;
            PathState s = p.load(i);
            Ray next;
            bool roulette = false;
            if (!sample_bounce(c, s, bsdf, p.ctx[i], p.surface[i], -p.ray[i].d, p.numbers[i], depth,
                               next, roulette))
              return;
            if (roulette && !survive(s, vertex_number(p.stream[i], depth, kRoulette))) return;
            p.store(i, s);
            p.ray[i] = next;
            p.depth[i] = depth + 1;
            atomic_add(&tally[0].bounce, uint64_t(1));
            next_rays.push(i);
          });
        });
        std::swap(rays, next_rays);
      }

      // Accumulation, in slot order: the film's sums do not depend on the threads.
      timed(times, WavefrontStage::Accumulate, [&] {
        for (uint32_t i = 0; i < n; ++i) {
          const size_t pixel = (batch + i) / size_t(count);
          Rgb L = p.L[i];
          if (!is_finite(L)) {
            ++pass_nonfinite;
            L = Rgb(0);
          }
          film.add(int(pixel % size_t(w)), int(pixel / size_t(w)), L);
        }
      });
      pass_rays.camera += n;
      pass_rays.bounce += tally[0].bounce;
      pass_rays.shadow += tally[0].shadow;
    }
  };
  const RenderProgress progress = run_passes(
      scene, [&] { timed(times, WavefrontStage::EndPass, [&] { sampler.end_pass(); }); }, film,
      settings, cancel, after_pass, pass);
  if (times) times->total_seconds += seconds_between(t_start, std::chrono::steady_clock::now());
  return progress;
}

}  // namespace rll
