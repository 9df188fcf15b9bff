// learn/moments.h's small helpers that the learnt cuts, pooling and ltc share: a cluster's
// effective value, the visited clusters' total, and forget=changes' cut back of every weight.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "rll/learn/moments.h"

using namespace rll;

TEST(Moments, TargetValueIsSqrtM2OrQ) {
  EXPECT_EQ(target_value(true, 2.0f, 9.0f), 3.0f);
  EXPECT_EQ(target_value(false, 2.0f, 9.0f), 2.0f);
  EXPECT_EQ(target_value(true, 2.0f, -1e-9f), 0.0f);           // a rounding below zero is no moment
  EXPECT_EQ(target_value(true, 0.5f, 2.0f), std::sqrt(2.0f));  // in float, as the cuts keep it
}

TEST(Moments, VisitedTotalTakesSmallSharesAsAQuarter) {
  VisitedTotal none;
  EXPECT_EQ(none.total(), 0.0);
  VisitedTotal a;
  a.add(1.0, 0.3);
  a.add(2.0, 0.2);
  EXPECT_DOUBLE_EQ(a.values, 3.0);
  EXPECT_DOUBLE_EQ(a.shares, 0.5);
  EXPECT_DOUBLE_EQ(a.total(), 6.0);  // 3 over a share of a half: the whole is 6
  VisitedTotal b;
  b.add(1.0, 0.05);  // one bright cluster of a small share
  b.add(0.5, 0.05);
  EXPECT_DOUBLE_EQ(b.total(), 6.0);  // 1.5 over a quarter, not over 0.1
  VisitedTotal c;
  c.add(1.0f, 0.25f);  // floats add as doubles, exactly
  EXPECT_EQ(c.total(), 4.0);
}

TEST(Moments, ForgetToWindowCapsEveryWeight) {
  std::vector<float> n = {3.0f, 100.0f, 50.0f, 49.5f, 1e30f};
  forget_to_window(n.data(), 4, 0.02);  // the last 1/alpha = 50 rewards; the fifth not in range
  EXPECT_EQ(n, (std::vector<float>{3.0f, 50.0f, 50.0f, 49.5f, 1e30f}));
  std::vector<float> m = {7.0f};
  forget_to_window(m.data(), 0, 0.5);  // none
  EXPECT_EQ(m[0], 7.0f);
  forget_to_window(m.data(), 1, double(0.3f));  // cap float(1 / 0.3f)
  EXPECT_EQ(m[0], float(1.0 / double(0.3f)));
}
