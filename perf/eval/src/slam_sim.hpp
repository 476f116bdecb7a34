#pragma once
// The closed-loop keyframe SLAM back end every variant runs on the same
// scenario, following ORB-SLAM2's tracking and local mapping:
//   tracking   each new keyframe, from the odometry prior, by motion-only BA
//              against the local map's points (so culled points really leave
//              tracking); the points in its frustum count as visible, the
//              inliers as found;
//   mapping    recent-point culling (found ratio < 0.25, or two keyframes old
//              with <= 2 (mono) / 3 observations, a stereo one counting twice),
//              new points (stereo at once, monocular by triangulation) fused
//              into the local keyframes' unmatched keypoints, so a culled
//              feature is re-mapped when seen again;
//   selection  none / keepless / ANMS / random / longest track, on the local
//              keyframes, before every local BA;
//   local BA   the new keyframe and its covisible keyframes (at most W), the
//              other observers fixed; robust solve, chi-square outliers out,
//              second solve without the kernel;
//   KF culling a local keyframe whose points are >= 90 % seen by >= 3 other
//              keyframes (close points only, for stereo) goes; its pose then
//              follows its parent's (ORB-SLAM2's trajectory output).

#include <cstdint>
#include <string>
#include <vector>

#include "geometry.hpp"
#include "keepless/core/config.hpp"
#include "run_record.hpp"
#include "scenario.hpp"
#include "window_sizes.hpp"

namespace keepless::eval {

enum class Selector { kNone, kKeepless, kAnms, kRandom, kLongestTrack };
const char* to_string(Selector s);

// One variant: a selector and, for keepless (and the count the baselines
// match), the core parameters it runs with: M, the cost terms, and whatever
// policy core::Params carries.
struct VariantSpec {
  std::string name;  // original, ours, anms, random, longest_track, c_c, ...
  Selector selector = Selector::kNone;
  core::Params params;
};

struct SimOptions {
  int window = 10;                // local keyframes (new + covisible), at most
  int ba_robust_iterations = 5;   // ORB-SLAM2: 5 robust, then 10 without the kernel
  int ba_iterations = 10;
  std::uint64_t seed = 1;         // baselines' priorities
  int snapshot_frame = -1;        // keyframe whose keypoints are recorded (SVG)
  bool measure_windows = false;   // fill RunResult::window_sizes (window_sizes.hpp)
};

struct SnapshotPoint {
  double u, v;
  int state;  // 0 not a map point, 1 kept map point, 2 culled by the selector
};

struct RunResult {
  VariantSpec spec;
  std::uint32_t mps = 0;         // map points alive at the end
  std::uint64_t mps_created = 0;
  std::uint32_t kfs = 0;         // keyframes alive at the end
  std::uint32_t kfs_total = 0;   // keyframes inserted
  std::uint32_t ba_calls = 0;
  std::uint64_t ba_observations = 0;  // residuals over every local BA (the information used)
  std::uint32_t track_failures = 0;   // keyframes left at the odometry prior (< 10 inliers)
  double ba_s = 0, select_s = 0, total_s = 0;
  std::uint64_t selector_culled = 0;
  std::uint32_t selector_errors = 0;  // keepless status != ok (window kept whole)
  SelectorCounts selector;
  bool sim3 = false;                  // ATE after Sim(3) (monocular) rather than SE(3)
  double ate_m = 0, ate_r_deg = 0;
  double C = 0, F = 0, S = 0;    // ablation metrics (section IV-F)
  std::vector<Pose> estimate;    // every keyframe, as output (culled ones follow their parent)
  std::vector<SnapshotPoint> snapshot;
  WindowSizes window_sizes;  // SimOptions::measure_windows
};

RunResult run_slam(const Scenario& scenario, const VariantSpec& spec, const SimOptions& options);

}  // namespace keepless::eval
