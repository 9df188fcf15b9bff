// `rll samplers`: the light sampler names, one a line (scripts pick from them); with
// `--params NAME`, a learning sampler's parameters with their defaults and ranges.
#include <fmt/format.h>

#include "commands.h"
#include "rll/core/error.h"
#include "rll/lights/light_sampler.h"
#include "rll/lights/rll_settings.h"

namespace rll::cli {

void add_samplers_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("samplers",
                                 "List the light samplers (use them with --sampler/--samplers)");
  auto params = std::make_shared<std::string>();
  cmd->add_option("--params", *params,
                  "List the parameters of rll or fermat (--set NAME.KEY=VALUE): each key, its "
                  "default and its range or choices");
  cmd->callback([params] {
    if (params->empty()) {
      for (const auto& name : light_sampler_names()) fmt::print("{}\n", name);
      return;
    }
    if (*params != "rll" && *params != "fermat")
      fail("--params {}: only the learning samplers (rll, fermat) have a parameter table; the "
           "README and docs/ describe the others'",
           *params);
    const RllSettings s = *params == "rll" ? RllSettings{} : fermat_settings();
    for (const auto& line : describe_rll_params(s, *params)) fmt::print("{}\n", line);
  });
}

}  // namespace rll::cli
