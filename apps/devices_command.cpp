// `rll devices`: what rll can run on here: the CPU's threads and each CUDA device, or why there
// is none (the lead's first look on a GPU machine, and what scripts check before GPU work).
#include <fmt/format.h>

#include <nlohmann/json.hpp>

#include "commands.h"
#include "rll/core/error.h"
#include "rll/core/parallel.h"
#include "rll/cuda/cuda.h"

namespace rll::cli {

namespace {

std::string cuda_version(int v) {
  return fmt::format("{}.{}", v / 1000, v % 1000 / 10);
}

// Why no GPU work can run here; empty where a usable device exists.
std::string gpu_problem() {
  try {
    cuda::require_gpu();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

void print_devices(bool json) {
  const std::vector<cuda::GpuInfo> gpus = cuda::gpus();
  const std::string problem = gpu_problem();
  if (json) {
    nlohmann::json devices = nlohmann::json::array();
    for (const cuda::GpuInfo& g : gpus)
      devices.push_back({{"name", g.name},
                         {"compute_capability", fmt::format("{}.{}", g.sm_major, g.sm_minor)},
                         {"multiprocessors", g.multiprocessors},
                         {"memory_bytes", g.memory_bytes},
                         {"driver_version", cuda_version(g.driver_version)},
                         {"runtime_version", cuda_version(g.runtime_version)}});
    nlohmann::json out = {
        {"cpu", {{"threads", hardware_threads()}}},
        {"cuda",
         {{"built", cuda::cuda_built()}, {"devices", devices}, {"usable", problem.empty()}}}};
    if (!problem.empty()) out["cuda"]["problem"] = problem;
    fmt::print("{}\n", out.dump(2));
    return;
  }
  fmt::print("cpu    {} threads\n", hardware_threads());
  for (size_t i = 0; i < gpus.size(); ++i) {
    const cuda::GpuInfo& g = gpus[i];
    fmt::print(
        "cuda:{} {}, compute capability {}.{}, {} SMs, {:.1f} GiB, driver CUDA {}, "
        "runtime CUDA {}\n",
        i, g.name, g.sm_major, g.sm_minor, g.multiprocessors,
        double(g.memory_bytes) / double(1ull << 30), cuda_version(g.driver_version),
        cuda_version(g.runtime_version));
  }
  if (!problem.empty()) fmt::print("no GPU: {}\n", problem);
}

}  // namespace

void add_devices_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "devices", "List what rll can run on: the CPU's threads and each CUDA device, or why none");
  auto json = std::make_shared<bool>(false);
  cmd->add_flag("--json", *json, "Print one JSON object");
  cmd->callback([json] { print_devices(*json); });
}

}  // namespace rll::cli
