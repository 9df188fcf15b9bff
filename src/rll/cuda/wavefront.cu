// The GPU's side of the wavefront renderer: the CUDA backend of wavefront/driver.h (slot memory
// kept from render to render, launches over queues, CUDA events read once per pass), the scene,
// BVH, Sobol' tables and film in device memory, and the light sampler's tables there: rll's
// learning state resident across passes and renders, its end of pass run there
// (cuda/device_rll.cuh); the other samplers' tables, which do not learn, uploaded once a render.
#include <cuda_runtime.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <optional>
#include <vector>

#include "rll/bvh/bvh.h"
#include "rll/core/error.h"
#include "rll/core/sobol.h"
#include "rll/cuda/cuda.h"
#include "rll/cuda/device_rll.cuh"
#include "rll/cuda/device_sampler.cuh"
#include "rll/cuda/device_scene.cuh"
#include "rll/cuda/launch.cuh"
#include "rll/cuda/wavefront.h"
#include "rll/scene/scene_view.h"
#include "rll/wavefront/driver.h"
#include "rll/wavefront/passes.h"

namespace rll::cuda {

namespace {

// The body (a lambda holding the whole WavefrontKernels, about 1 KB) is read in place from the
// parameter space: without __grid_constant__ the call through `this` copies it to each thread's
// local memory (a 1 KB stack frame for emission; tests/unit/kernel_budgets.h).
template <typename Body>
__global__ void queue_kernel(WavefrontQueue q, uint32_t upper, const __grid_constant__ Body body) {
  const uint32_t k = blockIdx.x * blockDim.x + threadIdx.x;
  if (k < upper && k < q.count()) body(q.slots[k]);
}

}  // namespace

// (Outside the anonymous namespace: GpuRenderer::Impl holds them.)

// Device memory for the path slots, kept from render to render (and frame to frame in
// interactive): array k of a render reuses block k where it is large enough, without clearing it
// (every stage writes a slot's state before it reads it); a new block starts zeroed.
class SlotArena {
 public:
  void restart() { m_taken = 0; }
  void* take(size_t bytes, bool& fresh) {
    const size_t k = m_taken++;
    if (k >= m_blocks.size()) m_blocks.resize(k + 1);
    fresh = m_blocks[k].bytes() < bytes;
    if (fresh) {
      m_blocks[k] = DeviceArray<unsigned char>();  // (back to the cache first)
      m_blocks[k] = DeviceArray<unsigned char>(bytes);
    }
    return m_blocks[k].view().data;
  }
  size_t bytes() const {
    size_t n = 0;
    for (const auto& b : m_blocks) n += b.bytes();
    return n;
  }

 private:
  std::vector<DeviceArray<unsigned char>> m_blocks;
  size_t m_taken = 0;
};

// The GPU's side of wavefront/driver.h: nothing in it waits for the device but read(). The
// stages' times come from CUDA events recorded around their launches without waiting, read
// after the pass's one read.
class CudaWavefrontBackend {
 public:
  // A render's start: its arrays from the first block again, its times into `times`.
  void begin(WavefrontTimes* times) {
    m_arena.restart();
    m_events.discard();
    m_times = times;
  }

  template <typename T>
  View<T> take(size_t n) {
    const size_t bytes = std::max<size_t>(1, n * sizeof(T));
    bool fresh = false;
    void* p = m_arena.take(bytes, fresh);
    if (fresh) zero(p, bytes);
    return {static_cast<T*>(p), n};
  }
  template <typename Body>
  void launch(size_t n, const Body& body) {
    parallel_for(n, body);
  }
  // One thread per slot the queue may hold; those past its size return at once (the size is
  // known only on the device).
  template <typename Body>
  void launch_queue(const WavefrontQueue& q, uint32_t upper, const Body& body) {
    if (upper == 0) return;
    const unsigned blocks = (upper + detail::kBlockSize - 1) / detail::kBlockSize;
    queue_kernel<<<blocks, detail::kBlockSize>>>(q, upper, body);
    check(cudaGetLastError(), "kernel launch");
    count::launch();
  }
  void zero(void* p, size_t bytes) {
    check(cudaMemsetAsync(p, 0, bytes), "cudaMemsetAsync");
    count::launch();
  }
  // A queue's size is on the device: every stage is launched.
  bool may_hold(const uint32_t*) const { return true; }
  // Waits for everything queued before it; the stages' times are read then.
  template <typename T>
  T read(const T* p) {
    T v;
    check(cudaMemcpy(&v, p, sizeof(T), cudaMemcpyDeviceToHost), "cudaMemcpy");
    count::sync();
    count::to_host(sizeof(T));
    collect_times();
    return v;
  }
  // The kernels' time by CUDA events; the end of a pass (host work, copies, the end of pass's
  // own reads) by the wall clock.
  template <typename Fn>
  void timed(WavefrontStage stage, const Fn& fn) {
    if (!m_times) return fn();
    if (stage == WavefrontStage::EndPass) {
      const auto t0 = std::chrono::steady_clock::now();
      fn();
      (*m_times)[stage] +=
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      return;
    }
    m_events.start(size_t(stage));
    fn();
    m_events.stop();
  }
  // The times of the events recorded so far (their work must be done).
  void collect_times() {
    if (m_times)
      m_events.read(
          [&](size_t stage, float ms) { (*m_times)[WavefrontStage(stage)] += double(ms) * 1e-3; });
  }
  DeviceWork work() const { return device_work(); }
  size_t bytes() const { return m_arena.bytes(); }

