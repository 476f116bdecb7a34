#include "point_quality.hpp"

#include <algorithm>
#include <cmath>

namespace keepless::eval::vo {

core::PointQuality point_quality(const Map& map, int p, int kf, const PinholeCamera& cam) {
  const MapPoint& m = map.points[static_cast<std::size_t>(p)];
  core::PointQuality q;
  q.track_length = static_cast<std::uint32_t>(m.obs.size());
  q.age = std::max(0, kf - m.first_kf);
  // RMS reprojection error over the observations in front of their camera
  // (pixels, at level 0), and the smallest cosine between two viewing rays.
  double squared = 0.0, min_cos = 1.0;
  int used = 0;
  for (std::size_t i = 0; i < m.obs.size(); ++i) {
    const KeyFrame& a = map.kfs[static_cast<std::size_t>(m.obs[i].first)];
    const Eigen::Vector3d x = a.Tcw * m.X;
    if (x.z() <= 0) continue;
    const cv::KeyPoint& key = a.f.keys[static_cast<std::size_t>(m.obs[i].second)];
    const double du = cam.fx * x.x() / x.z() + cam.cx - key.pt.x;
    const double dv = cam.fy * x.y() / x.z() + cam.cy - key.pt.y;
    squared += du * du + dv * dv;
    ++used;
    const Eigen::Vector3d ray_a = (m.X - a.centre()).normalized();
    for (std::size_t j = i + 1; j < m.obs.size(); ++j) {
      const Eigen::Vector3d ray_b = (m.X - map.kfs[static_cast<std::size_t>(m.obs[j].first)].centre()).normalized();
      min_cos = std::min(min_cos, ray_a.dot(ray_b));
    }
  }
  if (used > 0) q.reprojection_error = static_cast<float>(std::sqrt(squared / used));
  if (m.obs.size() >= 2) {
    q.triangulation_angle = static_cast<float>(std::acos(std::clamp(min_cos, -1.0, 1.0)) * (180.0 / 3.14159265358979323846));
  }
  return q;
}

}  // namespace keepless::eval::vo
