// The GPU side of the check that the light samplers' dispatch is device code (issue 31): the
// device instantiates prepare_point, sample_light, light_pmf and record_nee for every SamplerKind,
// and a kernel runs sampler_probe over device copies of a SamplerView's arrays.
#include <vector>

#include "rll/cuda/device_sampler.cuh"
#include "rll/cuda/launch.cuh"
#include "rll/cuda/sampler_check.h"

namespace rll {

std::vector<SamplerProbeResult> sampler_probe_gpu(const SamplerView& s,
                                                  const std::vector<SamplerProbe>& probes) {
  cuda::DeviceSampler d;
  d.upload(s);
  cuda::DeviceArray<SamplerProbe> d_probes(probes.size());
  d_probes.upload(probes);
  cuda::DeviceArray<SamplerProbeResult> d_out(probes.size());
  const SamplerView view = d.view();
  const View<const SamplerProbe> in = d_probes.view();
  const View<SamplerProbeResult> out = d_out.view();
  cuda::parallel_for(probes.size(), [=] RLL_HD(size_t i) { out[i] = sampler_probe(view, in[i]); });
  return d_out.download();
}

}  // namespace rll
