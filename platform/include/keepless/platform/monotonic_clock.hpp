#pragma once

#include <cstdint>

#include "keepless/solver/min_cost_flow.hpp"

namespace keepless::platform {

// CLOCK_MONOTONIC in nanoseconds: never goes backwards, unaffected by NTP steps.
std::uint64_t monotonic_ns();

// When a message arrived, on the monotonic clock: `now_ns`, moved back by
// the time it waited in a queue that stamped its receipt on the wall clock
// (`wall_us` now, `received_us` then), but never further back than
// `queue_empty_ns`, the last time the queue was seen empty: a wall-clock
// step (NTP, PTP, a board without an RTC syncing) then invents no waiting.
std::uint64_t queued_arrival_ns(std::uint64_t now_ns, std::int64_t wall_us, std::int64_t received_us,
                                std::uint64_t queue_empty_ns);

// monotonic_ns() as the solver's deadline clock (solver::Budget::clock).
class MonotonicClock final : public solver::Clock {
 public:
  std::uint64_t now_ns() const override { return monotonic_ns(); }
};

}  // namespace keepless::platform
