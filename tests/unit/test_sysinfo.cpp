// Machine facts for reports: the machine's description and the commit rll was built from.
#include <gtest/gtest.h>

#include <regex>

#include "rll/core/sysinfo.h"

using namespace rll;

TEST(Sysinfo, MachineDescriptionNamesCpuCoresAndMemory) {
  const std::string m = machine_description();
  // "<model>, <n> logical cores, <x.y> GiB"; /proc exists wherever the tests run.
  EXPECT_TRUE(std::regex_match(m, std::regex(".+, [1-9][0-9]* logical cores, [0-9]+\\.[0-9] GiB")))
      << m;
}

TEST(Sysinfo, BuildCommitIsAShortHashOrUnknown) {
  const std::string c = build_commit();
  EXPECT_TRUE(std::regex_match(c, std::regex("[0-9a-f]{7,40}(-dirty)?|unknown"))) << c;
}
