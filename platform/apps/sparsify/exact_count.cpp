#include "sparsify/exact_count.hpp"

#include <algorithm>

#include "keepless/core/keep_thresholds.hpp"
#include "sparsify/modes.hpp"

namespace keepless::sparsify {

ExactCount keep_exactly(const std::vector<std::vector<core::PointId>>& images, std::uint32_t floor,
                        std::uint64_t count, const std::vector<std::uint32_t>& thresholds,
                        std::vector<core::PointDecision>* decisions, double track_share) {
  std::vector<core::PointDecision>& d = *decisions;
  std::vector<std::size_t> order;
  std::uint64_t skipped = 0;
  for (std::size_t i = 0; i < d.size(); ++i) {
    if (d[i].verdict == core::Verdict::kSkip) {
      ++skipped;
    } else {
      order.push_back(i);
    }
  }
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return thresholds[a] != thresholds[b] ? thresholds[a] < thresholds[b] : d[a].point < d[b].point;
  });
  if (track_share > 0.0) {
    std::vector<std::uint32_t> views(d.size()), ranked(order.begin(), order.end()), scratch(order.size());
    // COLMAP's track length: every observation, an image seeing a point twice
    // counting twice (by distinct images, the window's n, the fixture's
    // deviation at 0.1-0.15 of its points was 1.2x the filter's).
    std::uint32_t max_views = 0;
    for (const std::vector<core::PointId>& image : images) {
      for (const core::PointId id : image) {
        const std::int64_t i = find_decision(d, id);
        if (i >= 0) max_views = std::max(max_views, ++views[static_cast<std::size_t>(i)]);
      }
    }
    std::vector<std::uint32_t> histogram(std::size_t{max_views} + 1);
    const auto wanted = static_cast<std::uint32_t>(std::min<std::uint64_t>(count > skipped ? count - skipped : 0, order.size()));
    core::take_longest_tracks(ranked.data(), static_cast<std::uint32_t>(ranked.size()), wanted, track_share, views.data(),
                              max_views, histogram.data(), scratch.data());
    order.assign(ranked.begin(), ranked.end());
  }
  // The first k of the order kept, the rest culled, then the floor.
  std::uint32_t restored = 0;
  const auto take = [&](std::size_t k) {
    for (std::size_t j = 0; j < order.size(); ++j) d[order[j]].verdict = j < k ? core::Verdict::kKeep : core::Verdict::kCull;
    restored = apply_floor(images, floor, decisions);
    return skipped + k + restored;
  };
  std::size_t lo = 0, hi = order.size();  // largest k with take(k) <= count
  ExactCount r;
  if (take(0) > count) {
    r.floor_fits = false;
  } else {
    while (lo < hi) {
      const std::size_t mid = lo + (hi - lo + 1) / 2;
      if (take(mid) <= count) {
        lo = mid;
      } else {
        hi = mid - 1;
      }
    }
  }
  std::uint64_t kept = take(lo);
  r.restored = restored;
  // Fill up to the count with the next points of the order.
  for (std::size_t j = lo; j < order.size() && kept < count; ++j) {
    if (d[order[j]].verdict == core::Verdict::kKeep) continue;
    d[order[j]].verdict = core::Verdict::kKeep;
    ++kept;
  }
  r.kept = kept;
  r.from_order = kept - skipped - r.restored;
  return r;
}

}  // namespace keepless::sparsify
