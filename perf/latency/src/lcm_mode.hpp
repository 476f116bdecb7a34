#pragma once
// keepless_latency's bus side (when built with LCM): the two-process
// measurement through keepless_node, and reading a recorded LCM log as the
// keyframe stream. Both allocate freely: neither is the decision path.

#include <cstdint>
#include <string>
#include <vector>

#include "stream.hpp"

namespace keepless::perf {

struct LcmResult {
  std::uint32_t decisions = 0;  // measured (after warm-up)
  std::uint32_t lost = 0;       // keyframes without a decision within the timeout
  double p50_ms = 0, p90_ms = 0, p99_ms = 0, max_ms = 0;
};

// Starts keepless_node (next to `argv0`) on a process-unique udpm port with
// ttl=0, publishes the stream's keyframes one at a time and times each from
// publish to the matching decision's arrival. `node_flags` (the policy) are
// passed to the node after the capacities, with the latency target
// (`latency_target_ms`, 0: none). Stops the node at the end.
bool run_lcm_mode(const char* argv0, const KeyframeStream& stream, std::uint32_t warmup, double latency_target_ms,
                  const std::vector<std::string>& node_flags, LcmResult* out, std::string* error);

// The keyframe_t messages on channel KEEPLESS_KEYFRAME of an LCM log, in
// log order, as a stream with the node's default window (20).
bool read_lcm_log(const std::string& path, KeyframeStream* out, std::string* error);

}  // namespace keepless::perf
