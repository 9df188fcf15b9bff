#include "rll/core/parallel.h"

#include "rll/core/device.h"

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_sort.h>

namespace rll {

struct ThreadLimit::Impl {
  std::unique_ptr<tbb::global_control> control;
};

ThreadLimit::ThreadLimit(int threads) : m_impl(std::make_unique<Impl>()) {
  if (threads > 0)
    m_impl->control = std::make_unique<tbb::global_control>(
        tbb::global_control::max_allowed_parallelism, size_t(threads));
}
ThreadLimit::~ThreadLimit() = default;

int hardware_threads() {
  return tbb::info::default_concurrency();
}

void parallel_for(size_t n, size_t grain, const std::function<void(size_t, size_t)>& body) {
  if (n == 0) return;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, std::max<size_t>(1, grain)),
                    [&](const tbb::blocked_range<size_t>& r) { body(r.begin(), r.end()); });
}

void host_parallel_for_impl(size_t n, void* context, void (*call)(void*, size_t, size_t)) {
  if (n == 0) return;
  // Chunks of 256 items: kernel bodies are small (one ray, one cell), and the split is what TBB's
  // auto partitioner would choose for them anyway, without its per-item overhead.
  tbb::parallel_for(
      tbb::blocked_range<size_t>(0, n, 256),
      [&](const tbb::blocked_range<size_t>& r) { call(context, r.begin(), r.end()); });
}

void parallel_for_each(size_t n, const std::function<void(size_t)>& body) {
  if (n == 0) return;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) body(i);
  });
}

void parallel_invoke(const std::function<void()>& a, const std::function<void()>& b) {
  tbb::parallel_invoke(a, b);
}

void parallel_sort(std::vector<std::pair<uint64_t, uint32_t>>& items) {
  tbb::parallel_sort(items.begin(), items.end());
}

}  // namespace rll
