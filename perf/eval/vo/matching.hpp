#pragma once
// ORB-SLAM2's ORBmatcher searches, by projection and descriptor distance:
// TH_HIGH 100 on projection searches, TH_LOW 50 where no pose guides the
// search (initialisation, triangulation), ratio tests as ORB-SLAM2 sets them.

#include <vector>

#include <Eigen/Geometry>

#include "vo_map.hpp"

namespace keepless::eval::vo {

constexpr int kHammingHigh = 100;
constexpr int kHammingLow = 50;

// A frame being tracked: its features, pose and matched map points.
struct TrackedFrame {
  int index = 0;
  Frame f;
  Eigen::Isometry3d Tcw = Eigen::Isometry3d::Identity();
  std::vector<int> mp;  // per keypoint, -1 = none
  std::vector<bool> outlier;
};

// The previous frame's matched points projected into `cur` (radius th x the
// keypoint's scale, levels around the previous one). Returns new matches.
int search_by_projection(TrackedFrame& cur, const TrackedFrame& last, const Map& map,
                         const PinholeCamera& cam, double th);

// Local map points (not yet matched in `cur`) in its frustum; counts them
// visible; radius th x (2.5 or 4 by viewing angle) x scale; ratio 0.8.
int search_local_points(TrackedFrame& cur, Map& map, const std::vector<int>& points,
                        const PinholeCamera& cam, double th);

// ORB-SLAM2's Fuse: `points` projected into keyframe kf (radius 3 x scale);
// a matched keypoint's own point and the projected one become one (the one
// with more observations survives), an unmatched keypoint gains the
// observation. Returns fused + added.
int fuse(Map& map, int kf, const std::vector<int>& points, const PinholeCamera& cam);

// The epipolar geometry of keyframe a seen from b: F with x_b^T F x_a = 0,
// and a's centre projected into b (b's keypoints near it carry no depth).
struct EpipolarGeometry {
  Eigen::Matrix3d F;
  double epipole_u = 0, epipole_v = 0;
};
EpipolarGeometry epipolar_geometry(const KeyFrame& a, const KeyFrame& b, const PinholeCamera& cam);

// Unmatched keypoint pairs of keyframes a and b that satisfy the epipolar
// constraint (chi2 3.84 at the level of b's keypoint), Hamming <= 50, ratio 0.7,
// not near the epipole (monocular).
std::vector<std::pair<int, int>> search_for_triangulation(const Map& map, int a, int b,
                                                          const PinholeCamera& cam);

}  // namespace keepless::eval::vo
