#include <fmt/format.h>

#include "commands.h"
#include "rll/scene/builtin.h"

namespace rll::cli {

void add_scenes_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("scenes", "List the built-in scenes (render them as builtin:NAME)");
  cmd->callback([] {
    for (const auto& s : builtin_scenes()) fmt::print("{:<22} {}\n", s.name, s.description);
  });
}

}  // namespace rll::cli
