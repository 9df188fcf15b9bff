// `rll filters`: the filters `--filter` takes, one a line; with `--params psf`, the path-space
// filter's keys (--set psf.KEY=VALUE) with their defaults and ranges, from the table that reads
// and checks them (render/psf.h).
#include <fmt/format.h>

#include "commands.h"
#include "rll/core/error.h"
#include "rll/core/params.h"
#include "rll/render/psf.h"

namespace rll::cli {

void add_filters_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "filters", "List the image filters of --filter (none, psf: path-space filtering)");
  auto params = std::make_shared<std::string>();
  cmd->add_option("--params", *params,
                  "List a filter's parameters (--set psf.KEY=VALUE): each key, its default and "
                  "its range");
  cmd->callback([params] {
    if (params->empty()) {
      for (const auto& name : filter_names()) fmt::print("{}\n", name);
      return;
    }
    if (*params == "none") {
      fmt::print("none has no parameters\n");
      return;
    }
    if (*params != "psf")
      fail("--params '{}': not a filter (valid: {})", shown_text(*params), "none, psf");
    for (const auto& line : describe_params(psf_params(), "psf", PsfSettings{}))
      fmt::print("{}\n", line);
  });
}

}  // namespace rll::cli
