#pragma once
// Ceres bundle adjustment for the VO, as ORB-SLAM2's Optimizer does it with
// g2o: poses T_cw as angle-axis + translation, reprojection residuals in
// pixels weighted by 1/scale of the keypoint's level, monocular (u, v) or
// RGB-D (u, v, u_r) with Huber at the chi-square 95 % thresholds (5.991,
// 7.815). Single-threaded: the same input gives the same output.

#include <array>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "real_sequence.hpp"

namespace keepless::eval::vo {

constexpr double kChi2Mono = 5.991;
constexpr double kChi2Stereo = 7.815;

using PoseBlock = std::array<double, 6>;  // angle-axis, t of T_cw
PoseBlock to_block(const Eigen::Isometry3d& Tcw);
Eigen::Isometry3d from_block(const PoseBlock& b);

struct BaObservation {
  int pose = 0, point = 0;
  double u = 0, v = 0, ur = -1;  // ur < 0: monocular
  int level = 0;
};

// Motion-only BA (ORB-SLAM2 PoseOptimization): 4 rounds of 10 iterations,
// outliers re-classified after each, Huber in the first two. `outlier` is
// in/out (one per observation); returns the inliers.
int optimize_pose(const PinholeCamera& cam, const std::vector<Eigen::Vector3d>& points,
                  const std::vector<BaObservation>& obs, Eigen::Isometry3d* Tcw, std::vector<bool>* outlier);

struct LocalBaProblem {
  std::vector<PoseBlock> poses;
  std::vector<bool> pose_fixed;
  std::vector<Eigen::Vector3d> points;
  std::vector<bool> point_fixed;  // per point (empty: none): held constant, a landmark
  std::vector<BaObservation> observations;
};

// Local BA (ORB-SLAM2 LocalBundleAdjustment): 5 robust iterations, outliers
// dropped, 10 more without the robust kernel. Returns per observation
// whether it is an outlier after the solve.
std::vector<bool> solve_local_ba(const PinholeCamera& cam, LocalBaProblem* problem);

// Structure-only BA of one point, the observing poses held (tcw[i] is
// obs[i]'s camera; obs[i].pose is not read): Gauss-Newton with Huber at the
// chi-square 95 % thresholds, outliers classified, then again without the
// robust kernel on the inliers, as local BA treats a point. `outlier` gets
// one flag per observation. False (X unchanged) if fewer than two inliers
// remain or the point falls behind a camera.
bool refine_point(const PinholeCamera& cam, const std::vector<Eigen::Isometry3d>& tcw,
                  const std::vector<BaObservation>& obs, Eigen::Vector3d* X, std::vector<bool>* outlier);

// Motion-only refinement of one pose, the points held: refine_point's
// Gauss-Newton on a left SE(3) increment (Huber, outliers classified, again
// without the kernel on the inliers). A fraction of optimize_pose's cost
// (no Ceres problem, 10 iterations instead of 40), for refining many poses
// against points the local BA left out. Returns the inliers; the pose is
// left as it was below 10.
int refine_pose(const PinholeCamera& cam, const std::vector<Eigen::Vector3d>& points,
                const std::vector<BaObservation>& obs, Eigen::Isometry3d* Tcw, std::vector<bool>* outlier);

// chi2 of one observation (weighted squared error); +inf behind the camera.
double chi2(const PinholeCamera& cam, const Eigen::Isometry3d& Tcw, const Eigen::Vector3d& X,
            const BaObservation& o);

}  // namespace keepless::eval::vo
