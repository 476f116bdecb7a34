#pragma once
// keepless_eval's real-VO inputs (--images with --calib/--poses, --rgbd):
// per seed the original, then per operating point keepless and the
// equal-count baselines, each run a RunRecord in issue 11's Comparison, so
// the same summarize / tables / JSON serve every kind of input.

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "keepless/core/config.hpp"
#include "real_sequence.hpp"
#include "real_vo.hpp"
#include "run_record.hpp"
#include "window_sizes.hpp"

namespace keepless::eval::vo {

// What a sequence folder holds and how the VO runs on it.
enum class VoLayout {
  kKittiImages,  // --images: KITTI greyscale frames, monocular (needs calib and poses)
  kRgbd,         // --rgbd: a 7-Scenes sequence, colour and depth
  kColourOnly,   // --rgb: a 7-Scenes sequence's colour frames alone, monocular
};

struct VoInput {
  VoLayout layout = VoLayout::kKittiImages;
  std::string dir, calib, poses;  // calib, poses: kKittiImages only
};

struct VoEvalOptions {
  FrameSelection frames;                            // --frames A:B[:S]; max_frames: --quick without --frames
  std::vector<std::uint64_t> seeds;                 // RANSAC order and the random baseline's priorities
  std::vector<std::pair<double, std::int64_t>> ops;  // (kept fraction, NaN for a given M; M)
  // The baselines that run beside keepless (--vo-baselines; empty with --no-baselines).
  std::vector<Selector> baselines = {Selector::kRandom, Selector::kLongestTrack, Selector::kAnms};
  // --scope, --floor, --cost: only scope, coverage_floor and cost_model are
  // read. A kept fraction runs keepless with that keep budget over the new
  // keyframe's points (scope newest: the points the VO culls), or with
  // decide_window over the window's (scope window).
  core::Params policy;  // and maturity_keyframes, defer_keyframes
  bool tracked_flags = false;  // RealVoOptions::tracked_flags
  int weak_keyframe = 0;       // RealVoOptions::weak_keyframe
  double keyframe_ratio = 0.9; // RealVoOptions::keyframe_ratio
  AnmsVariant anms_variant = AnmsVariant::kSsc;  // RealVoOptions::anms_variant
  bool defer_fixed = false;    // RealVoOptions::defer_fixed
  bool defer_refine = false;   // RealVoOptions::defer_refine
  bool defer_alternate = false;  // RealVoOptions::defer_alternate
  bool decide_window = false;  // RealVoOptions::decide_window (keepless with scope window)
  bool hashed_ids = false;     // RealVoOptions::hashed_ids
  KeyframeCulling keyframe_culling = KeyframeCulling::kOn;  // RealVoOptions::keyframe_culling
  std::string out;  // non-empty: NAME_trajectory.svg and NAME_keypoints.svg there
};

// Appends one Comparison per operating point; false with `error` on
// unreadable input.
[[nodiscard]] bool evaluate_real_vo(const VoInput& input, const VoEvalOptions& options,
                                    std::vector<Comparison>* out, std::string* error);

// The original run of one seed with its windows measured (window_sizes.hpp);
// `name` gets the sequence's name. False with `error` on unreadable input.
// `replay`: RealVoOptions::replay_capacities.
[[nodiscard]] bool measure_real_windows(const VoInput& input, const FrameSelection& frames, std::uint64_t seed,
                                        const core::Capacities& replay, std::string* name, WindowSizes* sizes,
                                        std::string* error);

}  // namespace keepless::eval::vo
