#pragma once
// Bundle adjustment in Ceres for the SLAM simulation, as ORB-SLAM2's
// Optimizer does it: poses T_cw as angle-axis + translation, points in world
// coordinates, stereo (u, v, u_r) or monocular (u, v) reprojection residuals
// at 1 px information, chi-square thresholds 5.991 (mono) / 7.815 (stereo).
//   - local BA: a robust (Huber) solve, the chi-square outliers dropped, a
//     second solve without the robust kernel, then the outliers reported;
//   - motion-only BA (tracking): the pose alone against fixed map points, four
//     rounds re-classifying outliers, the robust kernel dropped in the last two.
// Single-threaded so that a seed gives the same numbers on every run.

#include <array>
#include <vector>

#include "scenario.hpp"

namespace keepless::eval {

struct BaObservation {
  int pose = 0;   // index into BaInput::poses
  int point = 0;  // index into BaInput::points
  double u = 0, v = 0, ur = -1;
};

struct BaInput {
  std::vector<double*> poses;  // 6 doubles each (angle-axis, t) of T_cw
  std::vector<bool> pose_fixed;
  std::vector<double*> points;  // 3 doubles each
  std::vector<BaObservation> observations;
};

struct BaResult {
  double seconds = 0;
  int iterations = 0;
  std::vector<bool> outlier;  // chi2 above its threshold (or behind the camera) after the second solve
};

// Stage 1: `robust_iterations` with Huber; stage 2: `iterations` without.
BaResult solve_local_ba(const Camera& cam, const BaInput& in, int robust_iterations, int iterations);

struct PoseObservation {
  const double* X = nullptr;  // world point, held fixed
  double u = 0, v = 0, ur = -1;
};

struct PoseResult {
  int inliers = 0;
  std::vector<bool> outlier;  // per observation, after the last round
  double seconds = 0;
};

// Refines `pose` (T_cw block) in place from its initial value.
PoseResult optimize_pose(const Camera& cam, const std::vector<PoseObservation>& obs, double* pose);

// Chi-square of one observation at a pose block (1e18 behind the camera).
double reprojection_chi2(const Camera& cam, const double* pose, const double* X, double u, double v, double ur);
double chi2_threshold(const Camera& cam, double ur);

// Pose conversions between T_wc (Pose) and the solver's T_cw block.
std::array<double, 6> to_block(const Pose& T_wc);
Pose from_block(const double* block);

}  // namespace keepless::eval
