#pragma once
// Trajectory accuracy as the paper defines it (section IV-B): RMS ATE in
// metres after Umeyama alignment, and RMS ATE_r in degrees, the angle of
// E_i = Q_i^-1 P_i with P_i the aligned estimate (evo's APE "angle_deg").

#include <vector>

#include <Eigen/Core>

#include "geometry.hpp"

namespace keepless::eval {

struct Alignment {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  double s = 1.0;
};

// Least-squares (s, R, t) with dst ~ s R src + t (Umeyama 1991); s = 1 when
// !with_scale (SE(3)). Needs >= 3 non-collinear points for a unique R.
Alignment umeyama(const std::vector<Eigen::Vector3d>& src, const std::vector<Eigen::Vector3d>& dst,
                  bool with_scale);

struct Ate {
  double rms_m = 0;
  double rms_r_deg = 0;
};

// with_scale: Sim(3) alignment (evo's --align --correct_scale), for
// monocular runs whose scale is not observable; otherwise SE(3) (--align).
// rms_m is after Umeyama's alignment always; rms_r_deg too, but where the
// estimated positions are nearly collinear (second eigenvalue of their
// scatter < 1e-3 of the first) its rotation comes from the orientations.
Ate absolute_trajectory_error(const std::vector<Pose>& estimate, const std::vector<Pose>& ground_truth,
                              bool with_scale);

// A keyframe culled on the way, as ORB-SLAM2 keeps it: its parent at the time
// (a keyframe then alive) and the relative pose T_parent,kf then.
struct CulledLink {
  int parent = -1;  // -1: the keyframe is alive
  Pose rel;
};

// The trajectory ORB-SLAM2 outputs: an alive keyframe's own pose; a culled
// one's parent pose (resolved the same way, recursively) composed with the
// stored relative pose, so culled keyframes follow their parent's correction.
std::vector<Pose> resolve_keyframe_poses(const std::vector<Pose>& pose, const std::vector<CulledLink>& link);

}  // namespace keepless::eval
