// Every kernel of the build's sm_90 code within the budgets of kernel_budgets.h: stack frame,
// and for the wavefront's path stages registers and spills, as ptxas reported them when
// rll_device compiled (scripts/ptxas-report.sh keeps each object's report in
// <build>/kernel_resources/). Skipped where rll was built without CUDA.
#include <cxxabi.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "kernel_budgets.h"
#include "rll/cuda/cuda.h"
#include "rll/wavefront/stages.h"

namespace rll {
namespace {

struct KernelUsage {
  std::string mangled, arch, object;
  int registers = -1, stack = 0, spill_stores = 0, spill_loads = 0;
};

// The entry functions (kernels) of a ptxas -v report: "Compiling entry function 'NAME' for
// 'sm_XX'", then "Function properties for NAME" followed by "N bytes stack frame, N bytes spill
// stores, N bytes spill loads", then "Used N registers, ..., N bytes cumulative stack size". The
// properties of functions that are not entries (called through the ABI) count only through the
// cumulative stack size of their callers.
std::vector<KernelUsage> parse_ptxas_report(std::istream& in, const std::string& object) {
  static const std::regex entry(R"(Compiling entry function '([^']+)' for '(sm_[0-9a-z]+)')");
  static const std::regex props(R"(Function properties for (\S+))");
  static const std::regex frame(
      R"(([0-9]+) bytes stack frame, ([0-9]+) bytes spill stores, ([0-9]+) bytes spill loads)");
  static const std::regex used(R"(Used ([0-9]+) registers)");
  static const std::regex cumulative(R"(([0-9]+) bytes cumulative stack size)");
  std::vector<KernelUsage> out;
  std::map<std::string, size_t> open;  // entry name -> its index in out, for its properties
  std::string props_of;
  KernelUsage* current = nullptr;
  std::string line;
  std::smatch m;
  while (std::getline(in, line)) {
    if (std::regex_search(line, m, entry)) {
      out.push_back({m[1], m[2], object});
      open[m[1]] = out.size() - 1;
      current = &out.back();
      props_of.clear();
    } else if (std::regex_search(line, m, props)) {
      props_of = m[1];
    } else if (std::regex_search(line, m, frame)) {
      const auto it = open.find(props_of);
      if (it != open.end()) {
        KernelUsage& k = out[it->second];
        k.stack = std::max(k.stack, std::stoi(m[1]));
        k.spill_stores = std::stoi(m[2]);
        k.spill_loads = std::stoi(m[3]);
      }
    } else if (current && std::regex_search(line, m, used)) {
      current->registers = std::stoi(m[1]);
      if (std::regex_search(line, m, cumulative))
        current->stack = std::max(current->stack, std::stoi(m[1]));
    }
  }
  return out;
}

std::string demangle(const std::string& mangled) {
  int status = 0;
  std::unique_ptr<char, decltype(&std::free)> d(
      abi::__cxa_demangle(mangled.c_str(), nullptr, nullptr, &status), &std::free);
  return status == 0 && d ? std::string(d.get()) : mangled;
}

// A kernel's short name: the wavefront stage it runs (the lambdas inside
// WavefrontDriver::stage<WavefrontStage::X>), else its demangled name up to its arguments.
struct KernelName {
  std::string name;
  bool path_stage = false;  // a kernel of the wavefront driver
};
KernelName kernel_name(const std::string& mangled) {
  const std::string d = demangle(mangled);
  static const std::regex stage(R"(stage<\(rll::WavefrontStage\)([0-9]+)>)");
  KernelName k;
  k.path_stage = d.find("WavefrontDriver<") != std::string::npos;
  std::smatch m;
  if (std::regex_search(d, m, stage)) {
    const size_t s = std::stoul(m[1]);
    k.name = s < kWavefrontStages ? kWavefrontStageNames[s] : "stage " + m[1].str();
  } else if (k.path_stage) {
    // A lambda of the driver outside stage<> (the camera rays, the accumulation): where it is.
    const size_t at = d.find("WavefrontDriver<");
    const size_t fn = d.find(">::", at);
    const size_t end = d.find('(', fn == std::string::npos ? at : fn);
    k.name =
        "WavefrontDriver" + d.substr(fn == std::string::npos ? at : fn + 1,
                                     end == std::string::npos ? std::string::npos : end - fn - 1);
    const size_t lambda = d.find("{lambda", end == std::string::npos ? at : end);
    if (lambda != std::string::npos)
      k.name += " " + d.substr(lambda, d.find('}', lambda) - lambda + 1);
  } else {
    k.name = d.substr(0, d.find('('));
  }
  return k;
}

// The registers a path stage may use: the budget, or its allowance (kernel_budgets.h).
int register_budget(const std::string& stage) {
  for (const budgets::RegisterAllowance& a : budgets::kRegisterAllowances)
    if (stage == a.stage) return a.registers;
  return budgets::kMaxPathStageRegisters;
}

// What is over budget in a kernel, or "" where it is within.
std::string over_budget(const KernelUsage& k, const KernelName& n) {
  std::ostringstream s;
  if (k.stack > budgets::kMaxStackBytes)
    s << " stack frame " << k.stack << " bytes (budget " << budgets::kMaxStackBytes << ")";
  const int registers = register_budget(n.name);
  if (n.path_stage && k.registers > registers)
    s << " " << k.registers << " registers (budget " << registers << ")";
  if (n.path_stage && std::max(k.spill_stores, k.spill_loads) > budgets::kMaxPathStageSpillBytes)
    s << " spills " << k.spill_stores << " bytes stored, " << k.spill_loads << " loaded (budget "
      << budgets::kMaxPathStageSpillBytes << ")";
  return s.str();
}

// A report as nvcc 13 writes it for today's kernels (figures made up to be over budget): the
// NeeSample stage, a function that is not an entry, the end-of-pass cut kernel and the camera
// rays (a lambda of the driver outside stage<>), for the parser's own test.
constexpr const char* kNee =
    "_ZN3rll4cuda45_GLOBAL__N__2a823ce1_12_wavefront_cu_abef501512queue_kernelIZZNS_15Wavefro"
    "ntDriverINS1_20CudaWavefrontBackendENS_9BvhTracerENS_11ViewSamplerEE5stageILNS_14Wavefro"
    "ntStageE3EEEvNS_16WavefrontQueueIdEjENKUlvE_clEvEUljE_EEvNS_14WavefrontQueueEjT_";
constexpr const char* kCut =
    "_ZN3rll4cuda6detail19parallel_for_kernelIZNS_16cut_end_pass_gpuERKNS_15CutStoreEndViewER"
    "KSt6vectorIjSaIjEEEUlmE_EEvmT_";
constexpr const char* kCamera =
    "_ZN3rll4cuda6detail19parallel_for_kernelIZZNS_15WavefrontDriverINS0_45_GLOBAL__N__2a823c"
    "e1_12_wavefront_cu_abef501520CudaWavefrontBackendENS_9BvhTracerENS_11ViewSamplerEE9run_b"
    "atchERKNS_14WavefrontBatchEENKUlvE_clEvEUlmE_EEvmT_";

std::string sample_report() {
  std::ostringstream s;
  s << "ptxas info    : 0 bytes gmem\n"
    << "ptxas info    : Compiling entry function '" << kNee << "' for 'sm_90'\n"
    << "ptxas info    : Function properties for " << kNee << "\n"
    << "    3120 bytes stack frame, 8 bytes spill stores, 12 bytes spill loads\n"
    << "ptxas info    : Used 135 registers, used 0 barriers, 3120 bytes cumulative stack size, "
       "392 bytes cmem[0]\n"
    << "ptxas info    : Function properties for _ZN3rll6helperEv\n"
    << "    64 bytes stack frame, 0 bytes spill stores, 0 bytes spill loads\n"
    << "ptxas info    : Compiling entry function '" << kCut << "' for 'sm_90'\n"
    << "ptxas info    : Function properties for " << kCut << "\n"
    << "    0 bytes stack frame, 0 bytes spill stores, 0 bytes spill loads\n"
    << "ptxas info    : Used 200 registers, used 0 barriers, 1056 bytes cumulative stack size\n"
    << "ptxas info    : Compiling entry function '" << kCamera << "' for 'sm_90'\n"
    << "ptxas info    : Function properties for " << kCamera << "\n"
    << "    32 bytes stack frame, 0 bytes spill stores, 0 bytes spill loads\n"
    << "ptxas info    : Used 32 registers, used 0 barriers, 32 bytes cumulative stack size\n"
    << "ptxas info    : Compile time = 10.000 ms\n";
  return s.str();
}

TEST(KernelBudgets, ReportParserReadsEachEntrysRegistersStackAndSpills) {
  std::istringstream in(sample_report());
  const std::vector<KernelUsage> k = parse_ptxas_report(in, "sample.cu.o");
  ASSERT_EQ(k.size(), 3u);
  EXPECT_EQ(k[0].arch, "sm_90");
  EXPECT_EQ(k[0].registers, 135);  // (one past nee_sample's allowance)
  EXPECT_EQ(k[0].stack, 3120);
  EXPECT_EQ(k[0].spill_stores, 8);
  EXPECT_EQ(k[0].spill_loads, 12);
  const KernelName n0 = kernel_name(k[0].mangled);
  EXPECT_EQ(n0.name, "nee_sample");
  EXPECT_TRUE(n0.path_stage);
  // Over every budget, and said so by name and figure.
  const std::string why = over_budget(k[0], n0);
  EXPECT_NE(why.find("stack frame 3120 bytes"), std::string::npos) << why;
  EXPECT_NE(why.find("135 registers"), std::string::npos) << why;
  EXPECT_NE(why.find("spills 8 bytes stored, 12 loaded"), std::string::npos) << why;
  // Not a path stage: registers are budgeted for the path stages only, and its callees' frames
  // count (cumulative stack size).
  EXPECT_EQ(k[1].registers, 200);
  EXPECT_EQ(k[1].stack, 1056);
  const KernelName n1 = kernel_name(k[1].mangled);
  EXPECT_FALSE(n1.path_stage);
  EXPECT_EQ(n1.name.rfind("void rll::cuda::detail::parallel_for_kernel<rll::cut_end_pass_gpu", 0),
            0u)
      << n1.name;
  EXPECT_EQ(over_budget(k[1], n1), " stack frame 1056 bytes (budget 1024)");
  // A lambda of the driver outside stage<> is a path stage, named by where it is.
  const KernelName n2 = kernel_name(k[2].mangled);
  EXPECT_TRUE(n2.path_stage);
  EXPECT_EQ(n2.name, "WavefrontDriver::run_batch {lambda()#1}");
  EXPECT_EQ(k[2].stack, 32);
  EXPECT_EQ(over_budget(k[2], n2), "");
}

TEST(KernelBudgets, EveryKernelOfTheBuildIsWithinItsBudget) {
  if (!cuda::cuda_built()) GTEST_SKIP() << "rll was built without CUDA: no kernels to check";
  const std::filesystem::path dir =
      std::filesystem::path(RLL_BINARY).parent_path() / "kernel_resources";
  std::vector<KernelUsage> kernels;
  if (std::filesystem::is_directory(dir))
    for (const auto& e : std::filesystem::directory_iterator(dir)) {
      if (e.path().extension() != ".txt") continue;
      std::ifstream in(e.path());
      for (KernelUsage& k : parse_ptxas_report(in, e.path().stem().string()))
        if (k.arch == budgets::kArch) kernels.push_back(std::move(k));
    }
  ASSERT_FALSE(kernels.empty())
      << "no ptxas report of " << budgets::kArch << " kernels in " << dir.string()
      << ": scripts/ptxas-report.sh writes it when rll_device's .cu files compile (touch "
         "src/rll/cuda/*.cu and rebuild; with another CUDA_ARCHITECTURES, add 90-real)";
  int path_stages = 0, nee = 0;
  std::ostringstream table;
  for (const KernelUsage& k : kernels) {
    const KernelName n = kernel_name(k.mangled);
    path_stages += n.path_stage;
    nee += n.name == "nee_sample";
    EXPECT_GE(k.registers, 0) << n.name << ": no register count in the report";
    table << k.object << "  " << n.name << ": " << k.registers << " registers, " << k.stack
          << " B stack, " << k.spill_stores << "/" << k.spill_loads << " B spilled\n";
    const std::string why = over_budget(k, n);
    EXPECT_EQ(why, "") << n.name << " (" << k.object << ", " << demangle(k.mangled).substr(0, 300)
                       << ") is over budget (tests/unit/kernel_budgets.h):" << why;
  }
  // The report names the driver's stages as this test expects (a kernel of NeeSample among them).
  EXPECT_GT(path_stages, 0) << table.str();
  EXPECT_GT(nee, 0) << table.str();
  // An allowance that no kernel needs any more is said so, to be removed.
  for (const budgets::RegisterAllowance& a : budgets::kRegisterAllowances) {
    int most = 0;
    for (const KernelUsage& k : kernels)
      if (kernel_name(k.mangled).name == a.stage) most = std::max(most, k.registers);
    EXPECT_GT(most, budgets::kMaxPathStageRegisters)
        << a.stage << " is within the register budget (" << most
        << "): remove its allowance from tests/unit/kernel_budgets.h";
  }
  std::cout << table.str();
}

}  // namespace
}  // namespace rll
