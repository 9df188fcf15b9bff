// Subcommands of the `rll` program.
#pragma once

#include <CLI/CLI.hpp>

namespace rll::cli {

void add_render_command(CLI::App& app);
void add_scenes_command(CLI::App& app);

// Set by SIGINT: renders stop at the next tile and still write what they have.
bool interrupted();
const std::atomic<bool>* interrupt_flag();
void install_interrupt_handler();

}  // namespace rll::cli
