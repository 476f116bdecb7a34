#pragma once
// Every capacity and parameter of the decision path, in one place. Storage is
// sized from Capacities once, at construction; nothing grows afterwards.

#include <cstddef>
#include <cstdint>

namespace keepless::core {

using KeyframeId = std::uint64_t;
using PointId = std::uint64_t;

struct Capacities {
  std::uint32_t max_keyframes = 32;        // window keyframes (K)
  std::uint32_t max_points = 16384;        // distinct point ids in the window
  std::uint32_t max_observations = 40000;  // (keyframe, point) observations
  std::uint32_t max_pair_arcs = 131072;    // point -> keyframe-pair arcs
  // Keyframe::unmapped keypoints held over the window (16 bytes each), for
  // CostModel::kAuthors; 0: keyframes carrying any are refused.
  std::uint32_t max_unmapped_keypoints = 0;
  // Observations of one keyframe; 0: max_observations. The per-keyframe
  // scratch (duplicate check, N(p, f)) is sized by it, not by the window's.
  std::uint32_t max_keyframe_observations = 0;
  // Hold Keyframe::quality (16 bytes per observation, max_observations of
  // them), for CostModel::kTrack; false: a keyframe's quality is not held
  // (the window's keyframes carry none, and kTrack ranks by the window).
  bool hold_quality = true;
};

// What one keyframe may carry: max_keyframe_observations, at most the
// window's max_observations.
inline std::uint32_t keyframe_observation_limit(const Capacities& c) {
  return c.max_keyframe_observations != 0 && c.max_keyframe_observations < c.max_observations
             ? c.max_keyframe_observations
             : c.max_observations;
}

// Bits of Params::cost_terms.
enum CostTerm : std::uint8_t { kConnectivityCost = 1, kSpatialCost = 2, kBaselineCost = 4 };

// Which points get a verdict. kWindow: every point seen by >= 2 window
// keyframes. kNewest: only the points the newest keyframe observes (the
// authors' ORB-SLAM2 integration, which decides the new keyframe's map
// points before each local BA); the others are skipped. The network is the
// whole window's either way (the newest keyframe's points compete for the
// pairs' M with every window point), so the scope is a pass over the exact
// optimum and run() and update() share it. A keyframe whose turn was missed
// (its call deferred or refused, or never made) is decided by the next call
// that decides (Sparsifier, Summary::caught_up). kAuto (beyond the paper):
// kNewest while the window's points come back to the camera, kWindow
// otherwise. Each call counts its evaluated points and those a window
// keyframe saw again after kReturnGap or more window keyframes without them;
// both counts go into sums that lose 1/2^kReturnDecayShift per call
// (integers), and the call decides as kNewest while the sums' share is at
// least kReturningForNewestPermille (Summary::returning_permille,
// Summary::decided_newest). Why: deciding the window re-decides about half
// of what it kept, and deferred culling deletes those points once they go
// unmatched; where they come back to the camera (a room) that costs
// accuracy, where few do (a road) re-deciding is the better
// (docs/evaluation/deferred-culling.md).
enum class Scope : std::uint8_t { kWindow, kNewest, kAuto };
inline constexpr std::uint32_t kReturnGap = 3;
inline constexpr std::uint32_t kReturnDecayShift = 4;
inline constexpr std::uint32_t kReturningForNewestPermille = 333;

// How the point -> pair costs (and the pair -> sink costs) are computed.
//   kPaper: section III-B as written (README, "The network").
//   kAuthors: the authors' code: N(p,f) counts every keypoint of f, mapped
//     or not (Keyframe::unmapped), in the 3x3 cells of ORB-SLAM2's 64x48
//     grid over the image around p's cell, p included; c_s = 2 * bin(N_j *
//     N_k) with bins < 100, < 500, < 1200, else (0..3); c_b = 10 * (10 -
//     floor(d / 10)) for d < 100 m, else 0. Their keep threshold, flow >
//     capacity / 2 in integers, is theta = 0.5 for integer flows.
//   kInformation: c_s is replaced by what the point's observations add to
//     the two poses' information: per observation the leverage tr(J L^-1 J^T)
//     of its 2x6 reprojection Jacobian J against the keyframe's information
//     L (the sum of J^T J over its observations with a depth), the first-order
//     log-det loss of dropping it, relative to the keyframe's mean (6 / n),
//     quantised to 0 (>= 4x the mean) .. 4 (< 0.5x); the arc costs the sum of
//     its two observations' levels. Observations without a depth, keyframes
//     without intrinsics, with fewer than 4 observations with a depth (every
//     leverage is then exactly the mean) or with a singular L, cost the
//     neutral level 2.
//   kTrack (beyond the paper): c_s is replaced by what the map knows about
//     the point beyond the window (Keyframe::quality, per observation): its
//     observations in the whole map, its age, its reprojection error and its
//     triangulation angle, each quantised to a level 0 (best) .. 4 and the
//     levels of Params::track_terms summed per observation; the arc costs
//     the sum of its two observations' sums. An unknown value (or a keyframe
//     without quality, Summary::track_fallback) costs the neutral level 2, so
//     the window's connectivity c_c alone ranks what the map did not say.
// c_c, the cost terms' mask and theta apply to every model.
enum class CostModel : std::uint8_t { kPaper, kAuthors, kInformation, kTrack };

// Bits of Params::track_terms: which of a point's qualities CostModel::kTrack
// sums (see PointQuality).
enum TrackTerm : std::uint8_t {
  kTrackLength = 1,
  kTrackAge = 2,
  kTrackError = 4,
  kTrackAngle = 8,
};

// --- Keep budgets ---------------------------------------------------------
// A budget states how much to keep instead of the pair capacity M. With the
// paper's capacities every evaluated point p has a keep threshold M*(p), the
// smallest M at which it is kept (Sparsifier, "Keep budgets"); a budget
// keeps the points with the smallest M*, ties to the smaller point id:
//   kPoints: exactly min(count, candidates) points;
//   kFraction: the share F (fraction, in [0, 1]) of the points evaluated,
//     over the sequence of one Sparsifier's decisions: K = (the candidates
//     it kept when they were last decided) + (floor(F x N + 0.5) minus that
//     of the decision before), N the points evaluated for the first time so
//     far (FractionBudget). A point stays in a sliding window for several
//     decisions; so the budget's points stay F of what it evaluated instead
//     of F^k after k decisions, also when points leave the window and come
//     back. A first decision keeps floor(F x candidates + 0.5);
//   kObservations: the longest prefix of that order whose window
//     observations (n per point) sum to at most `count`.
// Candidates are the evaluated points within Params::scope. The coverage
// floor's promotions come on top of the budget (Summary::floor_promoted).
// With a budget, M (Params::pair_capacity) is not used for selection.
// A track share S (kPoints and kFraction) takes floor(S x K + 0.5) of the K
// points by track length instead: the first K minus those by the order
// above, then the other candidates with the most window observations n,
// ties in that order (take_longest_tracks). The network's order spreads
// points evenly over the keyframe pairs; camera accuracy after BA follows
// long tracks more (docs/evaluation/budget-sweep.md, offline). With
// track_share_from > 0 or track_share_to < 1 the share applies only where
// the budget keeps a share of the candidates in [from, to] (kFraction: F,
// so the whole sequence alike; kPoints: K / candidates, per decision; never
// for the other kinds): on monocular KITTI a share helped from F = 0.3 and
// cost tracking at F = 0.2 (Use::kMonocular); with deferred culling it
// helped at F = 0.1 and cost local-BA time at 0.2 (Use::kMonocularDeferred).
enum class BudgetKind : std::uint8_t { kNone, kPoints, kFraction, kObservations };

struct KeepBudget {
  BudgetKind kind = BudgetKind::kNone;
  std::uint64_t count = 0;   // kPoints: K; kObservations: B
  double fraction = 0.0;     // kFraction: F
  double track_share = 0.0;  // S in [0, 1]; 0: every point by the network's order
  double track_share_from = 0.0;  // in [0, 1]; with track_share_to 1: S applies at every budget
  double track_share_to = 1.0;    // in [track_share_from, 1]
};

// "none", "points", "fraction", "observations".
const char* to_string(BudgetKind kind);
// A budget that keeps a number of points (kPoints, kFraction): what a track
// share, an exact count and a floor taken within it need.
constexpr bool keeps_a_count(BudgetKind kind) { return kind == BudgetKind::kPoints || kind == BudgetKind::kFraction; }
// A share at every budget (a caller's --track-share) needs a count; one
// bounded to a range of budgets (a use's) just never applies without one.
constexpr bool share_needs_a_count(const KeepBudget& b) {
  return b.track_share > 0.0 && b.track_share_from == 0.0 && b.track_share_to >= 1.0;
}
// A caller's share (--track-share S): S of the count at every budget, in
// place of a use's share and the budgets it applied at.
constexpr void share_at_every_budget(double share, KeepBudget* b) {
  b->track_share = share;
  b->track_share_from = 0.0;
  b->track_share_to = 1.0;
}
// --- end keep budgets -------------------------------------------------------

constexpr std::int32_t kMaxSpatialWeight = 1 << 16;

// The most window keyframes one point may be seen by (m, the largest n of
// the connectivity cost c_m(n), keepless/core/costs.hpp) while c_c is on:
// c_m(2) grows about as m^3/10 and at m = 2201 (1074123210) passes the
// solver's arc cost bound 2^30 (c_2200(2) = 1071887514 fits). A window with
// a point seen by more is refused, kCapacityExceeded, before any solve.
constexpr std::uint32_t kMaxPointViews = 2200;

// The paper's section III-B parameters, and the decision policies around them.
struct Params {
  std::int64_t pair_capacity = 100;  // M
  double theta = 0.5;                // keep iff flow > theta * n(n-1)/2
  std::int32_t box_width = 64;       // spatial-diversity box, pixels (closed, centred)
  std::int32_t box_height = 48;
  // Which costs the network uses (the paper's ablation); the default, all
  // three, is the paper's method. A term switched off costs 0 on its arcs.
  std::uint8_t cost_terms = kConnectivityCost | kSpatialCost | kBaselineCost;
  // Beyond the paper: the point -> pair cost (c_s, or the cost model's
  // replacement) is multiplied by it, 1 .. kMaxSpatialWeight. 1 is the
  // paper's; c_c otherwise outranks c_s (0 .. ~4): c_m(n) is 1 at n = m
  // (the most views of a window point) and grows to about m^3/10 at n = 2
  // (840 at m = 20; 2, 3, 4 .. for the longest tracks), so a pair prefers
  // the points with the most window views and c_s mostly breaks their ties. No weight tried beat 1 on both real
  // monocular sequences (docs/design/policies.md).
  std::int32_t spatial_weight = 1;
  Scope scope = Scope::kWindow;
  // Coverage floor L: after the solve, every window keyframe keeps at least L
  // of its evaluated points (those not culled: kept, or skipped by the scope),
  // or all of them; culled points are promoted back (Sparsifier::run). 0: off.
  std::uint32_t coverage_floor = 0;
  CostModel cost_model = CostModel::kPaper;
  // The image that CostModel::kAuthors lays its 64x48 grid over, pixels
  // [0, width) x [0, height) (ORB-SLAM2's mnMinX.. mnMaxX, undistorted).
  std::int32_t image_width = 640;
  std::int32_t image_height = 480;
  // Keep budget (see KeepBudget): when set, it replaces M in selection.
  KeepBudget budget{};
  // Tracking-safe culling: the maturity guard A. A point is first seen in
  // the oldest window keyframe that observes it (window order); points first
  // seen in the newest A keyframes are not decided yet (skipped,
  // Summary::guarded) and are decided once A newer keyframes follow that
  // one. With Scope::kNewest the decided keyframe is the one A slots before
  // the newest (none while the window holds A keyframes or fewer). 0: off.
  // (A keyframe's tracked flags, Keyframe::tracked, need no parameter.)
  std::uint32_t maturity_keyframes = 0;
  // With a keep budget: the points the newest keyframe flags tracked
  // (Keyframe::tracked) stay candidates and the budget keeps them first
  // (the network's order, a track share's swaps included, with the tracked
  // ahead), so they count toward it; Summary::tracked counts them. The kept
  // set is then not {M* <= Summary::budget_m}: budget_m and the flows follow
  // the network's order. false, or no budget: they are skipped (kept beside
  // a budget).
  bool tracked_first = false;
  // Deferred culling (DeferredCulls, keepless/core/deferred_culls.hpp): T.
  // A culled point is excluded from local BA at once and deleted only once
  // T keyframes in a row have not matched it (none of the newest T observes
  // it). 0: off, a culled point is deleted at once (the decisions and
  // everything else unchanged). Read by the callers that hold the culls (the
  // node, the adapter's users), not by the Sparsifier.
  std::uint32_t defer_keyframes = 0;
  // The qualities CostModel::kTrack sums (TrackTerm bits; 0: every arc
  // costs the same c_s, only c_c ranks).
  std::uint8_t track_terms = kTrackLength | kTrackAge | kTrackError | kTrackAngle;
};

// The options' names as command lines spell them: "window", "newest", "auto";
// "paper", "authors", "information", "track". parse_* return false (and leave *out
// alone) for any other text.
const char* to_string(Scope scope);
const char* to_string(CostModel model);
[[nodiscard]] bool parse_scope(const char* text, Scope* out);
[[nodiscard]] bool parse_cost_model(const char* text, CostModel* out);
// Params::track_terms from a comma-separated list of "length", "age",
// "error", "angle" (each at most once); false (and *out unchanged) for
// anything else, an empty list included.
[[nodiscard]] bool parse_track_terms(const char* text, std::uint8_t* out);
// Params::cost_terms from a comma-separated list of "c_c", "c_s", "c_b", the
// same way.
[[nodiscard]] bool parse_cost_terms(const char* text, std::uint8_t* out);

}  // namespace keepless::core
