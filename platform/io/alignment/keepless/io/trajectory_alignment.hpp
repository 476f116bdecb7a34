#pragma once
// Comparing camera centres up to a similarity (bundle adjustment leaves the
// gauge, scale included, free): Umeyama's least-squares alignment, then the
// residual distances. Header-only, for the maps bench and tests through the
// build-tree target keepless_io_alignment (Eigen): not installed, so the io
// library needs nothing beyond core.

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <vector>

namespace keepless::io {

struct AlignedDeviation {
  double max = 0;  // in `reference`'s units
  double rms = 0;
  double scale = 1;  // of the similarity mapping `estimate` onto `reference`
};

// The similarity (4x4, scale times rotation | translation) that maps `estimate`
// onto `reference` best in least squares; `estimate[i]` and `reference[i]` are
// one camera's centres (at least 3).
inline Eigen::Matrix4d umeyama_similarity(const std::vector<std::array<double, 3>>& reference,
                                          const std::vector<std::array<double, 3>>& estimate) {
  const Eigen::Index n = static_cast<Eigen::Index>(reference.size());
  Eigen::Matrix3Xd ref(3, n), est(3, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    ref.col(i) = Eigen::Vector3d(reference[i].data());
    est.col(i) = Eigen::Vector3d(estimate[i].data());
  }
  return Eigen::umeyama(est, ref, true);
}

inline AlignedDeviation aligned_deviation(const std::vector<std::array<double, 3>>& reference,
                                          const std::vector<std::array<double, 3>>& estimate) {
  const Eigen::Matrix4d T = umeyama_similarity(reference, estimate);
  AlignedDeviation d;
  d.scale = T.block<3, 1>(0, 0).norm();
  double sum = 0;
  for (std::size_t i = 0; i < reference.size(); ++i) {
    const double e = (T.block<3, 3>(0, 0) * Eigen::Vector3d(estimate[i].data()) + T.block<3, 1>(0, 3) -
                      Eigen::Vector3d(reference[i].data()))
                         .norm();
    d.max = std::max(d.max, e);
    sum += e * e;
  }
  d.rms = reference.empty() ? 0 : std::sqrt(sum / static_cast<double>(reference.size()));
  return d;
}

}  // namespace keepless::io
