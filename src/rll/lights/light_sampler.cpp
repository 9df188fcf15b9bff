#include "rll/lights/light_sampler.h"

#include "rll/core/error.h"
#include "rll/core/params.h"
#include "rll/lights/ltc_sampler.h"
#include "rll/lights/oracle_sampler.h"
#include "rll/lights/rht_sampler.h"
#include "rll/lights/rll_sampler.h"
#include "rll/lights/simple_samplers.h"
#include "rll/lights/tree_sampler.h"

namespace rll {

const std::vector<std::string>& light_sampler_names() {
  static const std::vector<std::string> names = {"uniform", "power", "tree", "fermat", "ltc", "rht", "rll", "oracle"};
  return names;
}

namespace {
[[noreturn]] void unknown_sampler(const std::string& name) {
  std::string list;
  for (const auto& n : light_sampler_names()) list += (list.empty() ? "" : ", ") + n;
  fail("unknown light sampler '{}' (valid: {})", name, list);
}
}  // namespace

std::vector<std::string> light_sampler_parameters(const std::string& name) {
  if (name == "rll") return describe_rll_params(RllSettings{}, "rll");
  if (name == "fermat") return describe_rll_params(fermat_settings(), "fermat");
  if (name == "rht") return describe_params(rht_params(), "rht", RhtSettings{});
  if (name == "oracle") {
    std::vector<std::string> out = describe_params(oracle_params(), "oracle", OracleSettings{});
    for (auto& line : describe_rll_params(RllSettings{}, "rll")) out.push_back(line);
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
  if (name == "rll")
    return std::make_unique<RllLightSampler>(scene, tree, rll_settings_from(params));
  if (name == "fermat")  // the paper's RLL as published: rll with Fermat's settings (fermat.*)
    return std::make_unique<RllLightSampler>(
        scene, tree, rll_settings_from(params, "fermat", fermat_settings()));
  if (name == "ltc")
    return std::make_unique<LtcLightSampler>(scene, tree, ltc_settings_from(params));
  if (name == "rht")
    return std::make_unique<RhtLightSampler>(scene, tree, rht_settings_from(params));
  if (name == "oracle") {
    if (!accel) fail("the oracle sampler traces rays before rendering and needs the scene's ray tracer");
    // The oracle samples with RLL's settings (rll.*), so that only the learning differs.
    return std::make_unique<OracleLightSampler>(scene, tree, *accel, rll_settings_from(params),
                                                oracle_settings_from(params));
  }
  unknown_sampler(name);
}

}  // namespace rll
