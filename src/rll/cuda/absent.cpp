// The CUDA backend where rll was built without nvcc: no GPUs, and a check that says why.
#include "rll/core/error.h"
#include "rll/cuda/cuda.h"
#include "rll/cuda/endpass_check.h"
#include "rll/cuda/onesource_check.h"
#include "rll/cuda/sampler_check.h"
#include "rll/cuda/trace.h"
#include "rll/cuda/wavefront.h"

namespace rll::cuda {

bool cuda_built() {
  return false;
}

std::vector<GpuInfo> gpus() {
  return {};
}

void require_gpu() {
  fail(
      "this rll was built without CUDA (nvcc was not found when it was configured): install the "
      "CUDA toolkit (nvcc on PATH or in /usr/local/cuda/bin) and re-run cmake");
}

// cuda/trace.h: every entry needs a GpuBvh, whose constructor says why there is none.
struct GpuBvh::Impl {};
GpuBvh::GpuBvh(const Bvh&) {
  require_gpu();
}
GpuBvh::~GpuBvh() = default;
size_t GpuBvh::bytes() const {
  return 0;
}
std::vector<Hit> gpu_intersect(const GpuBvh&, const std::vector<Ray>&) {
  require_gpu();
  return {};
}
std::vector<uint8_t> gpu_occluded(const GpuBvh&, const std::vector<Ray>&) {
  require_gpu();
  return {};
}
TraceRate gpu_trace_rate(const GpuBvh&, const std::vector<Ray>&, bool, int) {
  require_gpu();
  return {};
}

// cuda/wavefront.h: the constructor says why there is no GPU renderer.
struct GpuRenderer::Impl {};
GpuRenderer::GpuRenderer(const Scene&) {
  require_gpu();
}
GpuRenderer::~GpuRenderer() = default;
void GpuRenderer::update(const Scene&) {
  require_gpu();
}
size_t GpuRenderer::device_bytes() const {
  return 0;
}
size_t GpuRenderer::psf_temporal_bytes() const {
  return 0;
}
const std::string& GpuRenderer::device_name() const {
  static const std::string none;
  return none;
}
void GpuRenderer::download_film(Film&) {
  require_gpu();
}
RenderProgress GpuRenderer::render(const Scene&, LightSampler&, const IntegratorSettings&, Film&,
                                   const RenderSettings&, const std::atomic<bool>*,
                                   const std::function<void(const RenderProgress&, const Film&)>&,
                                   const WavefrontSettings&) {
  require_gpu();
  return {};
}

}  // namespace rll::cuda

namespace rll {

// cuda/onesource_check.h: the probes of the hot functions need a GPU.
std::vector<OneSourceResult> onesource_probe_gpu(const SceneView&, const std::vector<Hit>&) {
  cuda::require_gpu();
  return {};
}

// cuda/sampler_check.h: the same for the light samplers' dispatch.
std::vector<SamplerProbeResult> sampler_probe_gpu(const SamplerView&,
                                                  const std::vector<SamplerProbe>&) {
  cuda::require_gpu();
  return {};
}

// cuda/endpass_check.h: the end of pass on the GPU.
std::vector<CutPassStats> cut_end_pass_gpu(const CutStoreEndView&, const std::vector<uint32_t>&) {
  cuda::require_gpu();
  return {};
}
RllPassCounts rll_end_pass_gpu(const RllLearnView&, RllPoolState<HostBackend>&, uint32_t, bool) {
  cuda::require_gpu();
  return {};
}
void rll_end_pass_resident_gpu(RllLightSampler&) {
  cuda::require_gpu();
}
void rll_lights_changed_resident_gpu(RllLightSampler&, const Scene&) {
  cuda::require_gpu();
}

}  // namespace rll
