#include "rll/learn/cut.h"

#include <algorithm>
#include <queue>

namespace rll {

std::vector<uint32_t> refine_cut(const LightTree& tree, int size,
                                 double (*priority)(const LightTree&, uint32_t)) {
  // Max-heap by priority; ties by node id for determinism.
  auto cmp = [&](uint32_t a, uint32_t b) {
    const double pa = priority(tree, a), pb = priority(tree, b);
    return pa != pb ? pa < pb : a > b;
  };
  std::priority_queue<uint32_t, std::vector<uint32_t>, decltype(cmp)> heap(cmp);
  std::vector<uint32_t> done;
  heap.push(LightTree::kRoot);
  while (!heap.empty() && int(heap.size() + done.size()) < size) {
    uint32_t n = heap.top();
    heap.pop();
    if (tree.node(n).is_leaf()) {
      done.push_back(n);
      continue;
    }
    heap.push(tree.node(n).child);
    heap.push(tree.node(n).child + 1);
  }
  for (; !heap.empty(); heap.pop()) done.push_back(heap.top());
  std::sort(done.begin(), done.end(),
            [&](uint32_t a, uint32_t b) { return tree.node(a).begin < tree.node(b).begin; });
  return done;
}

std::vector<uint32_t> initial_cut(const LightTree& tree, int cut_size) {
  return refine_cut(tree, cut_size,
                    [](const LightTree& t, uint32_t n) { return double(t.node(n).light_count()); });
}

bool is_valid_cut(const LightTree& tree, const std::vector<uint32_t>& nodes) {
  uint32_t next = 0;
  for (uint32_t n : nodes) {
    if (n >= tree.node_count() || tree.node(n).begin != next) return false;
    next = tree.node(n).end;
  }
  return next == tree.light_count() && !nodes.empty();
}

}  // namespace rll
