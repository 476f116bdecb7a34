#pragma once
// A naive, independent implementation of the paper's section III-B, written
// straight from the formulas for tests: std::map/std::vector, all-pairs box
// counting, its own cost code (nothing from core/src). It solves the network
// by its per-pair closed form: the source arcs never bind (capacity n(n-1)/2 =
// the point's out-degree), so each pair (f_j, f_k) independently carries
// min(M, shared points) units on its cheapest points by c_c + c_s, ties to the
// smaller point id.
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
};

struct RefKeyframe {
  std::uint64_t id = 0;
  double centre[3] = {0, 0, 0};
  std::vector<RefObservation> observations;
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

inline std::vector<RefKeyframe> ref_frames_of(const core::Window& window) {
  std::vector<RefKeyframe> frames;
  for (std::uint32_t s = 0; s < window.keyframe_count(); ++s) {
    RefKeyframe f;
    f.id = window.keyframe(s).id;
    for (int i = 0; i < 3; ++i) f.centre[i] = window.keyframe(s).centre[i];
    for (std::uint32_t i = 0; i < window.observation_count(s); ++i) {
      const core::Observation& o = window.observations(s)[i];
      f.observations.push_back({o.point, o.u, o.v});
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

  // Candidates of each pair (j, k): (c_c + c_s, point id).
  std::map<std::pair<std::size_t, std::size_t>, std::vector<std::pair<std::int64_t, std::uint64_t>>>
      candidates;
  RefResult result;
  for (const auto& entry : seen) {
    const auto& views = entry.second;
    const std::int64_t n = static_cast<std::int64_t>(views.size());
    if (n < 2) continue;
    ++result.evaluated;
    const std::int64_t cc = ref_connectivity_cost(n, m);
    for (std::size_t x = 0; x < views.size(); ++x) {
      for (std::size_t y = x + 1; y < views.size(); ++y) {
        const std::uint64_t nx = ref_nearby(frames[views[x].first], views[x].second, params);
        const std::uint64_t ny = ref_nearby(frames[views[y].first], views[y].second, params);
        candidates[{views[x].first, views[y].first}].push_back({cc + ref_spatial_cost(nx, ny),
                                                                entry.first});
        ++result.pair_arcs;
      }
    }
  }

  std::map<std::uint64_t, std::int64_t> flow;
  for (auto& entry : candidates) {
    auto& list = entry.second;
    std::sort(list.begin(), list.end());  // by cost, then by point id
    const std::int64_t cb = ref_baseline_cost(frames[entry.first.first].centre,
                                              frames[entry.first.second].centre);
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