 private:
  SlotArena m_arena;
  WavefrontTimes* m_times = nullptr;
  EventPool m_events;
};

// Page-locked host memory, where copies of the film go to and come from at the full speed of the
// bus and without the driver's own staging copy; kept and grown as needed.
class PinnedBuffer {
 public:
  PinnedBuffer() = default;
  PinnedBuffer(const PinnedBuffer&) = delete;
  PinnedBuffer& operator=(const PinnedBuffer&) = delete;
  ~PinnedBuffer() {
    if (m_data) cudaFreeHost(m_data);
  }
  unsigned char* get(size_t bytes) {
    if (bytes > m_bytes) {
      if (m_data) cudaFreeHost(m_data);
      m_data = nullptr;
      m_bytes = 0;
      check(cudaMallocHost(reinterpret_cast<void**>(&m_data), bytes), "cudaMallocHost");
      count::allocation();
      m_bytes = bytes;
    }
    return m_data;
  }

 private:
  unsigned char* m_data = nullptr;
  size_t m_bytes = 0;
};

namespace {

// The share of the GPU's memory the path slots may take: a quarter (the scene, its BVH, the
// film and the sampler's tables, rll's learning state among them, take the rest).
size_t device_slot_budget() {
  size_t free = 0, total = 0;
  check(cudaMemGetInfo(&free, &total), "cudaMemGetInfo");
  return total / 4;
}

}  // namespace

struct GpuRenderer::Impl {
  std::string name;
  Bvh bvh;
  std::optional<SceneData> data;
  std::optional<DeviceScene> scene;
  DeviceMirror bvh_memory;    // the BVH, uploaded again after each refit
  DeviceMirror sobol_memory;  // the Sobol' tables, uploaded once
  BvhView bvh_view;
  SobolView sobol;
  size_t render_bytes = 0;  // the most the last render took besides the above
  // A learner's state (lights/resident.h: rll's, fermat's), kept here from render to render
  // while it holds it (DeviceRll::holds); a learner that took it back since is uploaded anew.
  // One at a time: another learner's render hands the state back first.
  std::unique_ptr<DeviceRll> rll;
  // Kept from render to render (interactive's frames take no new memory): the path slots and
  // the stages' events, another sampler's tables (uploaded again each render into the memory
  // the last one freed: the cache of launch.cuh), the film and its pinned host copy.
  CudaWavefrontBackend backend;
  DeviceSampler device_sampler;
  DeviceArray<double> film_sum;
  DeviceArray<uint32_t> film_count;
  PinnedBuffer film_pinned;
  // The path-space filter's temporal reuse (render/psf.h): its two tables of cells, kept here from
  // frame to frame, made at the first render with psf.temporal that has frames around it (a
  // still render takes none: RenderSettings::precedes_frame).
  DeviceArray<uint64_t> psf_keys[2];
  DeviceArray<ExactSum> psf_sums[2];
  DeviceArray<uint32_t> psf_used;
  PsfFrameCells psf_frames;
  PsfFrameCells* psf_cells(const IntegratorSettings& is, const RenderSettings& rs, size_t pixels) {
    if (!psf_temporal_frames(is.psf, rs)) return nullptr;
    if (psf_frames.pixels != pixels) {
      check_psf_memory(pixels, true);
      psf_frames = PsfFrameCells{};
      const size_t cells = psf_capacity(pixels);
      psf_used = DeviceArray<uint32_t>(2);
      for (int i = 0; i < 2; ++i) {
        psf_keys[i] = DeviceArray<uint64_t>();
        psf_sums[i] = DeviceArray<ExactSum>();
        psf_keys[i] = DeviceArray<uint64_t>(cells);
        psf_sums[i] = DeviceArray<ExactSum>(6 * cells);
        psf_frames.tables[i] = {psf_keys[i].view(), psf_sums[i].view(), psf_used.view().data + i};
      }
      psf_frames.pixels = pixels;
    }
    return &psf_frames;
  }
  // ReSTIR's history (render/restir.h): the last sample's vertex records, Bsdfs and final
  // reservoirs, kept here from frame to frame, made at the first restir render; one history, so
  // a render of another restir spec (WavefrontSettings::restir_spec) starts it afresh.
  DeviceArray<RestirVertex> restir_vertex[2];
  DeviceArray<Bsdf> restir_bsdf[2];
  DeviceArray<Reservoir> restir_final[2];
  RestirFrames restir_frames;
  std::string restir_spec;
  RestirFrames* restir_history(const IntegratorSettings& is, size_t pixels,
                               const std::string& spec) {
    if (!is.restir.on) return nullptr;
    if (restir_frames.pixels != pixels) {
      check_restir_memory(pixels);
      restir_frames = RestirFrames{};
      for (int i = 0; i < 2; ++i) {
        restir_vertex[i] = DeviceArray<RestirVertex>();
        restir_bsdf[i] = DeviceArray<Bsdf>();
        restir_final[i] = DeviceArray<Reservoir>();
        restir_vertex[i] = DeviceArray<RestirVertex>(pixels);
        restir_bsdf[i] = DeviceArray<Bsdf>(pixels);
        restir_final[i] = DeviceArray<Reservoir>(pixels);
        restir_frames.vertex[i] = restir_vertex[i].view();
        restir_frames.bsdf[i] = restir_bsdf[i].view();
        restir_frames.final_[i] = restir_final[i].view();
      }
      restir_frames.pixels = pixels;
    }
    if (spec != restir_spec) restir_frames.holds = false;
    restir_spec = spec;
    return &restir_frames;
  }
  size_t restir_bytes() const {
    size_t bytes = 0;
    for (int i = 0; i < 2; ++i)
      bytes += restir_vertex[i].bytes() + restir_bsdf[i].bytes() + restir_final[i].bytes();
    return bytes;
  }
  // The film that stayed here after the last render (WavefrontSettings::film_stays_on_device),
  // its host copy out of date, and its fewest samples per pixel.
  const Film* resident = nullptr;
  int resident_width = 0;
  uint32_t resident_min = 0;

