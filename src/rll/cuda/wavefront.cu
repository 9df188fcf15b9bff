// The GPU's side of the wavefront renderer: the CUDA backend of wavefront/driver.h (device memory,
// launches over queues, CUDA events), the scene, BVH, Sobol' tables and film in device memory, and
// the light sampler's tables there: rll's learning state resident across passes and renders, its
// end of pass run there (cuda/device_rll.cuh); the other samplers' tables, which do not learn,
// mirrored around each (empty) end of pass as before.
#include <cuda_runtime.h>

#include <algorithm>
#include <chrono>
#include <optional>

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

template <typename Body>
__global__ void queue_kernel(WavefrontQueue q, uint32_t upper, Body body) {
  const uint32_t k = blockIdx.x * blockDim.x + threadIdx.x;
  if (k < upper && k < q.count()) body(q.slots[k]);
}

// The GPU's side of wavefront/driver.h.
class CudaWavefrontBackend {
 public:
  explicit CudaWavefrontBackend(WavefrontTimes* times) : m_times(times) {}

  template <typename T>
  View<T> take(size_t n) {
    void* p = m_memory.allocate(n * sizeof(T));
    check(cudaMemset(p, 0, n * sizeof(T)), "cudaMemset");
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
  }
  void zero(void* p, size_t bytes) { check(cudaMemsetAsync(p, 0, bytes), "cudaMemsetAsync"); }
  void write(uint32_t* p, uint32_t v) {
    check(cudaMemcpy(p, &v, sizeof v, cudaMemcpyHostToDevice), "cudaMemcpy");
  }
  void copy(uint32_t* to, const uint32_t* from) {
    check(cudaMemcpyAsync(to, from, sizeof(uint32_t), cudaMemcpyDeviceToDevice), "cudaMemcpy");
  }
  template <typename T>
  T read(const T* p) {
    T v;
    check(cudaMemcpy(&v, p, sizeof(T), cudaMemcpyDeviceToHost), "cudaMemcpy");
    return v;
  }
  // The kernels' time by CUDA events; the end of a pass (host work and copies) by the wall clock.
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
    m_timer.start();
    fn();
    (*m_times)[stage] += m_timer.stop_ms() * 1e-3;
  }
  size_t bytes() const { return m_memory.bytes(); }

 private:
  DeviceMirror m_memory;
  WavefrontTimes* m_times;
  EventTimer m_timer;
};

ViewSampler view_sampler(const SamplerView& v, const LightSampler& s) {
  return {v, s.prepares(), s.learns()};
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
  // rll's learning state, kept here from render to render while the sampler's state is this
  // (RllLightSampler::remote); a sampler whose host arrays changed since is uploaded anew.
  std::shared_ptr<DeviceRll> rll;

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

const std::string& GpuRenderer::device_name() const {
  return m_impl->name;
}

RenderProgress GpuRenderer::render(
    const Scene& scene, LightSampler& sampler, const IntegratorSettings& integrator, Film& film,
    const RenderSettings& settings, const std::atomic<bool>* cancel,
    const std::function<void(const RenderProgress&, const Film&)>& after_pass,
    const WavefrontSettings& wavefront) {
  require_device_version(sampler, sampler.name());
  const auto t_start = std::chrono::steady_clock::now();
  Impl& m = *m_impl;
  // A learning rll or fermat: its state resident here (uploaded only where the host's arrays are
  // newer); every other sampler's tables uploaded for this render.
  auto* rll = dynamic_cast<RllLightSampler*>(&sampler);
  if (rll && !rll->learns()) rll = nullptr;
  DeviceSampler device_sampler;
  if (rll) {
    if (!m.rll || rll->remote() != m.rll.get()) {
      rll->sync();
      m.rll.reset();  // (its memory first)
      m.rll = std::make_shared<DeviceRll>(*rll);
    }
    m.rll->make_remote(*rll);
  } else {
    device_sampler.upload(sampler.sampler_view());
  }
  auto sampler_view = [&] { return rll ? m.rll->sampler_view() : device_sampler.view(); };

  // The film's sums and counts on the device, starting from the host film's.
  FilmView host_film = film.view();
  DeviceMirror film_memory;
  const FilmView device_film = {film_memory.mirror(host_film.sum),
                                film_memory.mirror(host_film.count), film.width()};
  const auto k = wavefront_kernels(scene, m.scene->view(), integrator, device_film, m.sobol,
                                   BvhTracer{m.bvh_view}, view_sampler(sampler_view(), sampler));

  CudaWavefrontBackend backend(wavefront.times);
  WavefrontDriver<CudaWavefrontBackend, BvhTracer, ViewSampler> driver(
      backend, k, wavefront_slot_count(wavefront.path_slots, film, settings.spp));
  m.render_bytes = 0;
  auto note_bytes = [&] {
    m.render_bytes = std::max(m.render_bytes, backend.bytes() + device_sampler.bytes() +
                                                  (rll ? m.rll->bytes() : 0) + film_memory.bytes());
  };
  note_bytes();
  // rll's end of pass on the device: only its counters come back. (Other samplers learn nothing
  // on the device: their end_pass is the host's, as before.)
  auto end_pass = [&] {
    backend.timed(WavefrontStage::EndPass, [&] {
      if (rll) {
        m.rll->end_pass(*rll);
      } else {
        device_sampler.copy_back();
        sampler.end_pass();
        device_sampler.upload(sampler.sampler_view());
      }
    });
    note_bytes();
    driver.set_sampler(view_sampler(sampler_view(), sampler));
  };
  const RenderProgress progress = run_wavefront_passes(
      scene, driver, end_pass, [&] { film_memory.copy_back(); }, film, settings, cancel,
      after_pass);
  // What the last pass learnt, for a state saved after the render (rll's: pulled when the host
  // reads it).
  if (!rll) device_sampler.copy_back();
  if (wavefront.times)
    wavefront.times->total_seconds +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  return progress;
}

}  // namespace rll::cuda
