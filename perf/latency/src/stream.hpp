#pragma once
// A deterministic keyframe stream for keepless_latency: the named workload's
// window (K keyframes) sliding over a longer synthetic corridor with the
// same density of points per keyframe, so every window looks like the
// workload and each keyframe brings in new points and retires old ones.

#include <cstdint>
#include <string>
#include <vector>

#include "keepless/core/config.hpp"
#include "keepless/core/window.hpp"

namespace keepless::perf {

struct KeyframeStream {
  std::string workload;
  std::uint32_t window = 0;  // K
  std::vector<core::Keyframe> keyframes;
  std::vector<std::vector<core::Observation>> observations;
};

// `total` keyframes of workload `name`; false for an unknown name.
bool make_stream(const std::string& name, std::uint32_t total, std::uint64_t seed,
                 KeyframeStream* out);

// The largest needs of any window of the stream (the last K keyframes after
// each keyframe): the capacities the decision path is sized with, exactly.
core::Capacities window_needs(const KeyframeStream& stream);

}  // namespace keepless::perf