  // The host film into the device's (the same size), through the pinned copy.
  void upload_film(Film& film) {
    const FilmView h = film.view();
    const size_t sum_bytes = h.sum.size * sizeof(double), count_bytes = h.count.size * 4;
    unsigned char* pinned = film_pinned.get(sum_bytes + count_bytes);
    std::memcpy(pinned, h.sum.data, sum_bytes);
    std::memcpy(pinned + sum_bytes, h.count.data, count_bytes);
    check(cudaMemcpyAsync(film_sum.view().data, pinned, sum_bytes, cudaMemcpyHostToDevice),
          "cudaMemcpyAsync");
    check(cudaMemcpyAsync(film_count.view().data, pinned + sum_bytes, count_bytes,
                          cudaMemcpyHostToDevice),
          "cudaMemcpyAsync");
    count::launch(2);
    count::to_device(sum_bytes + count_bytes);
  }
  // Queues the device's film's copy into the pinned memory; film_arrived() after a wait.
  void queue_film_download() {
    const size_t sum_bytes = film_sum.bytes(), count_bytes = film_count.bytes();
    unsigned char* pinned = film_pinned.get(sum_bytes + count_bytes);
    check(cudaMemcpyAsync(pinned, film_sum.view().data, sum_bytes, cudaMemcpyDeviceToHost),
          "cudaMemcpyAsync");
    check(cudaMemcpyAsync(pinned + sum_bytes, film_count.view().data, count_bytes,
                          cudaMemcpyDeviceToHost),
          "cudaMemcpyAsync");
    count::launch(2);
    count::to_host(sum_bytes + count_bytes);
  }
  void film_arrived(Film& film) {
    const FilmView h = film.view();
    const size_t sum_bytes = h.sum.size * sizeof(double), count_bytes = h.count.size * 4;
    const unsigned char* pinned = film_pinned.get(sum_bytes + count_bytes);
    std::memcpy(h.sum.data, pinned, sum_bytes);
    std::memcpy(h.count.data, pinned + sum_bytes, count_bytes);
  }
  void download_film(Film& film) {
    queue_film_download();
    check(cudaStreamSynchronize(0), "cudaStreamSynchronize");
    count::sync();
    film_arrived(film);
  }

