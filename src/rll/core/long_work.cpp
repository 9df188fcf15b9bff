#include "rll/core/long_work.h"

#include <fmt/format.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>

namespace rll {

namespace {
std::atomic<const std::atomic<bool>*> g_cancel{nullptr};
std::atomic<int> g_progress{-1};  // -1: where stderr is a terminal

// "1.2 s", "3 min 05 s" (as render/progress.h's format_duration, which core cannot use).
std::string duration(double s) {
  if (!std::isfinite(s) || s < 0) return "?";
  if (s < 60) return fmt::format("{:.1f} s", s);
  const int total = int(s + 0.5);
  if (total < 3600) return fmt::format("{} min {:02d} s", total / 60, total % 60);
  return fmt::format("{} h {:02d} min", total / 3600, (total / 60) % 60);
}
}  // namespace

void set_long_work_progress(bool enabled) {
  g_progress.store(enabled ? 1 : 0);
}

void set_cancel_flag(const std::atomic<bool>* flag) {
  g_cancel.store(flag);
}

bool cancel_requested() {
  const std::atomic<bool>* f = g_cancel.load(std::memory_order_relaxed);
  return f && f->load(std::memory_order_relaxed);
}

CancelScope::CancelScope(const std::atomic<bool>* flag) : m_previous(g_cancel.exchange(flag)) {}
CancelScope::~CancelScope() {
  g_cancel.store(m_previous);
}

LongWork::LongWork(std::string label, uint64_t total, std::string unit)
    : m_label(std::move(label)),
      m_unit(std::move(unit)),
      m_total(total),
      m_t0(std::chrono::steady_clock::now()),
      m_next_ms(int64_t(kEverySeconds * 1000)) {}

void LongWork::add(uint64_t n) {
  const uint64_t done = m_done.fetch_add(n, std::memory_order_relaxed) + n;
  const auto elapsed = std::chrono::steady_clock::now() - m_t0;
  const int64_t ms = std::chrono::duration_cast<std::chrono::milliseconds>(elapsed).count();
  int64_t next = m_next_ms.load(std::memory_order_relaxed);
  if (ms < next || done >= m_total) return;
  const int enabled = g_progress.load(std::memory_order_relaxed);
  if (enabled == 0 || (enabled < 0 && !::isatty(STDERR_FILENO))) return;
  // One thread tells each line.
  if (!m_next_ms.compare_exchange_strong(next, ms + int64_t(kEverySeconds * 1000))) return;
  const double seconds = double(ms) * 1e-3, frac = m_total ? double(done) / double(m_total) : 1;
  fmt::print(stderr, "rll: {}: {:.0f}% ({} of {} {}), {} elapsed, about {} left\n", m_label,
             100 * frac, done, m_total, m_unit, duration(seconds),
             duration(frac > 0 ? seconds * (1 - frac) / frac : NAN));
  std::fflush(stderr);
}

}  // namespace rll
