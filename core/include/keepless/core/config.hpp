#pragma once
// Every capacity and parameter of the decision path, in one place. Storage is
// sized from Capacities once, at construction; nothing grows afterwards.

#include <cstddef>
#include <cstdint>

namespace keepless::core {

using KeyframeId = std::uint64_t;
using PointId = std::uint64_t;

struct Capacities {
  std::uint32_t max_keyframes = 32;        // window keyframes (K)
  std::uint32_t max_points = 16384;        // distinct point ids in the window
  std::uint32_t max_observations = 40000;  // (keyframe, point) observations
  std::uint32_t max_pair_arcs = 131072;    // point -> keyframe-pair arcs
};

// Bits of Params::cost_terms.
enum CostTerm : std::uint8_t { kConnectivityCost = 1, kSpatialCost = 2, kBaselineCost = 4 };

// The paper's section III-B parameters.
struct Params {
  std::int64_t pair_capacity = 100;  // M
  double theta = 0.5;                // keep iff flow > theta * n(n-1)/2
  std::int32_t box_width = 64;       // spatial-diversity box, pixels (closed, centred)
  std::int32_t box_height = 48;
  // Which costs the network uses (the paper's ablation); the default, all
  // three, is the paper's method. A term switched off costs 0 on its arcs.
  std::uint8_t cost_terms = kConnectivityCost | kSpatialCost | kBaselineCost;
};

}  // namespace keepless::core
