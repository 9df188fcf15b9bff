// The rewards of a cluster and what the learning makes of them: exact sums of a pass
// (ExactSum), the pass's moments (RewardMoments), the shrinkage rule that folds them into the
// learnt mean and second moment with its forgetting (shrinkage_fold, reward_changed,
// shrinkage_update), and pooling's shrinkage of a cell's values toward a coarse distribution
// (shrink_toward). Every function here runs on either device (RLL_HD).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "rll/core/device.h"
#include "rll/learn/cut_settings.h"

namespace rll {

// A sum of non-negative values that is exact and independent of the order of additions, over a
// wide range: values are fixed point with 2^-40 of the unit per step, up to 2^36 units (larger
// values saturate), held in two 64-bit words (units of 2^-8 and 2^-40) so that 2^19 saturated
// values or 2^31 ordinary ones fit in a pass. Resolution and range together span 2^76 (1e23).
struct ExactSum {
  static constexpr double kMax = 0x1p36;
  // A square summed saturates with the sum: the root of kMax.
  static constexpr double kMaxRoot = 0x1p18;
  // Signed 64-bit words in two's complement, added with core/device.h's atomic_add (DESIGN 6).
  uint64_t hi = 0, lo = 0;
  RLL_HD void add(double x) {  // x: the value in units of scale, >= 0
    Words w = words(x);
    add(w);
  }
  // The two words one value adds: integers, so that the words of several values may be summed
  // first and added once (the same sum to the bit as adding each; psf_end_paths does so).
  struct Words {
    uint64_t hi = 0, lo = 0;
    RLL_HD Words& operator+=(const Words& o) {
      hi += o.hi;
      lo += o.lo;
      return *this;
    }
  };
  RLL_HD static Words words(double x) {
    x = std::min(x, double(kMax));
    const double h = std::floor(x * 0x1p8);
    return {uint64_t(int64_t(h)), uint64_t(int64_t((x * 0x1p8 - h) * 0x1p32 + 0.5))};
  }
  RLL_HD void add(const Words& w) {
    atomic_add(&hi, w.hi);
    atomic_add(&lo, w.lo);
  }
  RLL_HD double value() const {
    return double(int64_t(atomic_load(&hi))) * 0x1p-8 + double(int64_t(atomic_load(&lo))) * 0x1p-40;
  }
  RLL_HD void reset() { hi = lo = 0; }  // between passes
};

// Adds a reward x (in the unit of the sums) to a cluster's exact sums of rewards and of their
// squares, and returns the square it added (0 for x <= 0: an occluded sample only counts), for a
// learner that sums part of the squares again (ltc, by child).
RLL_HD inline double add_reward(ExactSum& sum, ExactSum& sq, double x) {
  if (!(x > 0)) return 0;
  sum.add(x);
  const double c = std::min(x, double(ExactSum::kMaxRoot));
  sq.add(c * c);
  return c * c;
}

// The unit of a cell's sums for the next pass: its largest learnt sqrt(M2) where it has one
// (`largest`), else the unit it had.
RLL_HD inline void next_unit(double& inv_unit, double largest) {
  if (largest > 0 && std::isfinite(largest)) inv_unit = 1 / largest;
}

// A pass's rewards of a cluster, n of them with absolute sum `sum` and sum of squares `sq`: their
// mean and second moment (E[r^2] >= E[r]^2 also where squares fell below the sums' resolution).
struct RewardMoments {
  double mean, mean2;
  RLL_HD RewardMoments(double n, double sum, double sq)
      : mean(sum / n), mean2(std::max(sq / n, mean * mean)) {}
};

// The shrinkage rule (LearningRule::Shrinkage) for one cluster: values old_q and old_m2, held
// with the weight of w rewards, and n new rewards of moments r give the weighted means; the
// weight becomes w + n, at most cap.
RLL_HD inline void shrinkage_fold(float& q, float& m2, float& weight, double w, double old_q,
                                  double old_m2, double n, const RewardMoments& r, double cap) {
  q = float((w * old_q + n * r.mean) / (w + n));
  m2 = float((w * old_m2 + n * r.mean2) / (w + n));
  weight = float(std::min(w + n, cap));
}

// The change test of forget=changes: true if n new rewards of moments r differ in mean from
// old_q (held with the weight of w rewards, second moment old_m2) by more than z standard errors
// of the difference. The variance is the larger of the old rewards' and the new ones', so that a
// rare bright reward among zeros (a cluster seen through a gap) does not count as a change, and
// a lamp switching off (new rewards all zero) or on (old ones all zero) does; a relative slack
// of 1e-4 absorbs the rounding of rewards that never vary.
RLL_HD inline bool reward_changed(double old_q, double old_m2, double w, double n,
                                  const RewardMoments& r, double z) {
  const double var = std::max(std::max(old_m2 - old_q * old_q, r.mean2 - r.mean * r.mean), 0.0);
  const double se = std::sqrt(var * (1 / n + 1 / std::max(w, 1.0)));
  return std::abs(r.mean - old_q) > z * se + 1e-4 * (std::abs(old_q) + std::abs(r.mean));
}

// One cluster's fold under the shrinkage rule as CutSettings say: the weight w of the past (the
// cluster's own n if `visited`, else the prior's weight) capped at 1/alpha under forget=floor, or
// where forget=changes finds a change; true if it found one.
RLL_HD inline bool shrinkage_update(const CutSettings& s, float& q, float& m2, float& weight,
                                    double w, bool visited, double old_q, double old_m2, double n,
                                    const RewardMoments& r) {
  const double floor_cap = 1.0 / s.alpha;
  if (s.forget == Forgetting::Floor) {
    shrinkage_fold(q, m2, weight, visited ? std::min(w, floor_cap) : w, old_q, old_m2, n, r,
                   floor_cap);
    return false;
  }
  const bool changed = visited && s.change_z > 0 && w > floor_cap &&
                       reward_changed(old_q, old_m2, w, n, r, s.change_z);
  shrinkage_fold(q, m2, weight, changed ? floor_cap : w, old_q, old_m2, n, r, 1e30);
  return changed;
}

// A cluster's effective value from what it learnt: sqrt(M2) under target=moment, else its mean Q
// (for a visited cluster; one never visited has q < 0 and gets a prior estimate instead).
RLL_HD inline float target_value(bool moment, float q, float m2) {
  return moment ? std::sqrt(std::max(m2, 0.0f)) : q;
}

// What the visited clusters of a cell say its total is: their values over their prior shares,
// both summed in double in the order they are added, the shares' sum taken as at least a quarter
// so that one bright, rarely chosen cluster does not inflate every unvisited one.
struct VisitedTotal {
  double values = 0, shares = 0;
  RLL_HD void add(double value, double share) {
    values += value;
    shares += share;
  }
  RLL_HD double total() const { return values / std::max(shares, 0.25); }
};

// forget=changes when the lights changed: every cluster's memory (n, the weight of the rewards
// behind its values) cut back to the last 1/alpha rewards, as if each had failed the change test.
RLL_HD inline void forget_to_window(float* n, size_t count, double alpha) {
  const float cap = float(1.0 / alpha);
  for (size_t k = 0; k < count; ++k) n[k] = std::min(n[k], cap);
}

// Pooling: shrinks K values, each held with the weight of n[k] rewards (visited[k] false: none,
// and the value is ignored), toward a distribution `shares` scaled to what the visited values say
// the total is (their sum over their shares, the shares' sum taken as at least a quarter, so that
// one bright, rarely chosen cluster does not inflate every unvisited one): each becomes
// (n v + c guess) / (n + c), an unvisited one the guess (also for c = 0). Unchanged where no
// visited value is positive.
template <class Visited>
RLL_HD void shrink_toward(size_t K, Visited visited, const float* n, const float* shares, double c,
                          float* values) {
  VisitedTotal sums;
  for (size_t k = 0; k < K; ++k)
    if (visited(k)) sums.add(values[k], shares[k]);
  if (!(sums.values > 0)) return;
  const double total = sums.total();
  for (size_t k = 0; k < K; ++k) {
    const double guess = total * shares[k], w = visited(k) ? double(n[k]) : 0.0;
    values[k] = w + c > 0 ? float((w * values[k] + c * guess) / (w + c)) : float(guess);
  }
}

struct Scene;
// The unit of the learning samplers' exact reward sums: the brightest light's largest irradiance,
// so that every scene gets the same relative range of ExactSum (2^-40 to 2^36 of it).
double reward_scale(const Scene& scene);

}  // namespace rll
