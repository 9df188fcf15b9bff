// RLL's end of pass written once over a backend (lights/rll_end_pass.h, core/backend.h): run with
// a host backend whose loops go backwards one index at a time (and whose table rebuild inserts
// in reverse id order), it leaves every learnt array, every statistic and every lookup of the
// cell table as the sampler's own end_pass (TBB loops) does, to the bit, pass after pass, for
// every family of settings: nothing it computes depends on the order its loops run in.
#include <gtest/gtest.h>

#include <utility>

#include "rll/core/backend.h"
#include "rll/lights/rll_end_pass.h"
#include "support/rll_twins.h"

using namespace rll;

namespace {

struct ReversedHostBackend : HostBackend {
  template <typename Body>
  void parallel_for(size_t n, const Body& body) const {
    for (size_t i = n; i-- > 0;) body(i);
  }
  template <typename Body>
  void ordered_for(size_t n, const Body& body) const {
    for (size_t i = n; i-- > 0;) body(i);
  }
};

RllPassCounts reversed_end_pass(const RllLearnView& v, RllPoolState<HostBackend>& pool,
                                uint32_t used_before, bool reset) {
  RllPoolState<ReversedHostBackend> p{std::move(pool.keys), std::move(pool.q), std::move(pool.m2),
                                      std::move(pool.n)};
  RllScratch<ReversedHostBackend> scratch;
  const RllPassCounts c = rll_end_pass(ReversedHostBackend{}, v, p, scratch, used_before, reset);
  pool = {std::move(p.keys), std::move(p.q), std::move(p.m2), std::move(p.n)};
  return c;
}

TEST(RllEndPass, AnyLoopOrderLearnsTheSameToTheBit) {
  for (const test::RllEndPassCase& c : test::rll_end_pass_cases()) {
    const nlohmann::json d = test::run_end_pass_case(
        c, [](RllLightSampler& s) { s.end_pass_with(reversed_end_pass); }, 0);
    // The cases reach what they are there for.
    const std::string label = c.label;
    if (label == "capacity40") {
      EXPECT_GT(d["evictions"].get<uint64_t>(), 0u);
    } else if (label == "fermat-reset3") {
      EXPECT_EQ(d["resets"].get<uint64_t>(), 2u);
    } else if (label == "splits4") {
      EXPECT_GT(d["splits_per_pass"][1].get<uint32_t>(), 0u);
    } else if (label == "rll") {
      EXPECT_GT(d["pool_cells"].get<uint64_t>(), 0u);
    }
  }
}

}  // namespace
