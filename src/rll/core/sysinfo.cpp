#include "rll/core/sysinfo.h"

#include <algorithm>

#include <sys/resource.h>

#include <fmt/format.h>
#include <sched.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <string>
#include <thread>

// CMakeLists.txt defines RLL_GIT_COMMIT for this file alone, so that a new commit recompiles
// nothing else; a build without it (another build system) says so instead of guessing.
#ifndef RLL_GIT_COMMIT
#define RLL_GIT_COMMIT "unknown"
#endif

namespace rll {

size_t usable_memory_bytes() {
  size_t usable = 0;
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
  if (pages > 0 && page > 0) usable = size_t(pages) * size_t(page);
  for (int resource : {RLIMIT_AS, RLIMIT_DATA}) {
    struct rlimit lim;
    if (::getrlimit(resource, &lim) == 0 && lim.rlim_cur != RLIM_INFINITY)
      usable = usable ? std::min(usable, size_t(lim.rlim_cur)) : size_t(lim.rlim_cur);
  }
  return usable;
}

size_t peak_rss_bytes() {
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("VmHWM:", 0) == 0) return size_t(std::stoull(line.substr(6))) * 1024;
  return 0;
}

bool reset_peak_rss() {
  std::ofstream f("/proc/self/clear_refs");
  f << "5";
  f.flush();
  return bool(f);
}

namespace {

std::string trim(const std::string& s) {
  const size_t b = s.find_first_not_of(" \t");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t\r") - b + 1);
}

// The value of the first "key : value" line of a /proc file whose key matches.
std::string proc_field(const char* file, const std::string& key) {
  std::ifstream f(file);
  std::string line;
  while (std::getline(f, line)) {
    const size_t colon = line.find(':');
    if (colon != std::string::npos && trim(line.substr(0, colon)) == key)
      return trim(line.substr(colon + 1));
  }
  return "";
}

}  // namespace

std::string machine_description() {
  std::string cpu = proc_field("/proc/cpuinfo", "model name");
  if (cpu.empty()) cpu = proc_field("/proc/cpuinfo", "Model");  // ARM boards
  if (cpu.empty()) cpu = "unknown CPU";
  // The cores the scheduler lets this process use (a container may see fewer than the machine).
  long cores = 0;
#ifdef CPU_COUNT
  cpu_set_t set;
  if (sched_getaffinity(0, sizeof set, &set) == 0) cores = CPU_COUNT(&set);
#endif
  if (cores <= 0) cores = sysconf(_SC_NPROCESSORS_ONLN);
  if (cores <= 0) cores = long(std::thread::hardware_concurrency());
  std::string s = cpu;
  if (cores > 0) s += fmt::format(", {} logical cores", cores);
  const std::string mem = proc_field("/proc/meminfo", "MemTotal");  // "24684092 kB"
  if (!mem.empty()) {
    const double kib = std::strtod(mem.c_str(), nullptr);
    if (kib > 0) s += fmt::format(", {:.1f} GiB", kib / (1024.0 * 1024.0));
  }
  return s;
}

std::string build_commit() {
  return RLL_GIT_COMMIT;
}

}  // namespace rll
