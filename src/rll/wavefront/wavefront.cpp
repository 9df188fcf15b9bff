#include "rll/wavefront/wavefront.h"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <new>
#include <type_traits>
#include <vector>

#include "rll/bvh/bvh.h"
#include "rll/core/device.h"
#include "rll/core/error.h"
#include "rll/scene/scene_view.h"
#include "rll/wavefront/driver.h"
#include "rll/wavefront/light_sampler_adapter.h"
#include "rll/wavefront/passes.h"
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

double seconds_between(std::chrono::steady_clock::time_point a,
                       std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

// The CPU's side of wavefront/driver.h: slot memory, host_parallel_for, the wall clock.
class HostBackend {
 public:
  explicit HostBackend(WavefrontTimes* times) : m_times(times) {}

  template <typename T>
  View<T> take(size_t n) {
    return m_memory.take<T>(n);
  }
  template <typename Body>
  void launch(size_t n, const Body& body) {
    host_parallel_for(n, body);
  }
  template <typename Body>
  void launch_queue(const WavefrontQueue& q, uint32_t, const Body& body) {
    const View<uint32_t> slots = q.slots;
    host_parallel_for(q.count(), [&](size_t k) { body(slots[k]); });
  }
  void zero(void* p, size_t bytes) { std::memset(p, 0, bytes); }
  void write(uint32_t* p, uint32_t v) { *p = v; }
  void copy(uint32_t* to, const uint32_t* from) { *to = *from; }
  template <typename T>
  T read(const T* p) {
    return *p;
  }
  // Runs `fn`, adding its wall time to `stage` when there is a record to fill; without one it
  // reads no clock.
  template <typename Fn>
  void timed(WavefrontStage stage, const Fn& fn) {
    if (!m_times) return fn();
    const auto t0 = std::chrono::steady_clock::now();
    fn();
    (*m_times)[stage] += seconds_between(t0, std::chrono::steady_clock::now());
  }

 private:
  SlotMemory m_memory;
  WavefrontTimes* m_times;
};

// Tracing by Embree, through the accel (the CPU's tracer).
struct AccelTracer {
  const Accel* accel;
  bool closest(const Ray& ray, Hit& hit) const { return trace_closest(*accel, ray, hit); }
  bool shadow(const Ray& ray) const { return trace_shadow(*accel, ray); }
};

template <typename Tracer>
RenderProgress render_with(
    const Scene& scene, const Tracer& tracer, LightSampler& light_sampler,
    const IntegratorSettings& integrator, Film& film, const RenderSettings& settings,
    const std::atomic<bool>* cancel,
    const std::function<void(const RenderProgress&, const Film&)>& after_pass,
    const WavefrontSettings& wavefront) {
  const SceneData data(scene);
  const auto k = wavefront_kernels(scene, data.view(), integrator, film.view(), host_sobol_view(),
                                   tracer, HostLightSampler::of(light_sampler));
  HostBackend backend(wavefront.times);
  WavefrontDriver<HostBackend, Tracer, HostLightSampler> driver(
      backend, k, wavefront_slot_count(wavefront.path_slots, film, settings.spp));
  auto end_pass = [&] {
    backend.timed(WavefrontStage::EndPass, [&] { light_sampler.end_pass(); });
    driver.set_sampler(HostLightSampler::of(light_sampler));
  };
  return run_wavefront_passes(
      scene, driver, end_pass, [] {}, film, settings, cancel, after_pass);
}

}  // namespace

double WavefrontTimes::stages_sum() const {
  double sum = 0;
  for (double s : stage_seconds) sum += s;
  return sum;
}

RenderProgress render_wavefront(
    const Scene& scene, const Accel& accel, LightSampler& sampler,
    const IntegratorSettings& integrator, Film& film, const RenderSettings& settings,
    const std::atomic<bool>* cancel,
    const std::function<void(const RenderProgress&, const Film&)>& after_pass,
    const WavefrontSettings& wavefront) {
  // Its next-event stages trace one shadow ray a vertex (docs/rht.md).
  if (sampler.rht_view())
    fail(
        "sampler '{}' draws several light samples per vertex, with a shadow ray each: the "
        "wavefront renderer traces one; render it with the megakernel (no --wavefront, --device "
        "cpu)",
        sampler.name());
  const auto t_start = std::chrono::steady_clock::now();
  RenderProgress progress;
  if (wavefront.tracer == WavefrontTracer::Bvh) {
    const Bvh bvh = build_bvh(scene.mesh);
    progress = render_with(scene, BvhTracer{bvh.view()}, sampler, integrator, film, settings,
                           cancel, after_pass, wavefront);
  } else {
    progress = render_with(scene, AccelTracer{&accel}, sampler, integrator, film, settings, cancel,
                           after_pass, wavefront);
  }
  if (wavefront.times)
    wavefront.times->total_seconds += seconds_between(t_start, std::chrono::steady_clock::now());
  return progress;
}

}  // namespace rll
