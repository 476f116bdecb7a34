#pragma once

#include <cstdint>

#include "keepless/solver/min_cost_flow.hpp"

namespace keepless::platform {

// CLOCK_MONOTONIC in nanoseconds: never goes backwards, unaffected by NTP steps.
std::uint64_t monotonic_ns();

// monotonic_ns() as the solver's deadline clock (solver::Budget::clock).
class MonotonicClock final : public solver::Clock {
 public:
  std::uint64_t now_ns() const override { return monotonic_ns(); }
};

}  // namespace keepless::platform
