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
  // What keyframes[i].unmapped points at (empty without unmapped keypoints).
  std::vector<std::vector<core::Keypoint>> unmapped;
};

// What the cost models read beyond the paper's inputs (SyntheticSpec):
// intrinsics and depths, unmapped keypoints per keyframe.
struct StreamExtras {
  bool camera = false;
  std::uint32_t unmapped_per_kf = 0;
};

// `total` keyframes of workload `name`; false for an unknown name. The
// extras never change the points, views or keypoints of the stream.
bool make_stream(const std::string& name, std::uint32_t total, std::uint64_t seed,
                 const StreamExtras& extras, KeyframeStream* out);

// The largest needs of any window of the stream (the last K keyframes after
// each keyframe), unmapped keypoints included: the capacities the decision
// path is sized with, exactly.
core::Capacities window_needs(const KeyframeStream& stream);

}  // namespace keepless::perf
