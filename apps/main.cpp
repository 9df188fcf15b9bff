// rll: a path tracer for importance sampling of many lights with learnt visibility.
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstring>

#include "commands.h"
#include "rll/core/error.h"
#include "rll/core/long_work.h"
#include "rll/core/memory_budget.h"
#include "rll/core/params.h"

namespace rll::cli {

namespace {
std::atomic<bool> g_interrupted{false};
std::atomic<int> g_signal{0};  // the first signal received
std::atomic<bool> g_working{false};

// Only async-signal-safe calls here: write(2) and _exit(2).
void say(const char* text) {
  [[maybe_unused]] ssize_t n = ::write(STDERR_FILENO, text, std::strlen(text));
}

extern "C" void on_signal(int sig) {
  if (!g_working.load()) {
    say("\nrll: interrupted; nothing was written\n");
    ::_exit(128 + sig);
  }
  int none = 0;
  if (g_signal.compare_exchange_strong(none, sig)) {
    g_interrupted.store(true);
    return;
  }
  // Cutting the program short now could lose what a second of patience saves.
  say("\nrll: already stopping: writing what has been rendered, then exiting\n");
}
}  // namespace

bool interrupted() {
  return g_interrupted.load();
}
int interrupt_exit_code() {
  return 128 + g_signal.load();
}
const std::atomic<bool>* interrupt_flag() {
  return &g_interrupted;
}
void begin_work() {
  g_working.store(true);
}

namespace {
std::string g_activity;  // set on the main thread only
}  // namespace

void set_activity(std::string what) {
  g_activity = std::move(what);
}

void install_interrupt_handler() {
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) sigaction(sig, &sa, nullptr);
  rll::set_cancel_flag(&g_interrupted);  // the oracle's precompute and the like stop on it too
}

namespace {

// "unknown command 'x' (commands: ...)" for a first word that names no subcommand; CLI11 would
// only say that a subcommand is required.
bool unknown_command(const CLI::App& app, int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.empty() || arg[0] == '-') continue;
    std::vector<std::string> names;
    for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; }))
      names.push_back(sub->get_name());
    if (std::find(names.begin(), names.end(), arg) != names.end()) return false;
    fmt::print(stderr, "rll: error: unknown command '{}' (commands: {})\n", shown_text(arg),
               fmt::join(names, ", "));
    return true;
  }
  return false;
}

// The arguments that no option of the parsed command took. CLI11 checks required options before
// it reports these, and so blamed a typo on a missing --out.
std::vector<std::string> unknown_arguments(const CLI::App& app, const CLI::App** where) {
  for (const CLI::App* sub : app.get_subcommands()) {
    std::vector<std::string> rest = sub->remaining();
    if (!rest.empty()) {
      *where = sub;
      return rest;
    }
  }
  *where = &app;
  return app.remaining();
}

// An empty value ("-o ''", "--stats=") is refused for every option that takes one, positionals
// included: CLI11 hands it on, and a command that reads "" as "not given" would do what the
// user did not ask (-o "" wrote out/<scene>.png).
void refuse_empty_values(CLI::App& app) {
  const CLI::Validator non_empty(
      [](std::string& value) {
        return value.empty() ? std::string("an empty value: give one, or leave the option out")
                             : std::string();
      },
      "");
  for (CLI::Option* opt : app.get_options())
    if (opt->get_type_size_max() > 0) opt->transform(non_empty);  // runs before other checks
  for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; }))
    refuse_empty_values(*sub);
}

// What main says when an allocation failed although the checks before it passed (the memory
// the machine or the process's limits give is less than the budget assumed, or something
// unchecked grew): what was being done, the budget, and what to try.
void report_out_of_memory(const CLI::App& app) {
  std::string doing = g_activity;
  if (doing.empty())
    for (const CLI::App* sub : app.get_subcommands())
      doing = "running `rll " + sub->get_name() + "`";
  fmt::print(stderr,
             "rll: error: out of memory while {} (rll checks what inputs and flags ask for "
             "against {}, and this allocation came on top of it): render fewer pixels (--res "
             "WIDTHxHEIGHT), lower a learning sampler's capacity (--set rll.capacity=N), use a "
             "smaller scene, or free memory\n",
             doing.empty() ? "starting" : doing, memory_budget_phrase());
}

}  // namespace
}  // namespace rll::cli

int main(int argc, char** argv) {
  CLI::App app{
      "rll: a path tracer that learns which lights are visible (Reinforcement Lightcuts Learning)"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "rll 0.1");
  rll::cli::add_render_command(app);
  rll::cli::add_scenes_command(app);
  rll::cli::add_samplers_command(app);
  rll::cli::add_filters_command(app);
  rll::cli::add_reference_command(app);
  rll::cli::add_compare_command(app);
  rll::cli::add_convert_command(app);
  rll::cli::add_merge_command(app);
  rll::cli::add_error_command(app);
  rll::cli::add_devices_command(app);
  rll::cli::add_interactive_command(app);
  rll::cli::refuse_empty_values(app);
  if (rll::cli::unknown_command(app, argc, argv)) return int(CLI::ExitCodes::ExtrasError);
  // --quiet silences the progress lines of pre-render work too (the commands run inside parse).
  for (int i = 1; i < argc; ++i)
    if (std::strcmp(argv[i], "--quiet") == 0) rll::set_long_work_progress(false);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const CLI::App* where = nullptr;
    const std::vector<std::string> rest = rll::cli::unknown_arguments(app, &where);
    if (e.get_exit_code() != 0 && !rest.empty()) {
      const std::string& a = rest.front();
      const std::string command = where == &app ? std::string("rll") : "rll " + where->get_name();
      if (a.size() > 1 && a[0] == '-')
        fmt::print(stderr, "rll: error: unknown option {} (see `{} --help`)\n", rll::shown_text(a),
                   command);
      else
        fmt::print(stderr, "rll: error: unexpected argument '{}' (see `{} --help`)\n",
                   rll::shown_text(a), command);
      return int(CLI::ExitCodes::ExtrasError);
    }
    return app.exit(e);
  } catch (const rll::cli::Interrupted& e) {
    fmt::print(stderr, "rll: {}\n", e.what());
    return rll::cli::interrupt_exit_code();
  } catch (const rll::Error& e) {
    fmt::print(stderr, "rll: error: {}\n", e.what());
    return 1;
  } catch (const std::bad_alloc&) {
    rll::cli::report_out_of_memory(app);
    return 1;
  } catch (const std::exception& e) {
    fmt::print(stderr, "rll: error: {}\n", e.what());
    return 1;
  }
  return rll::cli::interrupted() ? rll::cli::interrupt_exit_code() : 0;
}
