#include "box_neighbours.hpp"

#include <algorithm>

namespace keepless::core {

void count_box_neighbours(const Observation* obs, std::uint32_t n, std::int32_t box_width,
                          std::int32_t box_height, BoxScratch s, std::uint32_t* out) {
  if (n == 0) return;
  // The same arithmetic as in_box: |q - o| <= half, with q - o rounded once.
  const double half_w = 0.5 * box_width;
  const double half_h = 0.5 * box_height;
  for (std::uint32_t i = 0; i < n; ++i) s.by_u[i] = s.by_v[i] = i;
  std::sort(s.by_u, s.by_u + n, [obs](std::uint32_t a, std::uint32_t b) {
    return obs[a].u != obs[b].u ? obs[a].u < obs[b].u : a < b;
  });
  std::sort(s.by_v, s.by_v + n, [obs](std::uint32_t a, std::uint32_t b) {
    return obs[a].v != obs[b].v ? obs[a].v < obs[b].v : a < b;
  });
  for (std::uint32_t r = 0; r < n; ++r) s.v_rank[s.by_v[r]] = r;
  std::fill(s.fenwick, s.fenwick + n + 1, 0u);
  const auto add = [&s, n](std::uint32_t rank, std::uint32_t delta) {
    for (std::uint32_t i = rank + 1; i <= n; i += i & (0u - i)) s.fenwick[i] += delta;
  };
  const auto prefix = [&s](std::uint32_t end) {  // items with rank < end
    std::uint32_t total = 0;
    for (std::uint32_t i = end; i > 0; i -= i & (0u - i)) total += s.fenwick[i];
    return total;
  };

  // Two pointers over u order: q is in the window of o iff
  // -half_w <= q.u - o.u <= half_w. Rounding is monotone, so as o.u grows a
  // keypoint that has left on the left never returns and one that entered
  // on the right stays.
  std::uint32_t lo = 0, hi = 0;
  for (std::uint32_t a = 0; a < n; ++a) {
    const Observation& o = obs[s.by_u[a]];
    while (hi < n && obs[s.by_u[hi]].u - o.u <= half_w) add(s.v_rank[s.by_u[hi++]], 1);
    while (obs[s.by_u[lo]].u - o.u < -half_w) add(s.v_rank[s.by_u[lo++]], 0u - 1u);
    // Ranks whose v passes -half_h <= v - o.v <= half_h: a contiguous run.
    std::uint32_t* first = std::partition_point(s.by_v, s.by_v + n, [&](std::uint32_t i) {
      return obs[i].v - o.v < -half_h;
    });
    std::uint32_t* last = std::partition_point(first, s.by_v + n, [&](std::uint32_t i) {
      return obs[i].v - o.v <= half_h;
    });
    const auto begin = static_cast<std::uint32_t>(first - s.by_v);
    const auto end = static_cast<std::uint32_t>(last - s.by_v);
    out[s.by_u[a]] = prefix(end) - prefix(begin) - 1;  // minus o itself
  }
}

}  // namespace keepless::core
