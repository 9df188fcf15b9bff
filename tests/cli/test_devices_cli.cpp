// `rll devices`: the CPU's threads and each CUDA device, or why there is none, in text and JSON;
// exit 0 either way (a machine without a GPU is no error for a listing).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "rll/core/parallel.h"
#include "rll/cuda/cuda.h"
#include "support/test_support.h"

using namespace rll::test;

namespace {

// Why this machine has no usable GPU, as require_gpu says it; empty where it has one.
std::string gpu_problem() {
  try {
    rll::cuda::require_gpu();
  } catch (const rll::Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(DevicesCli, ListsTheCpuAndTheGpusOrWhyNone) {
  const CommandResult r = run_rll({"devices"}, 60);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  expect_mentions(r.output, {fmt::format("cpu    {} threads\n", rll::hardware_threads())});
  const std::vector<rll::cuda::GpuInfo> gpus = rll::cuda::gpus();
  for (size_t i = 0; i < gpus.size(); ++i)
    expect_mentions(r.output,
                    {fmt::format("cuda:{} {}, compute capability {}.{}, {} SMs", i, gpus[i].name,
                                 gpus[i].sm_major, gpus[i].sm_minor, gpus[i].multiprocessors)});
  const std::string problem = gpu_problem();
  if (problem.empty()) {
    EXPECT_EQ(r.output.find("no GPU"), std::string::npos) << r.output;
  } else {
    expect_mentions(r.output, {"no GPU: " + problem});
  }
  if (!rll::cuda::cuda_built()) expect_mentions(r.output, {"built without CUDA", "re-run cmake"});
}

TEST(DevicesCli, Json) {
  const CommandResult r = run_rll({"devices", "--json"}, 60);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j.at("cpu").at("threads").get<int>(), rll::hardware_threads());
  const nlohmann::json& cuda = j.at("cuda");
  EXPECT_EQ(cuda.at("built").get<bool>(), rll::cuda::cuda_built());
  const std::vector<rll::cuda::GpuInfo> gpus = rll::cuda::gpus();
  ASSERT_EQ(cuda.at("devices").size(), gpus.size());
  for (size_t i = 0; i < gpus.size(); ++i) {
    EXPECT_EQ(cuda["devices"][i].at("name").get<std::string>(), gpus[i].name);
    EXPECT_EQ(cuda["devices"][i].at("memory_bytes").get<size_t>(), gpus[i].memory_bytes);
  }
  const std::string problem = gpu_problem();
  EXPECT_EQ(cuda.at("usable").get<bool>(), problem.empty());
  if (!problem.empty()) {
    EXPECT_EQ(cuda.at("problem").get<std::string>(), problem);
  }
}

TEST(DevicesCli, UnknownOption) {
  expect_clean_failure({"devices", "--bogus"}, {"--bogus"});
}

// --device cuda: on a machine without a usable GPU, render, compare and interactive exit non-zero
// with require_gpu's reason; with one, a sampler without a device version is refused by name.
// --device and --tracer take only their values.
TEST(DevicesCli, DeviceCudaWithoutAGpuSaysWhy) {
  const std::string problem = gpu_problem();
  if (problem.empty()) {
    TempDir dir;
    const CommandResult r =
        run_rll({"render", "builtin:cornell-boxes-room", "--res", "16x12", "--spp", "1", "--device",
                 "cuda", "--sampler", "ltc", "-o", (dir.path() / "x.exr").string()},
                120);
    EXPECT_NE(r.exit_code, 0) << r.output;
    expect_mentions(r.output, {"'ltc' has no device version"});
    return;
  }
  TempDir dir;
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"render", "builtin:cornell-boxes-room", "--device", "cuda", "-o",
                                 (dir.path() / "x.exr").string()},
        std::vector<std::string>{"compare", "builtin:cornell-boxes-room", "--device", "cuda",
                                 "--out", (dir.path() / "cmp").string(), "--spp", "1"},
        std::vector<std::string>{"interactive", "builtin:cornell-boxes-room", "--device", "cuda",
                                 "--frames", "1"}}) {
    const CommandResult r = run_rll(args, 60);
    EXPECT_NE(r.exit_code, 0) << r.output;
    expect_mentions(r.output, {problem});
  }
}

TEST(DevicesCli, DeviceAndTracerTakeOnlyTheirValues) {
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"render", "builtin:cornell-boxes-room", "--device", "gpu"},
        std::vector<std::string>{"render", "builtin:cornell-boxes-room", "--tracer", "optix"}}) {
    const CommandResult r = run_rll(args, 60);
    EXPECT_NE(r.exit_code, 0) << r.output;
    expect_mentions(r.output, {args[2]});
  }
  const CommandResult r =
      run_rll({"render", "builtin:cornell-boxes-room", "--tracer", "bvh", "--res", "8x6"}, 60);
  EXPECT_NE(r.exit_code, 0) << r.output;
  expect_mentions(r.output, {"--tracer bvh", "--wavefront"});
}
