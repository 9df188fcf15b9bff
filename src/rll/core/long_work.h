// What a computation that runs before rendering (the oracle's precompute, ...) needs to stay
// bounded and interruptible: the flag a front end's signal handler sets, which the render loop's
// cancel pointer does not reach there, and a progress line on stderr when it runs long.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <string>

namespace rll {

// The flag the front end sets on SIGINT, SIGTERM or SIGHUP (the CLI points it at the flag its
// render loops are given; null: none). Pre-render computations poll cancel_requested() and stop
// early; the render that follows sees the same flag and stops before its first pass.
void set_cancel_flag(const std::atomic<bool>* flag);
bool cancel_requested();

// Sets the cancel flag for a scope (Python, around work it waits on) and restores the one before.
class CancelScope {
 public:
  explicit CancelScope(const std::atomic<bool>* flag);
  ~CancelScope();
  CancelScope(const CancelScope&) = delete;
  CancelScope& operator=(const CancelScope&) = delete;

 private:
  const std::atomic<bool>* m_previous;
};

// Whether LongWork tells progress: by default where stderr is a terminal (as the render's
// progress bar); the CLI turns it off for --quiet.
void set_long_work_progress(bool enabled);

// Progress of a long pre-render computation of `total` units, told on stderr as whole lines
// ("rll: LABEL: 40% (1234 of 3000 cells), 1 min 20 s left") every kEverySeconds once it has run
// that long, from whichever thread calls add(); silent when it finishes sooner.
class LongWork {
 public:
  static constexpr double kEverySeconds = 5;
  LongWork(std::string label, uint64_t total, std::string unit);
  // Counts `n` more units done; thread-safe.
  void add(uint64_t n);
  uint64_t done() const { return m_done.load(std::memory_order_relaxed); }

 private:
  std::string m_label, m_unit;
  uint64_t m_total;
  std::chrono::steady_clock::time_point m_t0;
  std::atomic<uint64_t> m_done{0};
  std::atomic<int64_t> m_next_ms;  // milliseconds after m_t0 of the next line
};

}  // namespace rll
