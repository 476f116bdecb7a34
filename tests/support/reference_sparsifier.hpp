#pragma once
// A naive, independent implementation of the paper's section III-B, written
// straight from the formulas for tests: std::map/std::vector, all-pairs box
// counting, its own cost code (nothing from core/src). It solves the network
// by its per-pair closed form: the source arcs never bind (capacity n(n-1)/2 =
// the point's out-degree), so each pair (f_j, f_k) independently carries
// min(M, shared points) units on its cheapest points by c_c + c_s, ties to the
// smaller point id. The cost models beside the paper's (core::CostModel) are
// written here from their definitions too: the authors' grid N(p,f) by
// comparing every keypoint's cell, their binned c_s and c_b by table, and
// the information levels from the explicit 3D point, a 2x3 projection
// Jacobian times [I | -[X]x], and the information matrix inverted by
// Gauss-Jordan elimination.
//
// Slow (quadratic box counting) and allocating: use it on small windows only.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "keepless/core/config.hpp"
#include "keepless/core/decision.hpp"
#include "keepless/core/window.hpp"

namespace keepless::test {

struct RefObservation {
  std::uint64_t point = 0;
  double u = 0;
  double v = 0;
  double depth = 0;  // <= 0: unknown
};

struct RefKeyframe {
  std::uint64_t id = 0;
  double centre[3] = {0, 0, 0};
  std::vector<RefObservation> observations;
  double fx = 0, fy = 0, cx = 0, cy = 0;  // fx = 0: unknown
  std::vector<std::pair<double, double>> unmapped;  // (u, v)
  std::vector<std::uint8_t> tracked;  // empty, or one flag per observation (core::Keyframe::tracked)
  std::vector<core::PointQuality> quality;  // empty, or one per observation (core::Keyframe::quality)
};

struct RefPoint {
  std::uint64_t id = 0;
  std::uint32_t views = 0;     // n
  std::int64_t capacity = 0;   // n(n-1)/2, 0 when skipped
  std::int64_t flow = 0;       // units through source -> point
  core::Verdict verdict = core::Verdict::kSkip;
};

struct RefResult {
  std::vector<RefPoint> points;  // every distinct point, ascending id
  std::uint32_t evaluated = 0;
  std::uint32_t pairs = 0;       // frame pairs sharing >= 1 evaluated point
  std::uint32_t pair_arcs = 0;   // point -> pair arcs
  std::int64_t max_flow = 0;
  std::int64_t total_cost = 0;   // sum of c_c + c_s + c_b over the units carried
  // The decision policies (reference_policies.hpp).
  std::uint32_t out_of_scope = 0;
  std::uint32_t floor_keyframes = 0;
  std::uint32_t floor_promoted = 0;
  std::uint32_t floor_short = 0;
  std::uint32_t guarded = 0;
  std::uint32_t tracked = 0;
};

// c_m(n): c_m(m) = 1, c_m(n) = ceil((n+1)/(n-1) * c_m(n+1)), recursively.
inline std::int64_t ref_connectivity_cost(std::int64_t n, std::int64_t m) {
  if (n >= m) return 1;
  const std::int64_t numerator = (n + 1) * ref_connectivity_cost(n + 1, m);
  const std::int64_t denominator = n - 1;
  return numerator / denominator + (numerator % denominator != 0 ? 1 : 0);
}

// floor(log10(x + 1)) for x = a*b: the number of decimal digits of x + 1, minus one.
inline std::int64_t ref_spatial_cost(std::uint64_t a, std::uint64_t b) {
  return static_cast<std::int64_t>(std::to_string(a * b + 1).size()) - 1;
}

// ceil(10 / (0.1 d + 1)), d the Euclidean distance of the camera centres.
inline std::int64_t ref_baseline_cost(const double* a, const double* b) {
  const double dx = a[0] - b[0];
  const double dy = a[1] - b[1];
  const double dz = a[2] - b[2];
  const double d = std::sqrt(dx * dx + dy * dy + dz * dz);
  return static_cast<std::int64_t>(std::ceil(10.0 / (0.1 * d + 1.0)));
}

// The other keypoints of `frame` inside the closed box centred on observation
// `self` (|du| <= width/2, |dv| <= height/2), by looking at every keypoint.
inline std::uint64_t ref_nearby(const RefKeyframe& frame, std::size_t self,
                                const core::Params& params) {
  const RefObservation& o = frame.observations[self];
  std::uint64_t n = 0;
  for (std::size_t i = 0; i < frame.observations.size(); ++i) {
    if (i == self) continue;
    const double du = frame.observations[i].u - o.u;
    const double dv = frame.observations[i].v - o.v;
    if (std::fabs(du) <= params.box_width / 2.0 && std::fabs(dv) <= params.box_height / 2.0) ++n;
  }
  return n;
}

// --- the authors' cost model (their MatchCuller and KeyFrame::GetNeighborInGrid)

inline std::int64_t ref_authors_spatial_cost(std::uint64_t a, std::uint64_t b) {
  const std::uint64_t bounds[] = {100, 500, 1200};
  std::int64_t bin = 3;
  for (int i = 2; i >= 0; --i) {
    if (a * b < bounds[i]) bin = i;
  }
  return bin * 2;
}

inline std::int64_t ref_authors_baseline_cost(const double* a, const double* b) {
  const double d = std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                             (a[2] - b[2]) * (a[2] - b[2]));
  const std::int64_t table[] = {10, 9, 8, 7, 6, 5, 4, 3, 2, 1};
  for (int i = 0; i < 10; ++i) {
    if (d < 10.0 * (i + 1)) return table[i] * 10;
  }
  return 0;
}

