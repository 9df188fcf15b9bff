// Light-sampler tests' set-up: a built-in scene ready for sampler checks, and shading contexts in
// it (points seen by the camera and random surface points).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "rll/accel/accel.h"
#include "rll/core/rng.h"
#include "rll/lights/light_dispatch.h"
#include "rll/lights/light_sampler.h"
#include "rll/lighttree/light_tree.h"
#include "rll/scene/scene.h"

namespace rll::test {

// A built-in scene ready for sampler checks: at 48x36 pixels (the cells' level of detail reads the
// camera's pixel footprint), finalized, with its light tree and ray tracer, and the light sampler
// `sampler` made with `set` (`--set` key=value, each key checked used; the oracle gets the
// tracer, which no other sampler reads).
struct SamplerScene {
  Scene scene;
  std::unique_ptr<LightTree> tree;  // (held by pointer: the sampler keeps its address)
  std::unique_ptr<Accel> accel;
  std::unique_ptr<LightSampler> sampler;
};
SamplerScene sampler_scene(const std::string& scene_name, const std::string& sampler,
                           const std::vector<std::string>& set);

// `count` contexts: half on surfaces seen through random pixels, half uniformly by area over
// the non-sky triangles with a random side. Deterministic for a given seed.
std::vector<LightContext> make_contexts(const Scene& scene, const Accel& accel, int count,
                                        uint64_t seed);

// True if some point of the light emits towards p and lies above the surface (n), ignoring
// occlusion: then a sampler must give the light a nonzero probability.
bool light_can_contribute(const Light& light, const Vec3& p, const Vec3& n);

// Renders `spp` samples per pixel of the scene with `path` (3 vertices), one per pass, with
// `sampler`; the image is dropped.
void render_path_passes(const Scene& scene, const Accel& accel, LightSampler& sampler, int spp,
                        PointSet points = PointSet::Sobol);

// The light-sampler contract at contexts already prepared by `sampler`, through the dispatch over
// its view (light_dispatch.h): sample_light's pmf equals light_pmf exactly and is positive, pmfs
// sum to one, stratified u draws each light N * pmf times to within two draws, and independent
// draws fit N * pmf (chi-square, Sidak-corrected over 4 contexts).
void expect_sampler_contract(const LightSampler& sampler, const std::vector<LightContext>& contexts,
                             uint32_t lights);

// Trains a learning sampler by rendering `passes` passes of the scene (no-op otherwise).
void train_sampler(const Scene& scene, const Accel& accel, LightSampler& sampler, int passes,
                   PointSet points = PointSet::Sobol);

}  // namespace rll::test
