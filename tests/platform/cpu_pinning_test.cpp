// platform::pin_to_cpus: what the node and the benchmarks report as pinned.

#include "keepless/platform/cpu_pinning.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <string>

namespace keepless::platform {
namespace {

TEST(CpuList, RangesAndListsParseAndMalformedTextIsRefused) {
  std::uint64_t mask[16];
  ASSERT_TRUE(parse_cpu_list("0,2-3,1023", mask));
  EXPECT_EQ(mask[0], 0b1101u);
  EXPECT_EQ(mask[15], 1ull << 63);
  for (const char* bad : {"", "1024", "-1", "3-2", "0,", "a", "0;1"}) EXPECT_FALSE(parse_cpu_list(bad, mask)) << bad;
}

// The kernel grants a list that holds one usable CPU and drops the others:
// that was reported as pinned.
TEST(CpuPinning, AListGrantedInPartIsNotPinned) {
  const std::string before = current_cpus();
  ASSERT_FALSE(before.empty());
  const PinResult part = pin_to_cpus(before + ",1023");  // no test machine has CPU 1023
  EXPECT_FALSE(part.ok);
  EXPECT_EQ(part.granted, before);
  EXPECT_EQ(part.error, "only some of them exist or are allowed");
  const PinResult all = pin_to_cpus(before);
  EXPECT_TRUE(all.ok) << all.error;
  EXPECT_EQ(all.granted, before);
  const PinResult malformed = pin_to_cpus("0-");
  EXPECT_FALSE(malformed.ok);
  EXPECT_EQ(malformed.error, "malformed CPU list '0-'");
}

}  // namespace
}  // namespace keepless::platform
