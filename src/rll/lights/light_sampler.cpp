#include "rll/lights/light_sampler.h"

#include "rll/core/error.h"
#include "rll/core/params.h"
#include "rll/lights/ltc_sampler.h"
#include "rll/lights/oracle_sampler.h"
#include "rll/lights/rht_sampler.h"
#include "rll/lights/rll_sampler.h"
#include "rll/lights/rll_study.h"
#include "rll/lights/simple_samplers.h"
#include "rll/lights/tree_sampler.h"

namespace rll {

const std::vector<std::string>& light_sampler_names() {
  static const std::vector<std::string> names = {"uniform", "power", "tree", "fermat",
                                                 "ltc",     "rht",   "rll",  "oracle"};
  return names;
}

namespace {
[[noreturn]] void unknown_sampler(const std::string& name) {
  std::string list;
  for (const auto& n : light_sampler_names()) list += (list.empty() ? "" : ", ") + n;
  fail("unknown light sampler '{}' (valid: {})", name, list);
}

// rll's parameters, then its study settings (rll.ideal_*, read apart: rll_settings.h).
std::vector<std::string> rll_parameter_lines() {
  std::vector<std::string> out = describe_rll_params(RllSettings{}, "rll");
  for (auto& line : describe_params(rll_study_params(), "rll", RllStudy{})) out.push_back(line);
  return out;
}

// rll, or the oracle (`oracle`: the oracle asked for by name), with the error budget's study
// settings (RllStudy) swapped in: the oracle's cluster table for rll.ideal_cluster, the ideal
// light within a cluster around either for rll.ideal_light. (rll.ideal_point and ideal_bsdf are
// the integrator's: render/integrator.cpp.)
std::unique_ptr<LightSampler> make_rll_study(bool oracle, const Scene& scene, const LightTree& tree,
                                             const Params& params, const Accel* accel) {
  const RllStudy study = rll_study_from(params);
  if (oracle && study.cluster)
    fail("--set rll.ideal_cluster=1: the oracle's table is already its own (leave it out)");
  if (study.light_at_point && study.light == 0)
    fail("--set rll.ideal_light_at=point: give rll.ideal_light, the shadow rays per light");
  if (oracle && !accel)
    fail("the oracle sampler traces rays before rendering and needs the scene's ray tracer");
  if ((study.cluster || study.light > 0) && !accel)
    fail("rll.ideal_cluster and rll.ideal_light trace rays and need the scene's ray tracer");
  std::unique_ptr<LightSampler> s;
  if (oracle || study.cluster) {
    // The oracle samples with RLL's settings (rll.*), so that only the learning differs. As
    // rll.ideal_cluster it keeps rll's own cut (oracle.refine 0 unless given): only the table
    // over the same clusters changes.
    OracleSettings os = oracle_settings_from(params);
    if (study.cluster && !params.has("oracle.refine")) os.refine = 0;
    s = std::make_unique<OracleLightSampler>(scene, tree, *accel, rll_settings_from(params), os);
  } else {
    s = std::make_unique<RllLightSampler>(scene, tree, rll_settings_from(params));
  }
  if (study.light > 0)
    s = std::make_unique<IdealLightSampler>(std::move(s), scene, *accel, study.light,
                                            study.light_at_point);
  return s;
}
}  // namespace

std::vector<std::string> light_sampler_parameters(const std::string& name) {
  if (name == "rll") return rll_parameter_lines();
  if (name == "fermat") return describe_rll_params(fermat_settings(), "fermat");
  if (name == "rht") return describe_params(rht_params(), "rht", RhtSettings{});
  if (name == "oracle") {
    std::vector<std::string> out = describe_params(oracle_params(), "oracle", OracleSettings{});
    for (auto& line : rll_parameter_lines()) out.push_back(line);
    return out;
  }
  if (name == "ltc") return describe_params(ltc_params(), "ltc", LtcSettings{});
  for (const auto& n : light_sampler_names())
    if (n == name) return {};
  unknown_sampler(name);
}

std::unique_ptr<LightSampler> make_light_sampler(const std::string& name, const Scene& scene,
                                                 const LightTree& tree, const Params& params,
                                                 const Accel* accel) {
  if (name == "uniform") return std::make_unique<UniformLightSampler>(scene);
  if (name == "power") return std::make_unique<PowerLightSampler>(scene);
  if (name == "tree") return std::make_unique<TreeLightSampler>(scene, tree);
  if (name == "rll" || name == "oracle")
    return make_rll_study(name == "oracle", scene, tree, params, accel);
  if (name == "fermat")  // the paper's RLL as published: rll with Fermat's settings (fermat.*)
    return std::make_unique<RllLightSampler>(
        scene, tree, rll_settings_from(params, "fermat", fermat_settings()));
  if (name == "ltc")
    return std::make_unique<LtcLightSampler>(scene, tree, ltc_settings_from(params));
  if (name == "rht")
    return std::make_unique<RhtLightSampler>(scene, tree, rht_settings_from(params));
  unknown_sampler(name);
}

}  // namespace rll
