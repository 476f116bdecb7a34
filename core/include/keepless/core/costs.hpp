#pragma once
// The three costs of the paper's section III-B, in exact integer arithmetic
// where the paper's formula allows it, and with -ffp-contract=off IEEE double
// where it does not (the baseline), so x86-64 and aarch64 agree bit for bit.

#include <cstdint>

#include "keepless/core/window.hpp"

namespace keepless::core {

// c_m(n) for n = 2..m: c_m(m) = 1, c_m(n) = ceil((n+1)/(n-1) * c_m(n+1)).
// Writes table[n] for 2 <= n <= m (table must hold m+1 entries).
void connectivity_costs(std::uint32_t m, std::int64_t* table);

// floor(log10(a*b + 1)) for keypoint counts a, b.
std::int64_t spatial_cost(std::uint64_t a, std::uint64_t b);

// ceil(10 / (0.1*d + 1)), d = |c_j - c_k| in metres.
std::int64_t baseline_cost(const double centre_j[3], const double centre_k[3]);

// The closed box test |du| <= half_w and |dv| <= half_h of the paper's
// 64x48 box, for a box of width w and height h (half = w/2, h/2).
bool in_box(double du, double dv, std::int32_t box_width, std::int32_t box_height);

// CostModel::kAuthors (their MatchCuller): 2 * bin(a*b), bins < 100, < 500,
// < 1200, else (0, 1, 2, 3).
std::int64_t authors_spatial_cost(std::uint64_t a, std::uint64_t b);

// CostModel::kAuthors: 10 * (10 - floor(d / 10)) for d < 100 m, else 0
// (their code leaves d >= 200 m undefined; 0 here).
std::int64_t authors_baseline_cost(const double centre_j[3], const double centre_k[3]);

// ORB-SLAM2's grid: kGridColumns x kGridRows cells over [0, width) x
// [0, height); a keypoint's cell is round(u * (columns / width)),
// round(v * (rows / height)) (half away from zero), and it is in the grid
// iff both lie in range.
constexpr std::int32_t kGridColumns = 64;
constexpr std::int32_t kGridRows = 48;

// CostModel::kAuthors' N(p, f) for every observation of a keyframe: the
// keypoints in the grid (observations and kf.unmapped, the observation
// itself included) whose cells lie in the 3x3 cells around the
// observation's, clamped to the grid. `cells` is scratch of
// kGridColumns * kGridRows entries. width, height > 0.
void grid_neighbours(const Keyframe& kf, const Observation* observations, std::uint32_t count,
                     std::int32_t width, std::int32_t height, std::uint32_t* cells,
                     std::uint32_t* out);

// CostModel::kInformation's level (0 .. kInformationLevels - 1, lower = more
// informative) of every observation of a keyframe; see CostModel. Plain
// IEEE arithmetic (+ - * / sqrt, frexp), no libm transcendental, so the
// levels are the same on every architecture built with -ffp-contract=off.
constexpr std::uint32_t kInformationLevels = 5;
constexpr std::uint32_t kNeutralInformationLevel = 2;
void information_levels(const Keyframe& kf, const Observation* observations, std::uint32_t count,
                        std::uint32_t* out);

// CostModel::kTrack's level of every observation of a keyframe: the sum over
// the qualities in `terms` (TrackTerm bits) of each one's level, 0 (best) ..
// 4, from kf.quality (absent, or a value unknown: the neutral 2):
//   track length T: 4 - min(4, floor(log2 T))  (1: 4, 2-3: 3, .. >= 16: 0);
//   age a: 4 - min(4, floor(log2(a + 1)))       (0: 4, 1-2: 3, .. >= 15: 0);
//   reprojection error e: < 0.5 px 0, < 1 1, < 2 2, < 4 3, else 4;
//   triangulation angle: >= 8 deg 0, >= 4 1, >= 2 2, >= 1 3, else 4.
// Integer shifts and comparisons with constants only: exact everywhere.
constexpr std::uint32_t kNeutralTrackLevel = 2;
void track_levels(const Keyframe& kf, std::uint32_t count, std::uint8_t terms,
                  std::uint32_t* out);

}  // namespace keepless::core
