// The light-sampler contract shared by every sampler (uniform, power, tree, rll, oracle):
// sample(ctx, u) -> {light, pmf} and pmf(ctx, light) for any light, which must agree exactly.
#pragma once

#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "rll/core/math.h"

namespace rll {

struct Scene;
class Params;
class LightTree;
class Accel;
class BinaryWriter;
class BinaryReader;

inline constexpr uint32_t kNoCell = ~0u;

// What a light sampler knows of a shading point.
struct LightContext {
  Vec3 p;
  Vec3 n;   // geometric normal on the side the path arrived from (zero: no surface)
  Vec3 ns;  // shading normal, same side as n
  Vec3 wo;  // direction towards where the path came from (zero: unknown)
  bool glossy = false;  // the surface's BSDF is not Lambertian: its response depends on wo
  float footprint = 0;     // ray footprint radius at this vertex, world units
  uint32_t cell = kNoCell;  // per-point sampler state (an RLL cell), set by prepare()
};

struct SampledLight {
  uint32_t light = 0;
  float pmf = 0;  // 0: nothing was sampled
  // Filled by samplers that choose a cluster first (rll, oracle), for their own record():
  uint32_t cluster = 0;     // index of the cluster in the cell's cut
  float cluster_pmf = 0;    // probability of that cluster
  float cluster_importance = 0;  // rll's guided descent: the tree's importance of the cluster at the point
};

// What the integrator reports of one next-event sample to a learning sampler. Each learner makes
// its own reward of these: rll the cluster's contribution (estimate / P(l | cluster)), Fermat's
// RLL the largest channel of the full weighted contribution over the full pdf, Wang et al. a
// second moment.
struct NeeRecord {
  // Luminance of f * Le * G * V / pdf(y | light): the sample's contribution before dividing by
  // the light's pmf, without the path throughput or the MIS weight.
  float estimate = 0;
  // The same without the shadow ray's verdict (V = 1): zero when the light cannot contribute
  // here at all (behind the surface, outside its emission cone, a black BSDF).
  float unoccluded = 0;
  // MIS weight of the light sample against the BSDF's (1 without MIS).
  float mis_weight = 1;
  // Largest RGB component of throughput * f * Le * G * V * mis_weight / pdf(y | light) (divide
  // by the light's pmf for the full pdf).
  float max_rgb = 0;
};

class LightSampler {
 public:
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

  // Name, parameters and statistics for --stats and reports.
  virtual nlohmann::json describe() const { return {{"name", name()}}; }
};

// The sampler names `make_light_sampler` knows, in the order they are listed to users.
const std::vector<std::string>& light_sampler_names();

// Builds a sampler by name with its parameters from `params` (keys "<name>.<param>");
// throws rll::Error listing valid names on an unknown name. The oracle traces rays before
// rendering and needs `accel`.
std::unique_ptr<LightSampler> make_light_sampler(const std::string& name, const Scene& scene,
                                                 const Params& params, const Accel* accel = nullptr);

}  // namespace rll
