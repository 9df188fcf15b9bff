// The Sidak correction of this suite's chi-square tests rests on kSuiteChi2Tests bounding how
// many there are: this fails when cases are added without raising it.
#include <gtest/gtest.h>

#include "support/sphere_chi2.h"

size_t bsdf_chi2_test_count();   // tests/stat/test_bsdf.cpp
size_t light_chi2_test_count();  // tests/stat/test_light.cpp
// tests/unit/test_sampling.cpp: DiscreteDistribution (2) and SampleStream (2);
// tests/unit/test_sphere_chi2.cpp: the two that must pass (the others must fail).
constexpr size_t kUnitChi2Tests = 6;

TEST(Chi2Budget, SuiteBoundCoversEveryTest) {
  const size_t total = bsdf_chi2_test_count() + light_chi2_test_count() + kUnitChi2Tests;
  EXPECT_LE(total, size_t(rll::test::kSuiteChi2Tests))
      << "raise kSuiteChi2Tests in tests/support/sphere_chi2.h to at least " << total;
  RecordProperty("chi2_tests", int(total));
}
