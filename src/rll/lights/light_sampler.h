// The light-sampler contract shared by every sampler (uniform, power, tree, rll, oracle):
// sample(ctx, u) -> {light, pmf} and pmf(ctx, light) for any light, which must agree exactly.
#pragma once

#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "rll/lights/light_context.h"
#include "rll/lights/sampler_view.h"

namespace rll {

struct Scene;
class Params;
class LightTree;
class Accel;
class BinaryWriter;
class BinaryReader;

class LightSampler {
 public:
  LightSampler();
  LightSampler(const LightSampler&) = delete;  // its host view points at it
  LightSampler& operator=(const LightSampler&) = delete;
  virtual ~LightSampler() = default;
  virtual std::string name() const = 0;

  // Called once per shading point before sample/pmf; a learning sampler finds its cell here.
  // u is a fresh uniform number for any stochastic choice it makes.
  virtual void prepare(LightContext& ctx, float u) const {
    (void)ctx;
    (void)u;
  }
  // True if prepare() does anything: the integrator skips the call, and its random number,
  // for samplers that keep no per-point state.
  virtual bool prepares() const { return false; }
  // u is uniform in [0,1) with 53 bits: descents over millions of lights need them.
  virtual SampledLight sample(const LightContext& ctx, double u) const = 0;
  // Probability that sample(ctx, .) returns `light`.
  virtual float pmf(const LightContext& ctx, uint32_t light) const = 0;

  // Learning samplers only. One call per next-event sample, zeros included (see NeeRecord);
  // safe to call from many threads at once.
  virtual bool learns() const { return false; }
  virtual void record(const LightContext& ctx, const SampledLight& s, const NeeRecord& r) {
    (void)ctx;
    (void)s;
    (void)r;
  }
  // Between passes: adapt to what was recorded (no sample/record calls run concurrently).
  virtual void end_pass() {}
  // Lights moved or changed power (animation): refit whatever depends on them.
  virtual void lights_changed(const Scene& scene) { (void)scene; }

  // Learnt state that travels between renders (--rll-state, sampler_state.h): a sampler that has
  // one writes it, between passes, and reads it back into a sampler made with the same
  // parameters for the same scene, throwing rll::Error if what it reads is damaged.
  virtual bool has_state() const { return false; }
  virtual void save_state(BinaryWriter& w) const { (void)w; }
  virtual void load_state(BinaryReader& r) { (void)r; }

  // This sampler as data for the dispatch every renderer runs (light_dispatch.h), valid while the
  // sampler lives and between changes to it (end_pass, lights_changed, load_state). By default
  // the host kind over this class's calls (a sampler with no device version: a device renderer
  // refuses it).
  virtual SamplerView sampler_view() const;

  // Name, parameters and statistics for --stats and reports.
  virtual nlohmann::json describe() const { return {{"name", name()}}; }

 protected:
  // prepares and learns of this sampler's view (its prepares() and learns()).
  SamplerView with_flags(SamplerView v) const {
    v.prepares = prepares();
    v.learns = learns();
    return v;
  }

 private:
  HostSampler m_host;  // this class's calls, for the default sampler_view()
};

// The sampler names `make_light_sampler` knows, in the order they are listed to users.
const std::vector<std::string>& light_sampler_names();
// A sampler's parameters (`--set NAME.KEY=VALUE`), one a line: each key with its default and its
// range or choices, from the tables that read and check them (the oracle's own, then rll's, which
// it samples with); none for uniform, power and tree. Throws rll::Error for an unknown name.
std::vector<std::string> light_sampler_parameters(const std::string& name);

// Builds a sampler by name with its parameters from `params` (keys "<name>.<param>") over
// `scene` and its light tree (build_light_tree), which the caller holds (the render session
// does) for as long as the sampler lives; throws rll::Error listing valid names on an unknown
// name. The oracle traces rays before rendering and needs `accel`.
std::unique_ptr<LightSampler> make_light_sampler(const std::string& name, const Scene& scene,
                                                 const LightTree& tree, const Params& params,
                                                 const Accel* accel = nullptr);

}  // namespace rll
