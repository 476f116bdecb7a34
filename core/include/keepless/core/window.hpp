#pragma once
// The sliding window: keyframes in insertion order and their observations,
// in storage sized once from Capacities. A failed call changes nothing.

#include <cstddef>
#include <cstdint>
#include <memory>

#include "keepless/core/config.hpp"
#include "keepless/core/status.hpp"

namespace keepless::core {

// A detected keypoint, pixels.
struct Keypoint {
  double u = 0;
  double v = 0;
};

// What the map knows about a point beyond the window, as the SLAM knew it
// when it sent the keyframe (CostModel::kTrack). Unknown values: 0 track
// length, negative age, negative error, angle <= 0.
struct PointQuality {
  std::uint32_t track_length = 0;   // observations of the point in the whole map
  std::int32_t age = -1;            // keyframes since the point was made (0: by this one)
  float reprojection_error = -1.f;  // pixels (BA residual, COLMAP's ERROR)
  float triangulation_angle = 0.f;  // degrees, largest between its observing rays
};

struct Keyframe {
  KeyframeId id = 0;
  double centre[3] = {0, 0, 0};          // camera centre, metres
  double orientation[4] = {1, 0, 0, 0};  // unit quaternion w, x, y, z (carried, not used by costs)
  // Optional, for the cost models that need them (Params::cost_model).
  // Pinhole intrinsics, pixels (CostModel::kInformation); fx = 0: unknown.
  double fx = 0, fy = 0, cx = 0, cy = 0;
  // The keyframe's detected keypoints that observe no map point
  // (CostModel::kAuthors counts them in N(p,f)). add_keyframe copies them
  // into the window (Capacities::max_unmapped_keypoints over the window);
  // a keyframe read back from a Window points at the window's copy.
  const Keypoint* unmapped = nullptr;
  std::uint32_t unmapped_count = 0;
  // Optional tracked flags, one per observation in add_keyframe's order
  // (null: none): nonzero = the tracker matched this point in its latest
  // frames. The newest window keyframe's flags protect those points from
  // culling (Summary::tracked); older keyframes' flags are history and are
  // not read. add_keyframe copies them; a keyframe read back from a Window
  // points at the window's copy.
  const std::uint8_t* tracked = nullptr;
  // Optional point quality, one per observation in add_keyframe's order
  // (null: none; CostModel::kTrack). Copied like `tracked` (unless
  // Capacities::hold_quality is false); a non-finite error or angle is
  // refused.
  const PointQuality* quality = nullptr;
};

struct Observation {
  PointId point = 0;
  double u = 0;  // keypoint, pixels
  double v = 0;
  // Optional: the point's depth (z) in this camera, metres
  // (CostModel::kInformation); <= 0: unknown.
  double depth = 0;
};

class Window {
 public:
  explicit Window(const Capacities& capacities);
  ~Window();
  Window(const Window&) = delete;
  Window& operator=(const Window&) = delete;

  // Adds a keyframe with all its observations (and unmapped keypoints),
  // atomically: on any error (capacity, non-finite number, duplicate
  // keyframe id, a point observed twice by this keyframe) the window is
  // unchanged.
  [[nodiscard]] Status add_keyframe(const Keyframe& keyframe, const Observation* observations,
                                    std::uint32_t count);
  // Adds keyframe `slot` of another window with its observations, as
  // add_keyframe does, keeping its stamp (see keyframe_stamp): a window
  // rebuilt from another one (e.g. without some points) stays recognisable
  // keyframe by keyframe. kInvalidArgument for a slot out of range.
  [[nodiscard]] Status copy_keyframe(const Window& from, std::uint32_t slot);
  [[nodiscard]] Status remove_keyframe(KeyframeId id);  // kUnknownKeyframe if absent
  // Removes the oldest keyframe and adds this one, as add_keyframe would into
  // the window without the oldest, atomically: on any error (as
  // add_keyframe's; an id equal to the oldest's is a duplicate) the window
  // is unchanged, the oldest included. kInvalidArgument for an empty window.
  [[nodiscard]] Status slide(const Keyframe& keyframe, const Observation* observations, std::uint32_t count);
  // Drops every observation of these points, given in ascending order
  // (kInvalidArgument otherwise). Keyframes that lose an observation get new
  // stamps; the others keep theirs. Nothing else can fail.
  [[nodiscard]] Status remove_points(const PointId* sorted_points, std::uint32_t count);
  void clear();

  std::uint32_t keyframe_count() const;
  // Slot i in insertion order (0 = oldest).
  const Keyframe& keyframe(std::uint32_t slot) const;
  const Observation* observations(std::uint32_t slot) const;
  std::uint32_t observation_count(std::uint32_t slot) const;
  // A number given to the keyframe in `slot` by add_keyframe, unique in the
  // process, and kept by copy_keyframe (unless the copy drops the keyframe's
  // point quality, into a window without hold_quality: then a new one): two
  // slots (of this or any other Window) with the same stamp hold the same
  // keyframe, observations and quality, so
  // a consumer that saw the stamp before can skip comparing the contents.
  // Different stamps say nothing (the same contents may be added twice).
  std::uint64_t keyframe_stamp(std::uint32_t slot) const;
  std::uint32_t total_observations() const;
  std::uint32_t total_unmapped() const;  // unmapped keypoints over the window
  std::uint32_t distinct_points() const;
  // Window keyframes observing `point` (0: not in the window).
  std::uint32_t point_views(PointId point) const;
  // The point -> pair arcs of the window's network: the sum over its points
  // of n(n-1)/2, n = point_views (what Capacities::max_pair_arcs must hold).
  std::uint64_t pair_arcs() const;
  // Slot of a keyframe id, or -1.
  std::int32_t find_keyframe(KeyframeId id) const;

  const Capacities& capacities() const;
  std::size_t memory_bytes() const;

 private:
  // add_keyframe with the given stamp (0: a new one); `slide`: in place of
  // the oldest keyframe.
  Status add(const Keyframe& keyframe, const Observation* observations, std::uint32_t count,
             std::uint64_t stamp, bool slide);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace keepless::core
