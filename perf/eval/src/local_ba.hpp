#pragma once
// Bundle adjustment in Ceres for the SLAM simulation: poses T_cw as
// angle-axis + translation, points in world coordinates, stereo (u, v, u_r)
// or monocular (u, v) reprojection residuals, Huber loss at ORB-SLAM2's
// chi-square thresholds (5.991 mono, 7.815 stereo, 1 px information).
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
  std::vector<double> chi2;     // per observation after the solve
  std::vector<bool> outlier;    // chi2 above its threshold
};

BaResult solve_local_ba(const Camera& cam, const BaInput& in, int max_iterations);

// Pose conversions between T_wc (Pose) and the solver's T_cw block.
std::array<double, 6> to_block(const Pose& T_wc);
Pose from_block(const double* block);

}  // namespace keepless::eval
