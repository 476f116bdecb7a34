#pragma once
// A compact ORB-SLAM2-style visual odometry on real images (RGB-D or
// monocular), with a point selector deciding, through keepless::opencv,
// which of the new keyframe's map points survive before every local BA.

#include <cstdint>
#include <string>
#include <vector>

#include "geometry.hpp"
#include "keepless/core/config.hpp"
#include "real_sequence.hpp"
#include "run_record.hpp"
#include "window_sizes.hpp"

namespace keepless::eval::vo {

// What decides before each local BA. kOriginal: nothing (ORB-SLAM2's own
// culling only). The baselines cull exactly as many of the new keyframe's
// evaluated points as keepless culls on the same window; with a kept
// fraction (params.budget) every selector keeps the count core::FractionBudget
// gives on its own map: F of the points new to it plus those it kept before.
enum class Selector : std::uint8_t { kOriginal, kKeepless, kRandom, kLongestTrack, kAnms };

// What the ANMS baseline ranks by, to tell its two ingredients apart: kSsc,
// SSC on the keypoints' responses (strong corners, spread); kSpread, SSC on
// a seeded random priority (spread alone); kResponse, the strongest
// responses without suppression (strength alone); kTrack, SSC on the map's
// track length, ties by that priority (spread with long tracks).
enum class AnmsVariant : std::uint8_t { kSsc, kSpread, kResponse, kTrack };
enum class KeyframeCulling : std::uint8_t { kOn, kOff, kCountCulled };
const char* to_string(Selector s);

struct RealVoOptions {
  int features = 0;  // ORB features per frame; 0: ORB-SLAM2's 1000 (RGB-D) or 2000 (monocular KITTI)
  std::uint64_t seed = 1;  // RANSAC sampling order and the random baseline's priorities
  Selector selector = Selector::kOriginal;
  AnmsVariant anms_variant = AnmsVariant::kSsc;
  // keepless (M = params.pair_capacity; scope, coverage_floor, cost_model as
  // the eval's --scope/--floor/--cost). image_width/height are the camera's.
  core::Params params;
  // Send the new keyframe's tracked flags (core::Keyframe::tracked: the map
  // points the tracker matched in that frame) with its window.
  bool tracked_flags = false;
  // A keyframe also when a tracked frame keeps fewer than this many pose
  // inliers (0: off; ORB-SLAM3 uses 75 for monocular-inertial input).
  // ORB-SLAM2's monocular test compares the inliers with the reference
  // keyframe's points seen 3+ times only, which a sparse map makes few, so
  // at a tight budget it can fire too late to keep tracking.
  int weak_keyframe = 0;
  // ORB-SLAM2's monocular keyframe test: a keyframe when a frame's inliers
  // fall below this share of the reference keyframe's points seen 3+ times.
  // Lower makes fewer keyframes (RGB-D input uses 0.75 whatever this says).
  double keyframe_ratio = 0.9;
  // Deferred culling (params.defer_keyframes > 0): excluded points enter local
  // BA as constant landmarks seen by the local keyframes, instead of not at all.
  bool defer_fixed = false;
  // Deferred culling: after the DLT, each excluded point's structure is
  // refined with the poses held (robust, as local BA would) and its outlier
  // observations are erased, instead of the DLT alone.
  bool defer_refine = false;
  // Deferred culling: after that, each local keyframe's pose is refined
  // (motion-only) against every point it observes, excluded ones included,
  // and the excluded points are re-triangulated again: one round of
  // resection-intersection over what local BA left out.
  bool defer_alternate = false;
  // Which points every selector decides at a keyframe: false, the new
  // keyframe's (the authors' integration; with params.maturity_keyframes the
  // keyframe that just matured); true, every evaluated point of the local
  // window (with params.scope kWindow), so a point kept before can be culled
  // later and a kept fraction is F of the points new to each window plus
  // those kept before among all of the window's.
  bool decide_window = false;
  // keepless sees each point under a bijective hash of its map index instead
  // of the index itself, so its ties (equal arc costs in a pair, equal M* at
  // a budget's cut; both to the smaller id) fall in an order unrelated to the
  // points' age (map indices grow as points are made).
  bool hashed_ids = false;
  // Keyframe culling (ORB-SLAM's: a keyframe 90 % of whose points three others
  // see is deleted). kOff: never; culled points make keyframes look redundant.
  // kCountCulled: the test also counts each point the selector deleted, with
  // the observations it had then, so culling points does not cull keyframes.
  KeyframeCulling keyframe_culling = KeyframeCulling::kOn;
  int max_local_keyframes = 20;      // local BA / keepless window: the new keyframe and its best covisibles
  bool measure_windows = false;  // fill RealRunResult::window_sizes (window_sizes.hpp)
  // With measure_windows: replay the K = 20 windows at these capacities
  // (max_keyframes 0: no replay).
  core::Capacities replay_capacities{0, 0, 0, 0, 0};
  bool verbose = false;
};

struct KeypointMark {
  float u = 0, v = 0;
  std::uint8_t state = 0;  // 0 unmapped, 1 kept, 2 culled
};

struct RealRunResult {
  std::string error;  // non-empty: the run did not happen (unreadable input)
  int frames = 0;
  int frames_tracked = 0;
  int tracking_losses = 0;  // tracked -> lost transitions
  int map_points = 0;       // alive at the end
  int keyframes = 0;        // alive at the end
  int keyframes_created = 0;
  std::int64_t observations = 0;  // of the alive points at the end
  std::int64_t points_culled_by_selector = 0;
  std::int64_t points_culled_elsewhere = 0;  // of those, points the decided keyframe does not observe (decide_window)
  std::int64_t points_deleted_deferred = 0;  // params.defer_keyframes: excluded points the rule deleted
  // Excluded points deleted before, or still held after, T keyframes in a row
  // that did not match them, by the VO's own record (0: the rule held).
  std::int64_t defer_rule_violations = 0;
  std::int64_t excluded_matches = 0;  // inlier matches of excluded points in tracked frames, summed over frames
  int local_bas = 0;
  int window_rejections = 0;  // windows the adapter or Sparsifier refused (nothing culled there)
  SelectorCounts selector;  // windows the selector decided, its Sparsifier's floor counts over them
  double local_ba_seconds = 0, selector_seconds = 0, total_seconds = 0;
  std::int64_t local_ba_observations = 0;  // residuals over every local BA
  double local_ba_cpu_seconds = 0;          // the local BAs' thread CPU time
  // Deferred culling: the thread CPU time of re-triangulating (and with
  // defer_refine refining) the excluded points after each local BA, which
  // local_ba_cpu_seconds does not count.
  double refine_cpu_seconds = 0;
  // The local BAs' point blocks (excluded points aside), summed over every
  // local BA, with their map track lengths and triangulation angles (degrees).
  std::int64_t ba_points = 0;
  double ba_point_track_sum = 0, ba_point_angle_sum = 0;
  // RMS over every frame from the first tracked one, an untracked frame at
  // the last tracked pose; SE(3) for RGB-D, Sim(3) monocular.
  double ate_m = 0, ate_r_deg = 0;
  double mean_kept_fraction = 1;    // of the new keyframes' evaluated points (>= 2 views in the window), over windows
  // With a kept fraction: the points the selector evaluated (first time),
  // so 1 - points_culled_by_selector / points_evaluated is the share of
  // them the map holds (core::FractionBudget aims it at F).
  std::int64_t points_evaluated = 0;
  std::vector<Pose> estimate, ground_truth;       // tracked frames, aligned estimate
  std::vector<KeypointMark> marks;                // one keyframe's keypoints (the window with most culls)
  int marked_frame = -1;
  WindowSizes window_sizes;  // RealVoOptions::measure_windows
};

RealRunResult run_real_vo(const RealSequence& sequence, const RealVoOptions& options);

}  // namespace keepless::eval::vo