// Keypoints (mapped and unmapped) in the 3x3 grid cells around observation
// `self`'s cell: every keypoint's cell compared with it.
inline std::uint64_t ref_grid_neighbours(const RefKeyframe& frame, std::size_t self,
                                         const core::Params& params) {
  const double per_u = 64.0 / params.image_width, per_v = 48.0 / params.image_height;
  const double su = std::round(frame.observations[self].u * per_u);
  const double sv = std::round(frame.observations[self].v * per_v);
  std::uint64_t n = 0;
  const auto consider = [&](double u, double v) {
    const double cu = std::round(u * per_u), cv = std::round(v * per_v);
    const bool in_grid = cu >= 0 && cu <= 63 && cv >= 0 && cv <= 47;
    if (in_grid && std::fabs(cu - su) <= 1 && std::fabs(cv - sv) <= 1) ++n;
  };
  for (const auto& o : frame.observations) consider(o.u, o.v);
  for (const auto& k : frame.unmapped) consider(k.first, k.second);
  return n;
}

// --- the information cost model

// 6x6 Gauss-Jordan inverse with partial pivoting; false if singular.
inline bool ref_invert6(std::vector<std::vector<double>> a, std::vector<std::vector<double>>& inv) {
  inv.assign(6, std::vector<double>(6, 0.0));
  for (int i = 0; i < 6; ++i) inv[i][i] = 1.0;
  for (int c = 0; c < 6; ++c) {
    int pivot = c;
    for (int r = c + 1; r < 6; ++r) {
      if (std::fabs(a[r][c]) > std::fabs(a[pivot][c])) pivot = r;
    }
    if (a[pivot][c] == 0.0) return false;
    std::swap(a[c], a[pivot]);
    std::swap(inv[c], inv[pivot]);
    const double p = a[c][c];
    for (int k = 0; k < 6; ++k) {
      a[c][k] /= p;
      inv[c][k] /= p;
    }
    for (int r = 0; r < 6; ++r) {
      if (r == c) continue;
      const double f = a[r][c];
      for (int k = 0; k < 6; ++k) {
        a[r][k] -= f * a[c][k];
        inv[r][k] -= f * inv[c][k];
      }
    }
  }
  return true;
}

// The 2x6 Jacobian of the pixel of point X (camera frame) with respect to a
// pose perturbation X' = X + dt + dtheta x X: d(pixel)/dX * [I | -[X]x].
inline std::vector<std::vector<double>> ref_jacobian(const RefKeyframe& f, const RefObservation& o) {
  const double z = o.depth;
  const double x = (o.u - f.cx) / f.fx * z, y = (o.v - f.cy) / f.fy * z;
  const double p[2][3] = {{f.fx / z, 0, -f.fx * x / (z * z)}, {0, f.fy / z, -f.fy * y / (z * z)}};
  const double m[3][6] = {{1, 0, 0, 0, z, -y}, {0, 1, 0, -z, 0, x}, {0, 0, 1, y, -x, 0}};
  std::vector<std::vector<double>> j(2, std::vector<double>(6, 0.0));
  for (int r = 0; r < 2; ++r) {
    for (int c = 0; c < 6; ++c) {
      for (int k = 0; k < 3; ++k) j[r][c] += p[r][k] * m[k][c];
    }
  }
  return j;
}

