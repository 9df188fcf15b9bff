// `rll samplers`: the light sampler names, one a line (scripts pick from them); with
// `--params NAME`, a learning sampler's parameters with their defaults and ranges.
#include <fmt/format.h>

#include "commands.h"
#include "rll/lights/light_sampler.h"
#include "rll/render/restir.h"

namespace rll::cli {

void add_samplers_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("samplers",
                                 "List the light samplers (use them with --sampler/--samplers)");
  auto params = std::make_shared<std::string>();
  cmd->add_option("--params", *params,
                  "List a sampler's parameters (--set NAME.KEY=VALUE): each key, its default and "
                  "its range or choices");
  cmd->callback([params] {
    if (params->empty()) {
      for (const auto& name : sampler_names()) fmt::print("{}\n", name);
      return;
    }
    const auto lines = *params == "restir"
                           ? describe_params(restir_params(), "restir", RestirSettings{})
                           : light_sampler_parameters(*params);
    if (lines.empty()) fmt::print("{} has no parameters of its own\n", *params);
    for (const auto& line : lines) fmt::print("{}\n", line);
  });
}

}  // namespace rll::cli
