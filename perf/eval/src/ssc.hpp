#pragma once
// ANMS by Suppression via Square Covering (Bailo et al., "Efficient adaptive
// non-maximal suppression algorithms for homogeneous spatial keypoint
// distribution", Pattern Recognition Letters 2018): a binary search on the
// suppression width over a coverage grid, keypoints taken by response.

#include <cstdint>
#include <vector>

namespace keepless::eval {

struct SscPoint {
  double x = 0, y = 0;
  double response = 0;
  std::uint64_t id = 0;  // tie-break: equal responses by ascending id
};

// Indices into `points` of exactly min(k, points.size()) selections: SSC's
// set, trimmed by response, or topped up by response when SSC returns fewer.
std::vector<std::uint32_t> ssc_select(const std::vector<SscPoint>& points, std::uint32_t k, int cols,
                                      int rows, double tolerance = 0.1);

// ANMS over several images: each group (one image's points) keeps its share
// of k in proportion to its size (largest remainder, ties to the earlier
// group), chosen by ssc_select on its image. Per group, the kept indices
// into it; min(k, total) in all.
std::vector<std::vector<std::uint32_t>> ssc_select_shared(const std::vector<std::vector<SscPoint>>& groups,
                                                          std::uint32_t k, int cols, int rows);

}  // namespace keepless::eval
