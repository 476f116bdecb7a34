// platform::MonotonicClock: the solver's deadline clock on the board.

#include "keepless/platform/monotonic_clock.hpp"

#include <gtest/gtest.h>
#include <time.h>

#include <cstdint>

namespace keepless::platform {
namespace {

std::uint64_t clock_monotonic_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::uint64_t>(ts.tv_sec) * 1000000000ull + static_cast<std::uint64_t>(ts.tv_nsec);
}

// CLOCK_MONOTONIC in nanoseconds (not the wall clock, which NTP may step):
// each read lies between two direct reads around it.
TEST(MonotonicClock, ReadsClockMonotonicInNanoseconds) {
  const MonotonicClock clock;
  const solver::Clock& as_solver_clock = clock;
  for (int i = 0; i < 3; ++i) {
    const std::uint64_t before = clock_monotonic_ns();
    const std::uint64_t read = as_solver_clock.now_ns();
    const std::uint64_t after = clock_monotonic_ns();
    EXPECT_LE(before, read);
    EXPECT_LE(read, after);
  }
}

}  // namespace
}  // namespace keepless::platform
