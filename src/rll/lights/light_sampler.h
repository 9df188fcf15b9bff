// The light-sampler contract shared by every sampler (uniform, power, tree, rll, fermat, ltc, rht,
// oracle), in two parts. Sampling is data: sampler_view() gives the SamplerView that every
// renderer and tool hands to the one dispatch (lights/light_dispatch.h: prepare_point,
// sample_light, light_pmf, record_nee), where sample and pmf agree exactly. This class keeps the
// host's lifecycle around it: the view, the end of a pass, lights that changed, the learnt state
// saved and loaded, and what --stats reports.
#pragma once

#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
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
class ResidentLearner;
class RllLightSampler;
class OracleLightSampler;

// The learnt cells a diagnostic reads (--aov, compare's cell chart, python's State), as the
// sampler that holds them says: rll's and fermat's own, the oracle's frozen rll's. `oracle` is set
// for the oracle, whose `rewards` are the shadow rays of its estimates (it learns from none).
struct LearntCells {
  const RllLightSampler* rll = nullptr;
  const OracleLightSampler* oracle = nullptr;
};

class LightSampler {
 public:
  LightSampler(const LightSampler&) = delete;  // views (and a host kind's calls) point at it
  LightSampler& operator=(const LightSampler&) = delete;
  virtual ~LightSampler() = default;
  // The name the user gives (rll and fermat are one class).
  const std::string& name() const { return m_name; }

  // This sampler as data for the dispatch every renderer runs (light_dispatch.h), valid while the
  // sampler lives and between changes to it (end_pass, lights_changed, load_state). A sampler
  // with no device version is the host kind (host_view below), which a device renderer refuses.
  virtual SamplerView sampler_view() const = 0;
  // Between passes: adapt to what was recorded (no sampling or record_nee runs concurrently).
  virtual void end_pass() {}
  // Lights moved or changed power (animation): refit whatever depends on them.
  virtual void lights_changed(const Scene& scene) { (void)scene; }

  // Learnt state that travels between renders (--rll-state, sampler_state.h): a sampler that has
  // one (has_state) writes it, between passes, and reads it back into a sampler made with the
  // same parameters for the same scene, throwing rll::Error if what it reads is damaged.
  bool has_state() const { return m_has_state; }
  virtual void save_state(BinaryWriter& w) const { (void)w; }
  virtual void load_state(BinaryReader& r) { (void)r; }

  // Name, parameters and statistics for --stats and reports.
  virtual nlohmann::json describe() const { return {{"name", name()}}; }

  // The learning state a device may keep between passes and renders (lights/resident.h: rll and
  // fermat while they learn; the GPU renderer makes its copy from it); null for a sampler that
  // learns nothing or whose tables a device renderer uploads for each render.
  ResidentLearner* resident_learner() const { return m_resident; }
  // Its learnt cells (above); both null for a sampler without cells. Not a virtual method: the
  // sampler sets them (set_learnt_cells) when it makes or remakes its cells.
  const LearntCells& learnt_cells() const { return m_cells; }

 protected:
  explicit LightSampler(std::string name, bool has_state = false)
      : m_name(std::move(name)), m_has_state(has_state) {}
  void set_resident_learner(ResidentLearner* r) { m_resident = r; }
  void set_learnt_cells(const LearntCells& c) { m_cells = c; }

  // The host kind of a sampler with no device version: set_host_calls(*this) once (in the
  // constructor) takes T's prepare(ctx, float), const sample(ctx, double), const pmf(ctx, light)
  // and its record(ctx, sampled, r) if T has them (T's own, private ones too where T befriends
  // LightSampler); host_view() is then its view.
  template <typename T>
  void set_host_calls(const T& self);
  SamplerView host_view(bool prepares, bool learns) const {
    SamplerView v;
    v.kind = SamplerKind::Host;
    v.host = &m_host;
    v.prepares = prepares;
    v.learns = learns;
    return v;
  }

 private:
  std::string m_name;
  bool m_has_state = false;
  ResidentLearner* m_resident = nullptr;
  LearntCells m_cells;
  HostSampler m_host;
};

template <typename T>
void LightSampler::set_host_calls(const T& self) {
  m_host.self = &self;
  // prepare may change the sampler too (ltc makes a point's entry there, thread-safely): then it
  // is called, as record is, on the object the view holds as const.
  m_host.prepare = [](const void* s, LightContext& ctx, float u) {
    if constexpr (requires(const T& t) { t.prepare(ctx, u); })
      static_cast<const T*>(s)->prepare(ctx, u);
    else if constexpr (requires(T & t) { t.prepare(ctx, u); })
      const_cast<T*>(static_cast<const T*>(s))->prepare(ctx, u);
  };
  m_host.sample = [](const void* s, const LightContext& ctx, double u) {
    return static_cast<const T*>(s)->sample(ctx, u);
  };
  m_host.pmf = [](const void* s, const LightContext& ctx, uint32_t light) {
    return static_cast<const T*>(s)->pmf(ctx, light);
  };
  // record changes the sampler (thread-safely); the view holds it as const like every view.
  m_host.record = [](const void* s, const LightContext& ctx, const SampledLight& l,
                     const NeeRecord& r) {
    if constexpr (requires(T & t) { t.record(ctx, l, r); })
      const_cast<T*>(static_cast<const T*>(s))->record(ctx, l, r);
  };
}

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
