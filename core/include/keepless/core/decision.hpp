#pragma once

#include <cstdint>

#include "keepless/core/config.hpp"

namespace keepless::core {

enum class Verdict : std::uint8_t { kKeep = 0, kCull, kSkip };

const char* to_string(Verdict v);  // "keep", "cull", "skip"

struct PointDecision {
  PointId point = 0;
  Verdict verdict = Verdict::kSkip;
  std::int64_t flow = 0;      // flow on source -> point (0 when skipped)
  std::int64_t capacity = 0;  // n(n-1)/2 (0 when skipped)
};

// Keep iff flow > theta * capacity, in double (exact for these magnitudes).
Verdict decide(std::int64_t flow, std::int64_t capacity, double theta);

struct Summary {
  std::uint32_t keyframes = 0;
  std::uint32_t points = 0;     // distinct points in the window
  std::uint32_t evaluated = 0;  // n >= 2
  std::uint32_t kept = 0;
  std::uint32_t culled = 0;
  std::uint32_t skipped = 0;
  std::uint32_t pairs = 0;
  std::uint32_t arcs = 0;  // all network arcs
  std::int64_t max_flow = 0;
  std::int64_t total_cost = 0;
  // Params::scope: evaluated points skipped because the newest keyframe does
  // not observe them (counted in `skipped`).
  std::uint32_t out_of_scope = 0;
  // Scope::kNewest: keyframes decided besides the scope's own one, whose
  // turns were missed (Sparsifier::note_undecided, a call that did not
  // return kOk); 0 while every call decides.
  std::uint32_t caught_up = 0;
  // Scope::kAuto: the smoothed share of evaluated points that came back to
  // the window's keyframes, per mille, and whether this call decided as
  // Scope::kNewest (else as kWindow). 0 and false for the other scopes.
  std::uint32_t returning_permille = 0;
  bool decided_newest = false;
  // Params::coverage_floor: keyframes below the floor when their turn came
  // (the floor bound), the culled points promoted back to keep, and the
  // keyframes still below it with every evaluated point of theirs kept.
  std::uint32_t floor_keyframes = 0;
  std::uint32_t floor_promoted = 0;
  std::uint32_t floor_short = 0;
  // Params::budget: the largest keep threshold M* among the points the
  // budget kept (the M it corresponds to; 0: none kept; Capacities::max_points
  // + 1 when it kept a point no M keeps, KeepThresholds::kNever), and the window
  // observations of the points it kept (before the floor's promotions).
  std::int64_t budget_m = 0;
  std::uint64_t budget_observations = 0;
  // Tracking-safe culling: evaluated points skipped because they are younger
  // than Params::maturity_keyframes, then those skipped because the newest
  // keyframe flags them tracked (Keyframe::tracked); both counted in
  // `skipped`, each point in one of them. With Params::tracked_first and a
  // budget, `tracked` counts the flagged candidates instead (not skipped).
  std::uint32_t guarded = 0;
  std::uint32_t tracked = 0;
  // CostModel::kTrack: window keyframes without point quality
  // (Keyframe::quality), priced by the window's connectivity alone.
  std::uint32_t track_fallback = 0;
};

}  // namespace keepless::core
