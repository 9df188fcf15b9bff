// The renderer's parallel loops; TBB lives behind these and nowhere else.
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <utility>
#include <vector>

namespace rll {

// Limits the worker threads for as long as the returned object lives; 0 means all cores.
class ThreadLimit {
 public:
  explicit ThreadLimit(int threads);
  ~ThreadLimit();
  ThreadLimit(const ThreadLimit&) = delete;
  ThreadLimit& operator=(const ThreadLimit&) = delete;

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

int hardware_threads();

// Calls body(begin, end) over chunks of [0, n); grain is the smallest chunk.
void parallel_for(size_t n, size_t grain, const std::function<void(size_t, size_t)>& body);

// Calls body(i) for every i in [0, n), one item per task (for coarse items such as image tiles).
void parallel_for_each(size_t n, const std::function<void(size_t)>& body);

// Runs a and b, possibly at the same time.
void parallel_invoke(const std::function<void()>& a, const std::function<void()>& b);

// Sorts 64-bit keys with a 32-bit payload by key (ties keep no particular order).
void parallel_sort(std::vector<std::pair<uint64_t, uint32_t>>& items);

}  // namespace rll
