// `rll samplers`: the light sampler names, one a line (scripts pick from them).
#include <fmt/format.h>

#include "commands.h"
#include "rll/lights/light_sampler.h"

namespace rll::cli {

void add_samplers_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("samplers",
                                 "List the light samplers (use them with --sampler/--samplers)");
  cmd->callback([] {
    for (const auto& name : light_sampler_names()) fmt::print("{}\n", name);
  });
}

}  // namespace rll::cli
