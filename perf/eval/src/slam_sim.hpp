#pragma once
// The closed-loop keyframe SLAM back end every variant runs on the same
// scenario: map-point creation (stereo at once, monocular by triangulation on
// the second view), ORB-SLAM2's recent-point culling, point selection before
// every local BA (none / keepless / ANMS / random), the local BA over the
// last W keyframes with the other observers fixed, outlier rejection, and
// ORB-SLAM2's keyframe culling (>= 90 % of a keyframe's points seen by >= 3
// other keyframes), so KF % is measured, not assumed.

#include <cstdint>
#include <string>
#include <vector>

#include "geometry.hpp"
#include "scenario.hpp"

namespace keepless::eval {

enum class Selector { kNone, kKeepless, kAnms, kRandom };
const char* to_string(Selector s);

struct VariantSpec {
  std::string name;  // original, ours, anms, random, c_c, c_c+c_s, c_c+c_b
  Selector selector = Selector::kNone;
  std::int64_t M = 100;          // keepless pair capacity; for anms/random: the M whose count they match
  std::uint8_t cost_terms = 7;   // bit 0 c_c, bit 1 c_s, bit 2 c_b
};

struct SimOptions {
  int window = 10;          // local BA keyframes
  int ba_iterations = 10;
  std::uint64_t seed = 1;
  int snapshot_frame = -1;  // keyframe whose keypoints are recorded (SVG)
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
  double ba_s = 0, select_s = 0, total_s = 0;
  std::uint64_t selector_culled = 0;
  std::uint32_t selector_errors = 0;  // keepless status != ok (window kept whole)
  double ate_m = 0, ate_r_deg = 0;
  double C = 0, F = 0, S = 0;    // ablation metrics (section IV-F)
  std::vector<Pose> estimate;    // every keyframe, last estimate
  std::vector<SnapshotPoint> snapshot;
};

RunResult run_slam(const Scenario& scenario, const VariantSpec& spec, const SimOptions& options);

}  // namespace keepless::eval
