#pragma once
// The decision policies (core::Params::maturity_keyframes and the newest
// keyframe's tracked flags, core::Params::scope, core::Params::coverage_floor)
// applied to the naive reference's optimum, written from their definitions:
// each point's keyframes in a std::set, each keyframe's coverage recounted
// from scratch at its turn, its culled points sorted whole.

#include <algorithm>
#include <cstdint>
#include <map>
#include <set>
#include <vector>

#include "keepless/core/config.hpp"
#include "keepless/core/decision.hpp"
#include "reference_sparsifier.hpp"

namespace keepless::test {

inline void ref_apply_policies(const std::vector<RefKeyframe>& frames, const core::Params& params,
                               RefResult& r) {
  std::map<std::uint64_t, std::set<std::size_t>> slots;
  for (std::size_t f = 0; f < frames.size(); ++f) {
    for (const auto& o : frames[f].observations) slots[o.point].insert(f);
  }
  const std::size_t k = frames.size();
  const auto skip = [](RefPoint& p) {
    p.verdict = core::Verdict::kSkip;
    p.flow = 0;
    p.capacity = 0;
  };
  // Tracking-safe culling: a point whose oldest observing window keyframe is
  // among the newest A is guarded; then a point the newest keyframe flags
  // tracked.
  const std::size_t a = params.maturity_keyframes;
  for (RefPoint& p : r.points) {
    if (a == 0 || p.verdict == core::Verdict::kSkip) continue;
    const std::size_t first = *slots[p.id].begin();  // std::set: ascending
    if (first + a >= k) {
      skip(p);
      ++r.guarded;
    }
  }
  if (k > 0 && !frames[k - 1].tracked.empty()) {
    std::set<std::uint64_t> tracked;
    for (std::size_t i = 0; i < frames[k - 1].observations.size(); ++i) {
      if (frames[k - 1].tracked[i] != 0) tracked.insert(frames[k - 1].observations[i].point);
    }
    for (RefPoint& p : r.points) {
      if (p.verdict == core::Verdict::kSkip || tracked.count(p.id) == 0) continue;
      skip(p);
      ++r.tracked;
    }
  }
  // Scope newest decides the keyframe A slots before the newest.
  if (params.scope == core::Scope::kNewest && k > a) {
    const std::size_t decided = k - 1 - a;
    for (RefPoint& p : r.points) {
      if (p.verdict == core::Verdict::kSkip || slots[p.id].count(decided) != 0) continue;
      p.verdict = core::Verdict::kSkip;
      p.flow = 0;
      p.capacity = 0;
      ++r.out_of_scope;
    }
  }
  const std::uint32_t floor = params.coverage_floor;
  if (floor == 0) return;
  for (std::size_t s = 0; s < k; ++s) {
    std::uint32_t covered = 0;
    std::vector<RefPoint*> culled;
    for (RefPoint& p : r.points) {
      if (p.views < 2 || slots[p.id].count(s) == 0) continue;
      if (p.verdict == core::Verdict::kCull) {
        culled.push_back(&p);
      } else {
        ++covered;
      }
    }
    if (covered >= floor) continue;
    ++r.floor_keyframes;
    // Nearest to being kept first: the largest flow / capacity, then the smaller id.
    std::sort(culled.begin(), culled.end(), [](const RefPoint* a, const RefPoint* b) {
      const long double x = static_cast<long double>(a->flow) / a->capacity;
      const long double y = static_cast<long double>(b->flow) / b->capacity;
      if (a->flow * b->capacity != b->flow * a->capacity) return x > y;
      return a->id < b->id;
    });
    std::size_t i = 0;
    for (; covered < floor && i < culled.size(); ++i, ++covered) {
      culled[i]->verdict = core::Verdict::kKeep;
      ++r.floor_promoted;
    }
    if (covered < floor) ++r.floor_short;
  }
}

// The reference's decisions under every Params field.
inline RefResult reference_decide(const std::vector<RefKeyframe>& frames, const core::Params& params) {
  RefResult r = reference_sparsify(frames, params);
  ref_apply_policies(frames, params, r);
  return r;
}

}  // namespace keepless::test
