// Subcommands of the `rll` program, and the options and checks they share.
#pragma once

#include <CLI/CLI.hpp>
#include <filesystem>
#include <string>
#include <vector>

#include "rll/render/session.h"

namespace rll::cli {

void add_render_command(CLI::App& app);
void add_scenes_command(CLI::App& app);
void add_samplers_command(CLI::App& app);
void add_reference_command(CLI::App& app);
void add_compare_command(CLI::App& app);
void add_convert_command(CLI::App& app);

// Set by SIGINT: renders stop at the next tile and still write what they have.
bool interrupted();
const std::atomic<bool>* interrupt_flag();
void install_interrupt_handler();

// The options of every command that renders a scene: the scene, --integrator, --max-depth,
// --res and --set.
void add_session_options(CLI::App* cmd, SessionSettings& settings);
// Checks an output file's extension before any work is done, and creates its folder.
void prepare_output(const std::filesystem::path& p, const char* flag,
                    const std::vector<std::string>& extensions);
// Creates an output folder (and its parents); throws rll::Error naming the flag.
void prepare_output_dir(const std::filesystem::path& dir, const char* flag);

}  // namespace rll::cli
