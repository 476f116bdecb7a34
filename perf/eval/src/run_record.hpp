#pragma once
// The evaluation's contract, in one place for every evaluation path (the
// synthetic world, real VO on images or RGB-D, BAL): a RunRecord per run
// (input, variant, seed), a Comparison per input and operating point holding
// the records of the original and of every variant compared at the same kept
// count, summarize() turning a Comparison into the contract's statistics
// (mean ± sd over seeds, better / worse seeds, sqrt(observation ratio), the
// error floor), and the JSON line users' scripts read:
//   {"runs": [{"input", "kind", "seeds", "M", "mp_percent", "kf_percent",
//              "ba_time_percent", "ate_original_m", "ate_ours_m", "ate_ours_sd_m",
//              "ate_random_m", "ate_longest_track_m", "ate_anms_m", "better_seeds",
//              "worse_seeds", "sqrt_obs_ratio", ...}, ...], ...}
// plus "failed_seeds" {"original", "ours", "random", "longest_track", "anms"}
// (runs that lost tracking or whose BA diverged), "ratio_seeds" (the seeds on
// which the original did not fail: every comparison with the original, the
// percentages, "ate_ratio*", "sqrt_obs_ratio*", "better_seeds", "worse_seeds",
// uses only those), "frames" and
// "frames_tracked" (0 where not a real VO), and, for the real VO (kind
// images / rgbd), "frames_tracked_VARIANT".

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "keepless/core/decision.hpp"

namespace keepless::eval {

// The selector's windows and, summed over them, core::Summary's coverage
// floor counts: keyframes where the floor bound, points it promoted,
// keyframes below it with all their points kept; and Scope::kAuto's
// decisions of the new keyframe's points and its switches between the two
// scopes (how often it flickers). For a baseline they describe the keepless
// run that set its count on its own window.
struct SelectorCounts {
  std::uint64_t windows = 0, floor_keyframes = 0, floor_promoted = 0, floor_short = 0;
  std::uint64_t decided_newest = 0, scope_switches = 0;
  bool last_newest = false;
  void add(const core::Summary& s) {
    ++windows;
    floor_keyframes += s.floor_keyframes;
    floor_promoted += s.floor_promoted;
    floor_short += s.floor_short;
    decided_newest += s.decided_newest;
    scope_switches += s.decided_newest != last_newest;
    last_newest = s.decided_newest;
  }
};

// One run of one variant on one input with one seed.
struct RunRecord {
  std::string variant;            // original, ours, random, longest_track, anms, or an ablation's name
  std::uint64_t seed = 0;
  std::int64_t M = 0;             // 0 for the original
  std::uint64_t mps = 0;          // map points at the end
  std::uint64_t kfs = 0;          // keyframes at the end
  std::uint64_t observations = 0; // residuals over every (local) BA: the information used
  double ba_s = 0, total_s = 0;
  double ate_m = NAN, ate_r_deg = NAN;
  double C = NAN, F = NAN, S = NAN;  // section IV-F: observations per point, keyframe span, grid occupancy %
  int frames = 0, frames_tracked = 0;  // real VO (kind images / rgbd): frames given and tracked; 0 elsewhere
  SelectorCounts selector;
  double ba_cpu_s = NAN;  // local BAs' thread CPU time (real VO), unmoved by the machine's load
  double refine_cpu_s = NAN;  // deferred culling: the excluded points' refinement after local BA (real VO)
  bool diverged = false;  // a BA that did not converge (BAL)
  // A failure: tracking lost (frames tracked < frames) or a BA diverged.
  // Its ATE still counts every frame (untracked ones at the last tracked pose).
  bool failed() const { return (frames > 0 && frames_tracked < frames) || diverged; }
};

struct InputInfo {
  std::string input;  // file or directory
  std::string name;   // short label
  std::string group;  // tum, euroc_mh, euroc_v, kitti, kitti_images, bal, ...
  std::string kind;   // trajectory | images | rgbd | bal
  bool sim3 = false;  // ATE after Sim(3) alignment (monocular) instead of SE(3)
  double error_floor_m = 0;  // 0: none
};

// One input at one operating point. Every vector holds one record per seed,
// in the same seed order; a baseline not run is empty.
struct Comparison {
  InputInfo info;
  std::string variant = "ours";   // the compared variant's name
  double target_fraction = NAN;   // --kept-fraction, or NaN for a given M
  std::int64_t M = 0;
  std::vector<RunRecord> original, ours, random, longest_track, anms;
  std::vector<RunRecord> ablation;  // the cost ablation's variants (by name), every seed; ours is "all"
};

struct Stat {
  double mean = NAN, sd = NAN;  // sd: sample standard deviation (0 for one value)
  int n = 0;
  double se() const { return n > 0 ? sd / std::sqrt(double(n)) : NAN; }  // standard error of the mean
};
Stat stat_of(const std::vector<double>& v);

// The contract's object for one Comparison.
struct ContractRun {
  InputInfo info;
  std::string variant;
  int seeds = 0;
  std::int64_t M = 0;
  double target_fraction = NAN;
  Stat mp_percent, kf_percent, ba_time_percent;
  Stat ate_original, ate_ours, ate_random, ate_longest_track, ate_anms;  // metres (BAL: its units)
  Stat ate_r_original, ate_r_ours;
  Stat mp_percent_random, mp_percent_longest_track, mp_percent_anms;
  Stat kf_percent_random, kf_percent_longest_track, kf_percent_anms;
  // Every figure against the original (percentages, ratios, better / worse) is over the
  // ratio_seeds seeds on which the original did not fail.
  int ratio_seeds = 0;
  int better_seeds = 0, worse_seeds = 0;  // ours vs original, seed by seed
  double ate_ratio = NAN;        // mean ours / mean original
  double ate_ratio_random = NAN, ate_ratio_longest_track = NAN, ate_ratio_anms = NAN;
  int below_random_seeds = 0, below_longest_track_seeds = 0, below_anms_seeds = 0;  // every seed
  // Ours' ATE minus the baseline's, seed by seed (every seed): the paired difference whose
  // mean and standard error say whether "below" is beyond the seeds' spread.
  Stat ate_diff_random, ate_diff_longest_track, ate_diff_anms;
  double sqrt_obs_ratio = NAN;   // sqrt(mean observations original / ours)
  double sqrt_obs_ratio_random = NAN, sqrt_obs_ratio_longest_track = NAN, sqrt_obs_ratio_anms = NAN;
  double ate_ratio_floored = NAN;  // with error_floor_m added in quadrature to both
  Stat floor_keyframes, floor_promoted, floor_short;  // ours, per run (summed over its windows)
  double windows = NAN;                                // ours, mean selector windows per run
  // Failed runs (RunRecord::failed) per method; every mean above includes them.
  struct Failed {
    int original = 0, ours = 0, random = 0, longest_track = 0, anms = 0;
    int total() const { return original + ours + random + longest_track + anms; }
  } failed;
  // Real VO only (frames > 0): frames given, mean frames tracked per variant.
  int frames = 0;
  Stat frames_tracked, frames_tracked_original, frames_tracked_random, frames_tracked_longest_track,
      frames_tracked_anms;
};

ContractRun summarize(const Comparison& c);

// One run's JSON object; the full line is {"runs":[...]<extra>} where
// `extra` is ",\"key\":value..." (may be empty).
std::string run_json(const ContractRun& r);
std::string contract_json(const std::vector<ContractRun>& runs, const std::string& extra);

// JSON helpers shared by the writers.
std::string json_number(double v, int precision = 6);
std::string json_string(const std::string& s);

}  // namespace keepless::eval
