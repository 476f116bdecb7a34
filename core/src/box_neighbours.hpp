#pragma once
// N(p, f) for all keypoints of one keyframe: how many other keypoints of the
// frame lie in the closed box |du| <= w/2, |dv| <= h/2 around each one.
// Shared by the from-scratch and the incremental network builders.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "keepless/core/window.hpp"

namespace keepless::core {

// Exact with respect to in_box(q.u - o.u, q.v - o.v, w, h) for finite
// coordinates and w, h >= 0. The rounded difference fl(q.u - o.u) is monotone
// in q.u and in o.u, so the keypoints passing either half of the test form a
// contiguous run of the keypoints sorted by that coordinate, and that run
// only moves forwards as o moves forwards. So: sort both coordinates (a radix
// sort on a monotone 16-bit quantisation, then the few runs of equal keys by
// their exact values), find each keypoint's run of v ranks with two pointers,
// and sweep u with two pointers, keeping the keypoints inside the u run in a
// bitset over v ranks; N is the popcount of the v run minus the keypoint
// itself. Cost: linear passes, the exact sorts of runs of equal keys (short
// unless many keypoints crowd into 1/65536 of the span), and per keypoint
// the popcount of its v run, a word per 64 keypoints in its band (n/64 words
// if all share one band). It replaces a Fenwick sweep with binary searches,
// about six times slower on ORB-like frames.
class BoxCounter {
 public:
  // Room for frames of up to `max_count` observations; allocates only here.
  explicit BoxCounter(std::uint32_t max_count);

  // Writes N for observations[0..count) into out[0..count); count must not
  // exceed max_count.
  void count(const Observation* observations, std::uint32_t count, std::int32_t box_width,
             std::int32_t box_height, std::uint32_t* out);

  std::size_t memory_bytes() const;

 private:
  // Sorts indices 0..n-1 by (coordinate, index): returns them (in the low
  // 32 bits of each element) and writes the sorted coordinates to coord.
  const std::uint64_t* sort_axis(const Observation* obs, std::uint32_t n, bool v_axis,
                                 double* coord);

  std::vector<std::uint64_t> keys_, spare_;  // radix sort (key << 32 | index), then the v runs
  std::vector<double> su_, sv_;              // coordinates in u order, in v order
  std::vector<std::uint32_t> by_u_, v_rank_;
  std::vector<std::uint64_t> active_;  // bitset over v ranks
};

}  // namespace keepless::core
