// What the GPU check of the hot functions computes (issue 31): one probe per hit calls the
// surface, texture, BSDF and light functions of scene/ and core/ over a SceneView. The CPU runs
// it directly, the GPU through onesource_probe_gpu (onesource_check.cu); the two must agree
// within float rounding (tests/gpu/test_gpu_onesource.cpp). Plain C++: host code includes it.
#pragma once

#include <cstdint>
#include <vector>

#include "rll/core/hash.h"
#include "rll/core/rng.h"
#include "rll/core/sampling.h"
#include "rll/scene/bsdf.h"
#include "rll/scene/hit.h"
#include "rll/scene/interaction.h"
#include "rll/scene/light.h"
#include "rll/scene/scene_view.h"

namespace rll {

struct OneSourceResult {
  Vec3 p, ns;
  Rgb albedo;
  float roughness = 0;
  Rgb f;          // BSDF eval for a random pair of directions
  float pdf = 0;  // and its pdf
  uint32_t sampled = 0;
  Vec3 wi;  // BSDF sample
  Rgb f_sampled;
  float pdf_sampled = 0;
  Rgb li;  // light sample from p
  float li_pdf = 0, pdf_li = 0;
  Rgb le;  // the light's emission back towards p
  float solid_angle = 0;
};

// Probe `i`: the surface at `hit`, its BSDF for random directions, a sample of a random light.
RLL_HD inline OneSourceResult onesource_probe(const SceneView& scene, const Hit& hit, uint64_t i) {
  Pcg32 rng(mix64(i + 1));
  OneSourceResult r;
  const SurfaceHit sh = make_surface_hit(scene.mesh, hit);
  r.p = sh.p;
  r.ns = sh.ns;
  r.albedo = albedo_at(scene, sh);
  r.roughness = roughness_at(scene, sh);
  const Vec3 wo = sample_uniform_sphere({rng.next_float(), rng.next_float()});
  const Vec3 wi = sample_uniform_sphere({rng.next_float(), rng.next_float()});
  const Bsdf bsdf(scene.materials[sh.material], r.albedo, sh.ns, sh.ng, wo, r.roughness, i);
  r.f = bsdf.eval(wo, wi);
  r.pdf = bsdf.pdf(wo, wi);
  BsdfSample bs;
  const float u_lobe = rng.next_float();
  const Vec2 u = {rng.next_float(), rng.next_float()};
  if (bsdf.sample(wo, u_lobe, u, bs)) {
    r.sampled = 1;
    r.wi = bs.wi;
    r.f_sampled = bs.f;
    r.pdf_sampled = bs.pdf;
  }
  if (!scene.lights.empty()) {
    const Light& light = scene.lights[rng.next_bounded(uint32_t(scene.lights.size))];
    const Vec2 ul = {rng.next_float(), rng.next_float()};
    const LightLiSample ls = sample_li(scene, light, sh.p, ul);
    r.li = ls.L;
    r.li_pdf = ls.pdf;
    if (ls.pdf > 0) {
      r.pdf_li = pdf_li(light, sh.p, ls.point);
      r.le = emitted_radiance(light, -ls.wi);
    }
    if (light.type == LightType::Triangle)
      r.solid_angle = triangle_solid_angle(sh.p, light.p0, light.p1, light.p2);
  }
  return r;
}

// Runs onesource_probe(scene, hits[i], i) for every hit on the GPU, the scene's arrays (host
// memory) copied to the device first. Throws std::runtime_error "CUDA: ..." where CUDA fails.
std::vector<OneSourceResult> onesource_probe_gpu(const SceneView& scene,
                                                 const std::vector<Hit>& hits);

}  // namespace rll
