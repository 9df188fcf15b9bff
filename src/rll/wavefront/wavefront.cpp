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
#include "rll/core/memory_budget.h"
#include "rll/scene/scene_view.h"
#include "rll/wavefront/driver.h"
#include "rll/wavefront/passes.h"
#include "rll/wavefront/trace.h"

namespace rll {

namespace {

double seconds_between(std::chrono::steady_clock::time_point a,
                       std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

// The CPU's side of wavefront/driver.h: slot memory (kept in a WavefrontMemory from render to
// render where one is given), host_parallel_for, the wall clock, and the counts of DeviceWork
// (its memory is the host's: it copies nothing).
class HostBackend {
 public:
  HostBackend(WavefrontTimes* times, WavefrontMemory* memory)
      : m_memory(memory ? memory : &m_own), m_times(times) {}

  // Array k of the render reuses the memory's block k where it is large enough (its contents are
  // what the last render left: every stage writes a slot's state before it reads it); a new
  // block is default-constructed where T has a default constructor (a Bsdf has none: its slot is
  // constructed in place by the stage that builds it).
  template <typename T>
  View<T> take(size_t n) {
    static_assert(std::is_trivially_destructible_v<T>);
    const size_t bytes = std::max<size_t>(1, n * sizeof(T)), k = m_taken++;
    std::vector<WavefrontMemory::Block>& blocks = m_memory->blocks;
    if (k < blocks.size() && blocks[k].bytes >= bytes && blocks[k].align >= alignof(T))
      return {static_cast<T*>(blocks[k].data), n};
    if (k >= blocks.size()) blocks.resize(k + 1);
    WavefrontMemory::Block& b = blocks[k];
    if (b.data) ::operator delete(b.data, std::align_val_t(b.align));
    b = {};
    b.data = ::operator new(bytes, std::align_val_t(alignof(T)));
    b.bytes = bytes;
    b.align = alignof(T);
    ++m_work.allocations;
    T* t = static_cast<T*>(b.data);
    if constexpr (std::is_default_constructible_v<T>)
      for (size_t i = 0; i < n; ++i) new (t + i) T();
    return {t, n};
  }
  template <typename Body>
  void launch(size_t n, const Body& body) {
    if (n == 0) return;
    ++m_work.launches;
    host_parallel_for(n, body);
  }
  template <typename Body>
  void launch_queue(const WavefrontQueue& q, uint32_t, const Body& body) {
    const View<uint32_t> slots = q.slots;
    const uint32_t n = q.count();
    if (n == 0) return;
    ++m_work.launches;
    host_parallel_for(n, [&](size_t k) { body(slots[k]); });
  }
  void zero(void* p, size_t bytes) {
    ++m_work.launches;
    std::memset(p, 0, bytes);
  }
  // The host reads its own memory without waiting: an empty queue is skipped.
  bool may_hold(const uint32_t* size) const { return *size != 0; }
  template <typename T>
  T read(const T* p) {
    ++m_work.syncs;  // (nothing to wait for here; counted as the GPU's read, which waits)
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
  const DeviceWork& work() const { return m_work; }

 private:
  WavefrontMemory m_own;  // where the caller keeps none
  WavefrontMemory* m_memory;
  size_t m_taken = 0;
  WavefrontTimes* m_times;
  DeviceWork m_work;
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
  const SamplerView view = light_sampler.sampler_view();
  check_nee_settings(integrator, view, light_sampler.name());
  const auto k = wavefront_kernels(scene, data.view(), integrator, film.view(), host_sobol_view(),
                                   tracer, view);
  const size_t draws = size_t(nee_draws_per_vertex(view));
  HostBackend backend(wavefront.times, wavefront.memory);
  // A quarter of the memory budget for the path slots (the scene, its accel and the sampler's
  // tables take the rest).
  const size_t budget = memory_budget_bytes() / 4;
  const size_t slots = render_path_slots(wavefront, film, settings, budget, kHostMaxPathSlots,
                                         draws, integrator.restir.on, draws_several(view));
  if (integrator.psf.on) check_psf_memory(size_t(film.width()) * film.height());
  if (integrator.restir.on) check_restir_memory(size_t(film.width()) * film.height());
  RestirFrames* restir = integrator.restir.on && wavefront.restir_history
                             ? &wavefront.restir_history->frames()
                             : nullptr;
  PsfFrameCells* frames = integrator.psf.on && integrator.psf.temporal > 0 && wavefront.psf_history
                              ? &wavefront.psf_history->cells()
                              : nullptr;
  WavefrontDriver<HostBackend, Tracer> driver(backend, k, slots, frames, settings.follows_frame,
                                              restir);
  auto end_pass = [&] {
    backend.timed(WavefrontStage::EndPass, [&] { light_sampler.end_pass(); });
    driver.set_sampler(light_sampler.sampler_view());
  };
  return run_wavefront_passes(
      scene, driver, end_pass, {}, film, settings, cancel, after_pass,
      [&] { return backend.work(); }, DeviceWork{},
      wavefront.work ? &wavefront.work->passes : nullptr);
}

}  // namespace

WavefrontMemory::~WavefrontMemory() {
  for (const Block& b : blocks)
    if (b.data) ::operator delete(b.data, std::align_val_t(b.align));
}

size_t WavefrontMemory::bytes() const {
  size_t n = 0;
  for (const Block& b : blocks) n += b.bytes;
  return n;
}

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
