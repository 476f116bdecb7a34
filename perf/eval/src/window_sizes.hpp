#pragma once
// How large the windows of a SLAM run are, to size keepless's capacities
// from real workloads: per window the keyframes, distinct map points,
// observations, point -> pair arcs (the sum over its points of n(n-1)/2, n
// the window keyframes observing the point) and unmapped keypoints; the
// maximum over a run's windows, at window sizes K = 10, 20 and 40, for two
// kinds of window taken at every local-mapping step:
//   local    the new keyframe and its best covisible keyframes, at most K
//            (the local BA's keyframes; keepless_eval's selector decides on it)
//   sliding  the K most recent live keyframes (what keepless_node holds)
// Observations are the keyframes' current ones (points culled or merged
// since are gone; observations added since are counted): an upper bound on
// what a node fed at keyframe creation holds.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "keepless/core/config.hpp"

namespace keepless::eval {

struct WindowSize {
  std::uint64_t keyframes = 0, points = 0, observations = 0, pair_arcs = 0, unmapped = 0;
  void max_with(const WindowSize& o);
};

struct WindowSizes {
  static constexpr std::array<int, 3> kSizes = {10, 20, 40};
  std::array<WindowSize, 3> local{}, sliding{};
  std::uint64_t steps = 0;  // local-mapping steps measured
  // The K = 20 windows (local and sliding) replayed into a Window and an
  // incremental Sparsifier sized by given capacities (keepless_node's
  // defaults): windows decided, and refused for a capacity.
  std::uint64_t replayed = 0, refused = 0;
  void max_with(const WindowSizes& o);
};

// One window, keyframe by keyframe.
class WindowMeasure {
 public:
  void clear();
  // A keyframe's map points (a repeated one counts once) and its keypoints without one.
  void add_keyframe(const std::vector<core::PointId>& points, std::uint64_t unmapped);
  WindowSize size();

 private:
  std::vector<core::PointId> ids_;
  WindowSize s_;
};

// A markdown table of `rows` (name, sizes), one line per (name, kind, K).
std::string window_sizes_table(const std::vector<std::pair<std::string, WindowSizes>>& rows);
// {"window_sizes":[{"input":..,"kind":"local|sliding","K":..,"keyframes":..,...},...]}
std::string window_sizes_json(const std::vector<std::pair<std::string, WindowSizes>>& rows);

}  // namespace keepless::eval
