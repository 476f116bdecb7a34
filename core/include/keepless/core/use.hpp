#pragma once
// Settings per use, chosen from the budget sweep on real sequences
// (docs/evaluation/budget-sweep.md#which-settings-per-use). A use sets the
// decision policy only: the scope, the maturity guard, deferred culling and
// the track share with the budget it starts from. M, theta, the costs and
// the budget's kind and count stay the caller's, so they refine it.

#include <cstdint>

#include "keepless/core/config.hpp"

namespace keepless::core {

enum class Use : std::uint8_t {
  // The paper's method: Params' defaults (Scope::kWindow, no guard, culls
  // deleted at once, the network's order for a whole count).
  kPaper,
  // A monocular VO that deletes what it culls: decide the newest keyframe's
  // points once two newer keyframes follow it (Scope::kNewest, maturity 2),
  // and from F = 0.3 take half the count by track length (track share 0.5
  // from 0.3). The only immediate setting that tracked every seed of both
  // KITTI sequences at F = 0.2; random, ANMS and longest-track-first under
  // the same guard did not. The share lowered the ATE at F = 0.3-0.4 and
  // lost tracking at F = 0.2, hence from 0.3. (The figures: the page above.)
  kMonocular,
  // A monocular VO that implements both verdicts (decision_t's excluded and
  // deleted lists) and keeps excluded points' structure refined: culls
  // deleted once 2 keyframes in a row miss them, the window decided, or the
  // new keyframe's points while a third of the window's come back
  // (Scope::kAuto), and up to F = 0.15 half the count by track length
  // (track share 0.5 to 0.15). It tracked every seed at F = 0.1 and 0.2,
  // where the monocular use did not; the auto scope changed 1 of 80 KITTI
  // runs and brought 7-Scenes' colour frames from 1.28x / 1.16x the
  // original's ATE to 1.09x / 1.01x. The share lowered the ATE at F = 0.1
  // on both KITTI sequences and at 5 Hz on 7-Scenes, was lower or level on
  // all four at 0.15, and at 0.2 took local BA past half the original's time
  // for little or no gain, hence to 0.15.
  kMonocularDeferred,
  // RGB-D: the monocular use's scope and guard, for accuracy rather than
  // tracking (depth makes new points usable at once; every selector
  // tracked down to F = 0.1). On 7-Scenes at F = 0.2-0.4 it was below the
  // paper's settings and level with the simple rules, at a larger local BA.
  // No track share: it cost accuracy at F = 0.3-0.4 there.
  kRgbd,
  // A finished model, with a point count: the count by track length, the
  // network's order breaking ties. keepless_sparsify, ranking by COLMAP's
  // track length with a per-image floor 10 % above the filter's poorest
  // image, was within 1.2x of COLMAP's point_filtering at its count in 15 of
  // 15 cells (half by the order: 14; ranked by images: 12).
  kOffline,
};

// Sets scope, maturity_keyframes, defer_keyframes and budget.track_share,
// track_share_from and track_share_to to the use's values; every other
// field of *params is left as it was.
void apply_use(Use use, Params* params);

// "paper", "monocular", "monocular-deferred", "rgbd", "offline"; parse_use
// returns false (and leaves *out alone) for any other text, which an error
// message answers with kUseNames.
inline constexpr const char* kUseNames = "paper, monocular, monocular-deferred, rgbd or offline";
const char* to_string(Use use);
bool parse_use(const char* text, Use* out);

}  // namespace keepless::core