// Every observation's level (core::CostModel::kInformation): 2 - floor(log2 r)
// in [0, 4], r the leverage tr(J L^-1 J^T) times n / 6; 2 where unknown or
// degenerate (fewer than 4 observations with a depth, or an LDL^T pivot
// <= 1e-9 of L's largest diagonal entry).
inline std::vector<std::uint64_t> ref_information_levels(const RefKeyframe& f) {
  std::vector<std::uint64_t> levels(f.observations.size(), 2);
  if (!(f.fx > 0) || !(f.fy > 0)) return levels;
  std::vector<std::vector<double>> info(6, std::vector<double>(6, 0.0));
  std::size_t used = 0;
  for (const auto& o : f.observations) {
    if (!(o.depth > 0)) continue;
    const auto j = ref_jacobian(f, o);
    for (int r = 0; r < 6; ++r) {
      for (int c = 0; c < 6; ++c) info[r][c] += j[0][r] * j[0][c] + j[1][r] * j[1][c];
    }
    ++used;
  }
  if (used < 4) return levels;  // not over-determined: every leverage is 1
  double largest = 0;
  for (int r = 0; r < 6; ++r) largest = std::max(largest, info[r][r]);
  auto d = info;  // elimination without pivoting: its pivots are LDL^T's D
  for (int c = 0; c < 6; ++c) {
    if (!(d[c][c] > 1e-9 * largest)) return levels;
    for (int r = c + 1; r < 6; ++r) {
      const double factor = d[r][c] / d[c][c];
      for (int k = c; k < 6; ++k) d[r][k] -= factor * d[c][k];
    }
  }
  std::vector<std::vector<double>> inv;
  if (!ref_invert6(info, inv)) return levels;
  for (std::size_t i = 0; i < f.observations.size(); ++i) {
    if (!(f.observations[i].depth > 0)) continue;
    const auto j = ref_jacobian(f, f.observations[i]);
    double t = 0;
    for (int row = 0; row < 2; ++row) {
      for (int r = 0; r < 6; ++r) {
        for (int c = 0; c < 6; ++c) t += j[row][r] * inv[r][c] * j[row][c];
      }
    }
    const double ratio = t * static_cast<double>(used) / 6.0;
    std::int64_t level = 2 - static_cast<std::int64_t>(std::floor(std::log2(ratio)));
    levels[i] = static_cast<std::uint64_t>(std::min<std::int64_t>(4, std::max<std::int64_t>(0, level)));
  }
  return levels;
}

// One quality's level (core::CostModel::kTrack), written from the rules:
// log2 steps for the track length and the age, thresholds for the error and
// the angle; 2 where unknown.
inline std::uint64_t ref_track_level(const core::PointQuality& q, std::uint8_t terms) {
  std::uint64_t sum = 0;
  const auto log_steps = [](double x) {  // 4 - min(4, floor(log2 x)), x >= 1
    return static_cast<std::uint64_t>(4 - std::min(4.0, std::floor(std::log2(x))));
  };
  if (terms & core::kTrackLength) sum += q.track_length == 0 ? 2 : log_steps(q.track_length);
  if (terms & core::kTrackAge) sum += q.age < 0 ? 2 : log_steps(q.age + 1.0);
  if (terms & core::kTrackError) {
    const float e = q.reprojection_error;
    sum += e < 0 ? 2 : e < 0.5f ? 0 : e < 1 ? 1 : e < 2 ? 2 : e < 4 ? 3 : 4;
  }
  if (terms & core::kTrackAngle) {
    const float a = q.triangulation_angle;
    sum += a <= 0 ? 2 : a >= 8 ? 0 : a >= 4 ? 1 : a >= 2 ? 2 : a >= 1 ? 3 : 4;
  }
  return sum;
}

// The integer each observation's arc costs are a function of, per model.
inline std::vector<std::uint64_t> ref_scores(const RefKeyframe& f, const core::Params& params) {
  if (params.cost_model == core::CostModel::kInformation) return ref_information_levels(f);
  if (params.cost_model == core::CostModel::kTrack) {
    std::vector<std::uint64_t> out;
    for (std::size_t i = 0; i < f.observations.size(); ++i) {
      out.push_back(ref_track_level(f.quality.empty() ? core::PointQuality{} : f.quality[i], params.track_terms));
    }
    return out;
  }
  std::vector<std::uint64_t> out;
  for (std::size_t i = 0; i < f.observations.size(); ++i) {
    out.push_back(params.cost_model == core::CostModel::kAuthors ? ref_grid_neighbours(f, i, params)
                                                                 : ref_nearby(f, i, params));
  }
  return out;
}

inline std::int64_t ref_arc_cost(const core::Params& params, std::uint64_t a, std::uint64_t b) {
  if (!(params.cost_terms & core::kSpatialCost)) return 0;
  std::int64_t cost = 0;
  switch (params.cost_model) {
    case core::CostModel::kAuthors: cost = ref_authors_spatial_cost(a, b); break;
    case core::CostModel::kInformation:
    case core::CostModel::kTrack: cost = static_cast<std::int64_t>(a + b); break;
    default: cost = ref_spatial_cost(a, b);
  }
  return cost * params.spatial_weight;
}

