#include "vo_geometry.hpp"

#include <numeric>
#include <utility>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

namespace keepless::eval::vo::detail {

std::vector<int> shuffled(std::size_t n, Rng& rng) {
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  for (std::size_t i = n; i > 1; --i) std::swap(order[i - 1], order[rng.below(static_cast<std::uint32_t>(i))]);
  return order;
}

Eigen::Isometry3d pose_from_cv(const cv::Mat& rvec, const cv::Mat& tvec) {
  cv::Mat R;
  cv::Rodrigues(rvec, R);
  Eigen::Matrix3d Re;
  Eigen::Vector3d te;
  cv::cv2eigen(R, Re);
  cv::cv2eigen(tvec, te);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Re;
  T.translation() = te;
  return T;
}

Eigen::Isometry3d motion_fraction(const Eigen::Isometry3d& T, int n) {
  if (n <= 1) return T;
  const Eigen::AngleAxisd aa(Eigen::Matrix3d(T.linear()));
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = Eigen::AngleAxisd(aa.angle() / n, aa.axis()).toRotationMatrix();
  out.translation() = T.translation() / n;
  return out;
}

bool triangulate(const Eigen::Matrix<double, 3, 4>& P1, const Eigen::Matrix<double, 3, 4>& P2,
                 const cv::Point2f& x1, const cv::Point2f& x2, Eigen::Vector3d* X) {
  Eigen::Matrix4d A;
  A.row(0) = x1.x * P1.row(2) - P1.row(0);
  A.row(1) = x1.y * P1.row(2) - P1.row(1);
  A.row(2) = x2.x * P2.row(2) - P2.row(0);
  A.row(3) = x2.y * P2.row(2) - P2.row(1);
  return dlt_point(A, X);
}

}  // namespace keepless::eval::vo::detail
