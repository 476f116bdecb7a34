#include "sparsify/exact_count.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "keepless/core/keep_thresholds.hpp"
#include "sparsify/modes.hpp"

namespace keepless::sparsify {
namespace {

// Each decision's observations in `images`: COLMAP's track length, an image
// seeing a point twice counting twice (by distinct images, the window's n,
// the fixture's deviation at 0.1-0.15 of its points was 1.2x the filter's).
// Returns the most.
std::uint32_t count_observations(const std::vector<std::vector<core::PointId>>& images,
                                 const std::vector<core::PointDecision>& d, std::vector<std::uint32_t>* views) {
  views->assign(d.size(), 0);
  std::uint32_t most = 0;
  for (const std::vector<core::PointId>& image : images) {
    for (const core::PointId id : image) {
      const std::int64_t i = find_decision(d, id);
      if (i >= 0) most = std::max(most, ++(*views)[static_cast<std::size_t>(i)]);
    }
  }
  return most;
}

// The indices of the decisions not skipped, into *order; returns the
// skipped ones' count (never culled, they count towards a kept count).
std::uint64_t judged(const std::vector<core::PointDecision>& d, std::vector<std::size_t>* order) {
  std::uint64_t skipped = 0;
  for (std::size_t i = 0; i < d.size(); ++i) {
    if (d[i].verdict == core::Verdict::kSkip) {
      ++skipped;
    } else {
      order->push_back(i);
    }
  }
  return skipped;
}

}  // namespace

std::uint32_t longest_tracks_poorest(const std::vector<std::vector<core::PointId>>& images,
                                     std::vector<core::PointDecision> decisions, std::uint64_t count) {
  std::vector<std::uint32_t> views;
  count_observations(images, decisions, &views);
  std::vector<std::size_t> order;
  const std::uint64_t skipped = judged(decisions, &order);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return views[a] != views[b] ? views[a] > views[b] : decisions[a].point < decisions[b].point;
  });
  const std::uint64_t take = count > skipped ? count - skipped : 0;
  for (std::size_t j = 0; j < order.size(); ++j) {
    decisions[order[j]].verdict = j < take ? core::Verdict::kKeep : core::Verdict::kCull;
  }
  const std::vector<std::uint32_t> per_image = kept_observations(images, decisions);
  return per_image.empty() ? 0 : *std::min_element(per_image.begin(), per_image.end());
}

std::uint32_t floor_over(double r, std::uint32_t observations) {
  const double floor = std::ceil(r * observations * (1 - 1e-12));
  return floor >= double{UINT32_MAX} ? UINT32_MAX : static_cast<std::uint32_t>(floor);
}

ExactCount keep_exactly(const std::vector<std::vector<core::PointId>>& images, std::uint32_t floor,
                        std::uint64_t count, const std::vector<std::uint32_t>& thresholds,
                        std::vector<core::PointDecision>* decisions, double track_share) {
  std::vector<core::PointDecision>& d = *decisions;
  std::vector<std::size_t> order;
  const std::uint64_t skipped = judged(d, &order);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return thresholds[a] != thresholds[b] ? thresholds[a] < thresholds[b] : d[a].point < d[b].point;
  });
  if (track_share > 0.0) {
    std::vector<std::uint32_t> views, ranked(order.begin(), order.end()), scratch(order.size());
    const std::uint32_t max_views = count_observations(images, d, &views);
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