  // The scene and the BVH (again after a frame's refit).
  void upload(const Scene& s) {
    data.reset();
    scene.reset();
    bvh_memory.clear();
    data.emplace(s);
    scene.emplace(data->view());
    bvh_view.nodes = bvh_memory.mirror(bvh.view().nodes);
    bvh_view.triangles = bvh_memory.mirror(bvh.view().triangles);
  }
};

GpuRenderer::GpuRenderer(const Scene& scene) : m_impl(std::make_unique<Impl>()) {
  require_gpu();
  // The name of the device the kernels run on (CUDA's current one).
  int device = 0;
  cudaDeviceProp props{};
  check(cudaGetDevice(&device), "cudaGetDevice");
  check(cudaGetDeviceProperties(&props, device), "cudaGetDeviceProperties");
  m_impl->name = props.name;
  const SobolTables& t = host_sobol_tables();
  m_impl->sobol.tables =
      m_impl->sobol_memory.mirror(View<const uint32_t>{t.view().tables, t.size()}).data;
  m_impl->bvh = build_bvh(scene.mesh);
  m_impl->upload(scene);
}

GpuRenderer::~GpuRenderer() = default;

void GpuRenderer::update(const Scene& scene) {
  m_impl->bvh.refit(scene.mesh);
  m_impl->upload(scene);
}

size_t GpuRenderer::device_bytes() const {
  return m_impl->bvh_memory.bytes() + m_impl->sobol_memory.bytes() +
         (m_impl->scene ? m_impl->scene->bytes() : 0) + m_impl->render_bytes;
}

size_t GpuRenderer::psf_temporal_bytes() const {
  // (Either table: the other replaces the one a render without temporal reuse takes.)
  return m_impl->psf_keys[1].bytes() + m_impl->psf_sums[1].bytes();
}

const std::string& GpuRenderer::device_name() const {
  return m_impl->name;
}

void GpuRenderer::download_film(Film& film) {
  if (m_impl->resident == &film) m_impl->download_film(film);
}

RenderProgress GpuRenderer::render(
    const Scene& scene, LightSampler& sampler, const IntegratorSettings& integrator, Film& film,
    const RenderSettings& settings, const std::atomic<bool>* cancel,
    const std::function<void(const RenderProgress&, const Film&)>& after_pass,
    const WavefrontSettings& wavefront) {
  // (A learner's view is not asked for: that would take its state back from here.)
  ResidentLearner* const rll = sampler.resident_learner();
  if (!rll) require_device_version(sampler, sampler.name());
  const auto t_start = std::chrono::steady_clock::now();
  const DeviceWork work_start = device_work();
  Impl& m = *m_impl;
  // A learning rll or fermat: its state resident here (uploaded only where it is not here
  // already: the host took it back since, or another learner's was); every other sampler's tables
  // uploaded for this render.
  auto hold_learner = [&] {
    if (m.rll && m.rll->holds(*rll)) return;
    m.rll.reset();  // (the last learner's state back to it, and its memory, first)
    m.rll = std::make_unique<DeviceRll>(*rll);
  };
  DeviceSampler& device_sampler = m.device_sampler;
  if (rll)
    hold_learner();
  else
    device_sampler.upload(sampler.sampler_view());
  const bool learns = rll || sampler.sampler_view().learns;
  auto sampler_view = [&] { return rll ? m.rll->sampler_view() : device_sampler.view(); };

  // The film's sums and counts on the device: where the film stayed here after the last render,
  // continued; else uploaded from the host's.
  const size_t pixels = size_t(film.width()) * film.height();
  const bool continues = wavefront.film_stays_on_device && m.resident == &film &&
                         m.resident_width == film.width() && m.film_count.size() == pixels;
  m.resident = nullptr;  // (again where this render ends with the film kept here)
  uint32_t start_min = m.resident_min;
  if (!continues) {
    if (m.film_count.size() != pixels) {
      m.film_sum = DeviceArray<double>();
      m.film_count = DeviceArray<uint32_t>();
      m.film_sum = DeviceArray<double>(3 * pixels);
      m.film_count = DeviceArray<uint32_t>(pixels);
    }
    m.upload_film(film);
    start_min = film.min_count();
  }
  const FilmView device_film = {m.film_sum.view(), m.film_count.view(), film.width()};
  check_nee_settings(integrator, sampler_view(), sampler.name());
  const auto k = wavefront_kernels(scene, m.scene->view(), integrator, device_film, m.sobol,
                                   BvhTracer{m.bvh_view}, sampler_view());
  const size_t draws = size_t(nee_draws_per_vertex(sampler_view()));

  CudaWavefrontBackend& backend = m.backend;
  backend.begin(wavefront.times);
  const size_t budget = device_slot_budget();
  const size_t slots = render_path_slots(wavefront, film, settings, budget, kMaxPathSlots, draws,
                                         integrator.restir.on, draws_several(sampler_view()));
  WavefrontDriver<CudaWavefrontBackend, BvhTracer> driver(
      backend, k, slots, m.psf_cells(integrator, settings, pixels), settings.follows_frame,
      m.restir_history(integrator, pixels, wavefront.restir_spec));
  m.render_bytes = 0;
  auto note_bytes = [&] {
    m.render_bytes = std::max(m.render_bytes, backend.bytes() + device_sampler.bytes() +
                                                  (rll ? m.rll->bytes() : 0) + m.film_sum.bytes() +
                                                  m.film_count.bytes() + m.psf_keys[0].bytes() +
                                                  m.psf_keys[1].bytes() + m.psf_sums[0].bytes() +
                                                  m.psf_sums[1].bytes() + m.restir_bytes());
  };
  note_bytes();
  // rll's end of pass runs on its copy here (the learner's own end_pass: only the counters come
  // back). Another sampler learns nothing within a pass (its tables are what was uploaded:
  // nothing to copy either way) and its end of pass is the host's.
  auto end_pass = [&] {
    backend.timed(WavefrontStage::EndPass, [&] {
      if (rll) {
        // An after_pass that read the state took it back: this copy is still that state with
        // this pass's records on top (the host changed nothing since), so it is lent as it is.
        if (!m.rll->holds(*rll)) m.rll->lend(*rll);
        sampler.end_pass();
      } else if (learns) {
        device_sampler.copy_back();
        sampler.end_pass();
        device_sampler.upload(sampler.sampler_view());
      } else {
        sampler.end_pass();
      }
    });
    note_bytes();
    driver.set_sampler(sampler_view());
  };
  // The film comes back only where the host reads it: before an after_pass that reads it, after
  // a stopped pass, and after the last pass unless it stays here; in the pass's one wait.
  bool host_film_current = !continues;
  WavefrontFilmHooks hooks;
  hooks.start_min_count = start_min;
  hooks.copy_film = [&](bool last, bool complete) {
    host_film_current = false;
    const bool wanted = (wavefront.after_pass_reads_film && after_pass) || !complete ||
                        (last && !wavefront.film_stays_on_device);
    if (wanted) m.queue_film_download();
    return wanted;
  };
  hooks.film_arrived = [&] {
    m.film_arrived(film);
    host_film_current = true;
  };
  const RenderProgress progress = run_wavefront_passes(
      scene, driver, end_pass, hooks, film, settings, cancel, after_pass,
      [] { return device_work(); }, work_start, wavefront.work ? &wavefront.work->passes : nullptr);
  backend.collect_times();
  if (wavefront.film_stays_on_device) {
    m.resident = &film;
    m.resident_width = film.width();
    m.resident_min = uint32_t(progress.spp_done);
  } else if (!host_film_current) {
    m.download_film(film);  // (the last pass brings it; this only where none ran to its end)
  }
  // What the last pass learnt, for a state saved after the render (rll's: pulled when the host
  // reads it).
  if (!rll) device_sampler.copy_back();
  if (wavefront.times)
    wavefront.times->total_seconds +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  return progress;
}

}  // namespace rll::cuda