inline std::int64_t ref_sink_cost(const core::Params& params, const double* a, const double* b) {
  if (!(params.cost_terms & core::kBaselineCost)) return 0;
  return params.cost_model == core::CostModel::kAuthors ? ref_authors_baseline_cost(a, b)
                                                        : ref_baseline_cost(a, b);
}

inline std::vector<RefKeyframe> ref_frames_of(const core::Window& window) {
  std::vector<RefKeyframe> frames;
  for (std::uint32_t s = 0; s < window.keyframe_count(); ++s) {
    RefKeyframe f;
    const core::Keyframe& kf = window.keyframe(s);
    f.id = kf.id;
    for (int i = 0; i < 3; ++i) f.centre[i] = kf.centre[i];
    f.fx = kf.fx;
    f.fy = kf.fy;
    f.cx = kf.cx;
    f.cy = kf.cy;
    for (std::uint32_t i = 0; i < kf.unmapped_count; ++i) {
      f.unmapped.push_back({kf.unmapped[i].u, kf.unmapped[i].v});
    }
    for (std::uint32_t i = 0; i < window.observation_count(s); ++i) {
      const core::Observation& o = window.observations(s)[i];
      f.observations.push_back({o.point, o.u, o.v, o.depth});
      if (kf.tracked != nullptr) f.tracked.push_back(kf.tracked[i]);
      if (kf.quality != nullptr) f.quality.push_back(kf.quality[i]);
    }
    frames.push_back(f);
  }
  return frames;
}

// `frames` in window slot order (oldest first).
inline RefResult reference_sparsify(const std::vector<RefKeyframe>& frames,
                                    const core::Params& params) {
  // point id -> (frame slot, index of the observation in that frame), slot order.
  std::map<std::uint64_t, std::vector<std::pair<std::size_t, std::size_t>>> seen;
  for (std::size_t f = 0; f < frames.size(); ++f) {
    for (std::size_t i = 0; i < frames[f].observations.size(); ++i) {
      seen[frames[f].observations[i].point].push_back({f, i});
    }
  }
  std::int64_t m = 0;
  for (const auto& entry : seen) m = std::max<std::int64_t>(m, entry.second.size());
  std::vector<std::vector<std::uint64_t>> scores;
  for (const auto& f : frames) scores.push_back(ref_scores(f, params));

  // Candidates of each pair (j, k): (c_c + c_s, point id).
  std::map<std::pair<std::size_t, std::size_t>, std::vector<std::pair<std::int64_t, std::uint64_t>>>
      candidates;
  RefResult result;
  for (const auto& entry : seen) {
    const auto& views = entry.second;
    const std::int64_t n = static_cast<std::int64_t>(views.size());
    if (n < 2) continue;
    ++result.evaluated;
    const std::int64_t cc =
        (params.cost_terms & core::kConnectivityCost) ? ref_connectivity_cost(n, m) : 0;
    for (std::size_t x = 0; x < views.size(); ++x) {
      for (std::size_t y = x + 1; y < views.size(); ++y) {
        const std::uint64_t nx = scores[views[x].first][views[x].second];
        const std::uint64_t ny = scores[views[y].first][views[y].second];
        candidates[{views[x].first, views[y].first}].push_back({cc + ref_arc_cost(params, nx, ny),
                                                                entry.first});
        ++result.pair_arcs;
      }
    }
  }

  std::map<std::uint64_t, std::int64_t> flow;
  for (auto& entry : candidates) {
    auto& list = entry.second;
    std::sort(list.begin(), list.end());  // by cost, then by point id
    const std::int64_t cb =
        ref_sink_cost(params, frames[entry.first.first].centre, frames[entry.first.second].centre);
    const std::int64_t take = std::min<std::int64_t>(params.pair_capacity, list.size());
    for (std::int64_t i = 0; i < take; ++i) {
      ++flow[list[i].second];
      result.total_cost += list[i].first + cb;
    }
    result.max_flow += take;
  }
  result.pairs = static_cast<std::uint32_t>(candidates.size());

  for (const auto& entry : seen) {
    RefPoint p;
    p.id = entry.first;
    p.views = static_cast<std::uint32_t>(entry.second.size());
    if (p.views >= 2) {
      p.capacity = static_cast<std::int64_t>(p.views) * (p.views - 1) / 2;
      p.flow = flow[p.id];
      p.verdict = static_cast<double>(p.flow) > params.theta * static_cast<double>(p.capacity)
                      ? core::Verdict::kKeep
                      : core::Verdict::kCull;
    }
    result.points.push_back(p);
  }
  return result;
}

}  // namespace keepless::test
