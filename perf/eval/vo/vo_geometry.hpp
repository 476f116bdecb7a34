// Geometry the real VO's tracking, initialisation and mapping share: poses
// from OpenCV's vectors, linear triangulation, a seeded RANSAC order.
#pragma once

#include <cmath>
#include <cstddef>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <opencv2/core.hpp>

#include "prng.hpp"

namespace keepless::eval::vo::detail {

// A seeded order for RANSAC's samples: OpenCV's RANSAC has its own fixed
// generator, so the seed acts through the order of the correspondences.
std::vector<int> shuffled(std::size_t n, Rng& rng);

Eigen::Isometry3d pose_from_cv(const cv::Mat& rvec, const cv::Mat& tvec);

// A fraction 1/n of a motion (for the velocity over an initialisation gap).
Eigen::Isometry3d motion_fraction(const Eigen::Isometry3d& T, int n);

// The DLT point of rows x * P.row(2) - P.row(0|1), one pair per view: the
// right singular vector of the smallest singular value, dehomogenised.
template <typename Rows>
bool dlt_point(const Rows& A, Eigen::Vector3d* X) {
  Eigen::JacobiSVD<typename Rows::PlainObject> svd(A, Eigen::ComputeFullV);
  const Eigen::Vector4d h = svd.matrixV().col(3);
  if (std::abs(h(3)) < 1e-12) return false;
  *X = h.head<3>() / h(3);
  return X->allFinite();
}

// Linear triangulation (ORB-SLAM2's Initializer::Triangulate).
bool triangulate(const Eigen::Matrix<double, 3, 4>& P1, const Eigen::Matrix<double, 3, 4>& P2,
                 const cv::Point2f& x1, const cv::Point2f& x2, Eigen::Vector3d* X);

}  // namespace keepless::eval::vo::detail
