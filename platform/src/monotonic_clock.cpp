#include "keepless/platform/monotonic_clock.hpp"

#include <time.h>

namespace keepless::platform {

std::uint64_t monotonic_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::uint64_t>(ts.tv_sec) * 1000000000ull + static_cast<std::uint64_t>(ts.tv_nsec);
}

std::uint64_t queued_arrival_ns(std::uint64_t now_ns, std::int64_t wall_us, std::int64_t received_us,
                                std::uint64_t queue_empty_ns) {
  const std::uint64_t most = now_ns > queue_empty_ns ? now_ns - queue_empty_ns : 0;
  if (received_us <= 0 || wall_us <= received_us) return now_ns;  // no stamp, or one in the future
  const auto waited_us = static_cast<std::uint64_t>(wall_us) - static_cast<std::uint64_t>(received_us);
  const std::uint64_t waited_ns = waited_us > most / 1000 ? most : waited_us * 1000;
  return now_ns - waited_ns;
}

}  // namespace keepless::platform
