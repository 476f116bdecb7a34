#pragma once
// N(p, f) for all keypoints of one keyframe: how many other keypoints of the
// frame lie in the closed box |du| <= w/2, |dv| <= h/2 around each one.
// Shared by the from-scratch and the incremental network builders.

#include <cstddef>
#include <cstdint>

#include "keepless/core/window.hpp"

namespace keepless::core {

// Scratch for count_box_neighbours, sized for the largest frame.
struct BoxScratch {
  std::uint32_t* by_u = nullptr;     // [n] indices sorted by u
  std::uint32_t* by_v = nullptr;     // [n] indices sorted by v
  std::uint32_t* v_rank = nullptr;   // [n] position of each index in by_v
  std::uint32_t* fenwick = nullptr;  // [n + 1]
  static constexpr std::size_t kWordsPerObservation = 4;  // plus one word
};

// Writes N for observations[0..count) into out[0..count). Exact with
// respect to in_box(q.u - o.u, q.v - o.v, w, h): the box test is monotone in
// each coordinate, so a sweep over u with a Fenwick tree over v ranks finds
// the same set as testing every pair, in O(n log n).
void count_box_neighbours(const Observation* observations, std::uint32_t count,
                          std::int32_t box_width, std::int32_t box_height, BoxScratch scratch,
                          std::uint32_t* out);

}  // namespace keepless::core
