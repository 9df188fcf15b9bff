// Subcommands of the `rll` program, and the options and checks they share.
#pragma once

#include <CLI/CLI.hpp>
#include <atomic>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "rll/session/session.h"

namespace rll::cli {

void add_render_command(CLI::App& app);
void add_scenes_command(CLI::App& app);
void add_samplers_command(CLI::App& app);
void add_filters_command(CLI::App& app);
void add_reference_command(CLI::App& app);
void add_compare_command(CLI::App& app);
void add_convert_command(CLI::App& app);
void add_merge_command(CLI::App& app);
void add_error_command(CLI::App& app);
void add_devices_command(CLI::App& app);
void add_interactive_command(CLI::App& app);

// ASCII lower case (file extensions).
std::string lower(std::string s);

// SIGINT, SIGTERM and SIGHUP: before begin_work() nothing would be lost, so the program ends at
// once; after it, renders stop at the next tile, the command writes what it has and exits with
// 128 + the signal. Further signals only say that it is stopping: they never cut a write short.
bool interrupted();
int interrupt_exit_code();
const std::atomic<bool>* interrupt_flag();
void install_interrupt_handler();
void begin_work();

// What the command is doing now ("loading scene 'x.pbrt'", "rendering 640x480"), for the
// message that a failed allocation gets; commands set it as they go (main thread only).
void set_activity(std::string what);

// Ends a command stopped by a signal once what it had is written: main prints the message and
// exits with interrupt_exit_code().
struct Interrupted : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Checks of numeric flags, shared by every command so that each rejects the same things: the
// whole text must be a number (no wrap-around of an integer past its type, no NaN or infinity),
// within [lo, hi].
CLI::Validator integer_in(long long lo, long long hi);
CLI::Validator unsigned_integer();  // any value of a uint64_t (seeds)
// `positive`: lo itself is refused (a time of 0 seconds).
CLI::Validator number_in(double lo, double hi, bool positive = false);

// Limits shared by the commands' flags.
inline constexpr long long kMaxSpp = (1 << 30) - 1;
inline constexpr long long kMaxPassSpp = 1024;  // passes double from it 20 times at most
inline constexpr long long kMaxThreads = 4096;
// A render writes a file a frame: more than this is a mistake (a --spp in the wrong place?).
inline constexpr long long kMaxFrames = 100000;
inline constexpr double kMaxSeconds = 1e7;
inline constexpr double kMaxExposure = 64;

// The options of every command that renders a scene: the scene, --integrator, --max-depth,
// --res, --points and --set.
void add_session_options(CLI::App* cmd, SessionSettings& settings);
// --wavefront (render and compare): SessionSettings::wavefront.
void add_wavefront_option(CLI::App* cmd, SessionSettings& settings);
// --device cpu|cuda and --tracer embree|bvh (add_wavefront_option adds them too).
void add_device_options(CLI::App* cmd, SessionSettings& settings);

// What the --stats file of every command that renders says of its session: the scene, the
// resolution, the integrator, the renderer and the sample points.
nlohmann::json session_stats(const RenderSession& session);

// The files a scene reads: the scene file itself and, followed through text formats (JSON,
// OBJ, MTL, glTF, pbrt), every existing file they name (meshes, material libraries, buffers,
// textures, includes). Empty for builtin:NAME.
std::vector<std::filesystem::path> scene_inputs(const std::string& spec);
// Throws rll::Error naming both when `out` is one of `inputs`: no command writes over its input.
void refuse_input(const std::filesystem::path& out, const std::string& flag,
                  const std::vector<std::filesystem::path>& inputs);
// session.make_sampler(spec), its errors prefixed by the flag that gave the spec.
std::unique_ptr<LightSampler> make_sampler_for(const RenderSession& session,
                                               const std::string& spec, const char* flag);
// Throws rll::Error naming both flags when two outputs (path, flag) are the same file; the
// first `distinct` are known to differ from one another (the frames of a render).
void refuse_same_outputs(const std::vector<std::pair<std::filesystem::path, std::string>>& outputs,
                         size_t distinct = 0);

// Checks an output file's extension (any case) before any work is done, refuses what it must
// never replace (rll/core/file_checks.h), creates its folder and checks that a file can be
// created there.
void prepare_output(const std::filesystem::path& p, const char* flag,
                    const std::vector<std::string>& extensions);
// Creates an output folder (and its parents) and checks that a file can be created in it;
// throws rll::Error naming the flag.
void prepare_output_dir(const std::filesystem::path& dir, const char* flag);

}  // namespace rll::cli
