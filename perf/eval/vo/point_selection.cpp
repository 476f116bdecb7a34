#include "point_selection.hpp"

#include <algorithm>
#include <numeric>

#include "prng.hpp"
#include "ssc.hpp"

namespace keepless::eval::vo {

std::vector<core::PointId> baseline_culls(Selector selector, const std::vector<Candidate>& candidates,
                                          std::size_t cull, std::uint64_t seed, int width, int height,
                                          AnmsVariant anms) {
  const std::size_t n = candidates.size();
  cull = std::min(cull, n);
  std::vector<std::uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  std::vector<core::PointId> out;
  if (cull == 0) return out;
  switch (selector) {
    case Selector::kRandom: {
      std::vector<std::uint64_t> priority(n);
      for (std::size_t i = 0; i < n; ++i) priority[i] = mix(seed, candidates[i].id);
      std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
        return priority[a] != priority[b] ? priority[a] < priority[b] : candidates[a].id < candidates[b].id;
      });
      break;
    }
    case Selector::kLongestTrack:
      std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
        const Candidate &x = candidates[a], &y = candidates[b];
        return x.track_length != y.track_length ? x.track_length < y.track_length : x.id > y.id;
      });
      break;
    case Selector::kAnms: {
      if (anms == AnmsVariant::kResponse) {  // the weakest go first
        std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
          const Candidate &x = candidates[a], &y = candidates[b];
          return x.response != y.response ? x.response < y.response : x.id > y.id;
        });
        break;
      }
      // Keyframes in the order they first appear, each with its candidates
      // (indices into `candidates`) and their keypoints.
      std::vector<int> frames;
      std::vector<std::vector<std::uint32_t>> per;
      std::vector<std::vector<SscPoint>> groups;
      for (std::uint32_t i = 0; i < n; ++i) {
        const Candidate& c = candidates[i];
        auto at = std::find(frames.begin(), frames.end(), c.keyframe);
        if (at == frames.end()) {
          frames.push_back(c.keyframe);
          per.emplace_back();
          groups.emplace_back();
          at = frames.end() - 1;
        }
        const auto k = static_cast<std::size_t>(at - frames.begin());
        per[k].push_back(i);
        // kSpread: a priority in [0, 1) that knows nothing of the keypoint;
        // kTrack: the track length, ties by that priority.
        const double priority = static_cast<double>(mix(seed, c.id) >> 11) * 0x1p-53;
        const double rank = anms == AnmsVariant::kSpread ? priority
                            : anms == AnmsVariant::kTrack ? c.track_length + priority
                                                          : static_cast<double>(c.response);
        groups[k].push_back({c.u, c.v, rank, c.id});
      }
      const auto chosen = ssc_select_shared(groups, static_cast<std::uint32_t>(n - cull), width, height);
      std::vector<bool> kept(n, false);
      for (std::size_t k = 0; k < per.size(); ++k) {
        for (std::uint32_t j : chosen[k]) kept[per[k][j]] = true;
      }
      std::stable_partition(order.begin(), order.end(), [&](std::uint32_t i) { return !kept[i]; });
      break;
    }
    case Selector::kOriginal:
    case Selector::kKeepless:
      return out;
  }
  for (std::size_t i = 0; i < cull; ++i) out.push_back(candidates[order[i]].id);
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace keepless::eval::vo
