#pragma once

#include <cstdint>

namespace keepless::platform {

// CLOCK_MONOTONIC in nanoseconds: never goes backwards, unaffected by NTP steps.
std::uint64_t monotonic_ns();

}  // namespace keepless::platform
