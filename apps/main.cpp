// rll: a path tracer for importance sampling of many lights with learnt visibility.
#include <fmt/format.h>

#include <atomic>
#include <csignal>

#include "commands.h"
#include "rll/core/error.h"

namespace rll::cli {

namespace {
std::atomic<bool> g_interrupted{false};
extern "C" void on_sigint(int) {
  if (g_interrupted.exchange(true)) {
    std::signal(SIGINT, SIG_DFL);  // a second Ctrl-C ends the program at once
    std::raise(SIGINT);
  }
}
}  // namespace

bool interrupted() { return g_interrupted.load(); }
const std::atomic<bool>* interrupt_flag() { return &g_interrupted; }
void install_interrupt_handler() { std::signal(SIGINT, on_sigint); }

}  // namespace rll::cli

int main(int argc, char** argv) {
  CLI::App app{"rll: a path tracer that learns which lights are visible (Reinforcement Lightcuts Learning)"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "rll 0.1");
  rll::cli::add_render_command(app);
  rll::cli::add_scenes_command(app);
  rll::cli::add_samplers_command(app);
  rll::cli::add_reference_command(app);
  rll::cli::add_compare_command(app);
  rll::cli::add_convert_command(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const rll::Error& e) {
    fmt::print(stderr, "rll: error: {}\n", e.what());
    return 1;
  } catch (const std::bad_alloc&) {
    fmt::print(stderr, "rll: error: out of memory\n");
    return 1;
  } catch (const std::exception& e) {
    fmt::print(stderr, "rll: error: {}\n", e.what());
    return 1;
  }
  return rll::cli::interrupted() ? 130 : 0;
}
