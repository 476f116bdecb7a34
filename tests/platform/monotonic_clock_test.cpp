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

// A queued message's arrival: moved back by the wall-clock wait LCM's stamp
// shows, never before the queue was last seen empty. Review: a 2 s
// wall-clock step while a keyframe was queued (it had waited microseconds)
// read as 2 s of queueing (the cap was 60 s), so the default 5 ms target
// stopped its decision and latency_max_ns kept the 2 s.
TEST(QueuedArrival, AWallClockStepInventsNoWaiting) {
  const std::uint64_t now = 50'000'000'000;   // monotonic
  const std::uint64_t empty = now - 300'000;  // the queue was empty 0.3 ms ago
  const std::int64_t wall = 1'700'000'000'000'000;
  EXPECT_EQ(queued_arrival_ns(now, wall, wall - 100, empty), now - 100'000) << "a real 0.1 ms wait";
  EXPECT_EQ(queued_arrival_ns(now, wall + 2'000'000, wall - 100, empty), empty) << "a 2 s step: at most 0.3 ms";
  EXPECT_EQ(queued_arrival_ns(now, wall, wall + 3'000'000, empty), now) << "a stamp in the future";
  EXPECT_EQ(queued_arrival_ns(now, wall, 0, empty), now) << "no stamp";
  EXPECT_EQ(queued_arrival_ns(now, wall, wall - 100, now + 5), now) << "a queue seen empty later than now";
  EXPECT_EQ(queued_arrival_ns(100, wall, 1, 0), 0u) << "never before the clock's zero";
}

}  // namespace
}  // namespace keepless::platform
