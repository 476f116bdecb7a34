#pragma once
// A whole model kept at exactly a requested count of points with every
// image's floor (keepless_maps_bench's keepless_exact rows).

#include <cstdint>
#include <vector>

#include "keepless/core/decision.hpp"

namespace keepless::sparsify {

struct ExactCount {
  std::uint64_t kept = 0;      // points not culled at the end (== count unless the floor alone needs more)
  std::uint64_t from_order = 0;  // kept by the threshold order (the rest: the floor's and the skipped)
  std::uint32_t restored = 0;  // kept by the floor
  bool floor_fits = true;      // false: the floor alone keeps more than `count`
};

// `decisions` (ascending id, every point of the model) and `thresholds` (each
// decision's keep threshold M*, core::Sparsifier::keep_thresholds(): 0 for a
// skipped point) from one budgeted whole-model decision. Points are taken in
// the budget's order (smallest M*, then smaller id): the largest prefix that,
// with apply_floor's restorations and the skipped points (never culled),
// stays within `count` (binary search), then the next points of the order
// until exactly `count` are kept. Adding points never breaks the floor.
// A track share (core::KeepBudget::track_share) reorders the points after
// the first count x (1 - share) by their observations in `images` (COLMAP's
// track length, duplicates included), most first (core::take_longest_tracks),
// before the search.
ExactCount keep_exactly(const std::vector<std::vector<core::PointId>>& images, std::uint32_t floor,
                        std::uint64_t count, const std::vector<std::uint32_t>& thresholds,
                        std::vector<core::PointDecision>* decisions, double track_share = 0.0);

// The observations of the poorest image (kept_observations) when the
// skipped points and the `count` minus them with the most observations in
// `images` are kept: where longest-track-first, and so COLMAP's
// point_filtering at its own count, leaves the poorest image
// (--floor-over-longest). Ties at the cut go to the smaller id (keep_exactly
// breaks them by the threshold order); 0 when an image is left none.
std::uint32_t longest_tracks_poorest(const std::vector<std::vector<core::PointId>>& images,
                                     std::vector<core::PointDecision> decisions, std::uint64_t count);

// ceil(r x observations), saturated: the floor r above an image's
// observations. The product is rounded down by a relative 1e-12 first, so
// 1.1 x 330 is 363, not 364 (363.00000000000006 in binary).
std::uint32_t floor_over(double r, std::uint32_t observations);

}  // namespace keepless::sparsify
