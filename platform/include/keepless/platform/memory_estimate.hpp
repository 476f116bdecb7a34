#pragma once
// The bytes a Window and a Sparsifier sized to some Capacities will take,
// known before allocating them, so a tool can refuse an input or a flag set
// whose fixed memory exceeds its limit (exit 2) instead of dying in
// bad_alloc. Measured on small probe instances (megabytes at most) and
// extrapolated: linear in points, observations, pair arcs and one keyframe's
// observations (its scratch), quadratic in keyframes (keyframe pairs), plus
// the point-id hash tables, whose slots are the power of two at or above
// twice the points.

#include <cstddef>
#include <cstdint>

#include "keepless/core/config.hpp"
#include "keepless/core/sparsifier.hpp"

namespace keepless::platform {

struct MemoryModel {
  double base = 0;
  double per_keyframe = 0;
  double per_keyframe_pair = 0;  // per K(K-1)/2
  double per_point = 0;
  double per_observation = 0;
  double per_pair_arc = 0;
  double per_keyframe_observation = 0;  // per keyframe_observation_limit (one keyframe's scratch)
  double per_table_slot = 0;  // per slot of the point-id tables (table_slots)
  double bytes(const core::Capacities& c) const;
  static double table_slots(std::uint32_t points);
};

// `windows` Windows plus one Sparsifier(params, mode) per capacity set.
MemoryModel probe_memory_model(const core::Params& params, core::SolveMode mode, std::uint32_t windows);

}  // namespace keepless::platform
