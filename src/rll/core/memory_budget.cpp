#include "rll/core/memory_budget.h"

#include <fmt/format.h>

#include <atomic>

#include "rll/core/error.h"
#include "rll/core/sysinfo.h"

namespace rll {

namespace {
std::atomic<size_t> g_override{0};
}  // namespace

size_t memory_budget_bytes() {
  if (const size_t o = g_override.load(std::memory_order_relaxed)) return o;
  // Computed once: physical memory and resource limits do not change while rll runs.
  static const size_t budget = [] {
    const size_t usable = usable_memory_bytes();
    return usable > 0 ? size_t(0.8 * double(usable)) : size_t(8) << 30;
  }();
  return budget;
}

void set_memory_budget_bytes(size_t bytes) {
  g_override.store(bytes, std::memory_order_relaxed);
}

std::string format_bytes(double bytes) {
  // A product of claimed counts can be any size: past a pebibyte the number says nothing more.
  if (!(bytes < double(1ull << 50))) return "more than 1 PiB";
  if (bytes >= double(1ull << 40)) return fmt::format("{:.1f} TiB", bytes / double(1ull << 40));
  if (bytes >= double(1ull << 30)) return fmt::format("{:.1f} GiB", bytes / double(1ull << 30));
  if (bytes >= double(1ull << 20)) return fmt::format("{:.1f} MiB", bytes / double(1ull << 20));
  return fmt::format("{:.0f} bytes", bytes);
}

std::string memory_budget_phrase() {
  return fmt::format("the {} a scene may use{}", format_bytes(double(memory_budget_bytes())),
                     g_override.load(std::memory_order_relaxed)
                         ? ""
                         : " (80% of the memory this process may use)");
}

void check_memory_budget(double bytes, const std::string& what) {
  if (!(bytes <= double(memory_budget_bytes())))
    fail("{} needs {}, more than {}", what, format_bytes(bytes), memory_budget_phrase());
}

}  // namespace rll
