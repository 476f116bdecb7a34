#pragma once
// Rigid poses for the evaluation: T_wc (camera to world), camera looking down
// +z with x right and y down, as TUM, EuRoC (left camera) and KITTI give them.

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace keepless::eval {

struct Pose {
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();  // rotation camera -> world
  Eigen::Vector3d t = Eigen::Vector3d::Zero();            // camera centre in world

  Eigen::Matrix3d R() const { return q.toRotationMatrix(); }
  Pose inverse() const {
    Pose p;
    p.q = q.conjugate();
    p.t = -(p.q * t);
    return p;
  }
  Pose operator*(const Pose& o) const {
    Pose p;
    p.q = (q * o.q).normalized();
    p.t = q * o.t + t;
    return p;
  }
  Eigen::Vector3d operator*(const Eigen::Vector3d& x) const { return q * x + t; }
};

// The angle of a rotation, radians, in [0, pi].
inline double rotation_angle(const Eigen::Quaterniond& q) {
  const double w = std::abs(q.w());
  const double v = q.vec().norm();
  return 2.0 * std::atan2(v, w);
}

inline Eigen::Quaterniond small_rotation(const Eigen::Vector3d& axis_angle) {
  const double a = axis_angle.norm();
  if (a < 1e-15) return Eigen::Quaterniond::Identity();
  return Eigen::Quaterniond(Eigen::AngleAxisd(a, axis_angle / a));
}

}  // namespace keepless::eval
