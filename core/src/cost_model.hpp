#pragma once
// The cost model (Params::cost_model) as the network builders use it: per
// keyframe, one integer per observation (N(p, f) for the paper's box or the
// authors' grid, the information level for kInformation, the quality level
// for kTrack), computed when the
// keyframe arrives; the point -> pair cost as a function of the two
// observations' integers, and the pair -> sink cost of two camera centres.
// Shared by PaperNetwork and IncrementalNetwork, so both price alike.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "box_neighbours.hpp"
#include "keepless/core/config.hpp"
#include "keepless/core/costs.hpp"
#include "keepless/core/window.hpp"

namespace keepless::core {

class ObservationScorer {
 public:
  explicit ObservationScorer(std::uint32_t max_count)
      : box_(max_count), cells_(static_cast<std::size_t>(kGridColumns) * kGridRows) {}

  void score(const Keyframe& kf, const Observation* observations, std::uint32_t count,
             const Params& params, std::uint32_t* out) {
    switch (params.cost_model) {
      case CostModel::kAuthors:
        grid_neighbours(kf, observations, count, params.image_width, params.image_height,
                        cells_.data(), out);
        return;
      case CostModel::kInformation:
        information_levels(kf, observations, count, out);
        return;
      case CostModel::kTrack:
        track_levels(kf, count, params.track_terms, out);
        return;
      case CostModel::kPaper:
        break;
    }
    box_.count(observations, count, params.box_width, params.box_height, out);
  }

  std::size_t memory_bytes() const {
    return box_.memory_bytes() + cells_.capacity() * sizeof(std::uint32_t);
  }

 private:
  BoxCounter box_;
  std::vector<std::uint32_t> cells_;
};

// Every keyframe of `window` within what a scorer sized for `caps` holds
// (keyframe_observation_limit).
inline bool keyframes_fit(const Window& window, const Capacities& caps) {
  const std::uint32_t limit = keyframe_observation_limit(caps);
  for (std::uint32_t s = 0; s < window.keyframe_count(); ++s) {
    if (window.observation_count(s) > limit) return false;
  }
  return true;
}

// Point -> pair cost from the two observations' scores, times
// Params::spatial_weight (0 with the spatial term off).
inline std::int64_t pair_arc_cost(const Params& params, std::uint32_t a, std::uint32_t b) {
  if (!(params.cost_terms & kSpatialCost)) return 0;
  std::int64_t cost = 0;
  switch (params.cost_model) {
    case CostModel::kAuthors: cost = authors_spatial_cost(a, b); break;
    case CostModel::kInformation:
    case CostModel::kTrack: cost = std::int64_t{a} + b; break;
    case CostModel::kPaper: cost = spatial_cost(a, b); break;
  }
  return cost * params.spatial_weight;
}

// Pair -> sink cost (0 with the baseline term off).
inline std::int64_t pair_sink_cost(const Params& params, const double centre_j[3],
                                   const double centre_k[3]) {
  if (!(params.cost_terms & kBaselineCost)) return 0;
  return params.cost_model == CostModel::kAuthors ? authors_baseline_cost(centre_j, centre_k)
                                                  : baseline_cost(centre_j, centre_k);
}

// The parameters that change the network (not the scope or the floor,
// which act on its optimum).
inline bool same_network(const Params& a, const Params& b) {
  return a.pair_capacity == b.pair_capacity && a.box_width == b.box_width &&
         a.box_height == b.box_height && a.cost_terms == b.cost_terms &&
         a.spatial_weight == b.spatial_weight &&
         a.cost_model == b.cost_model && a.image_width == b.image_width &&
         a.image_height == b.image_height && a.track_terms == b.track_terms;
}

}  // namespace keepless::core
