#pragma once
// The node's window of the last K keyframes, double-buffered so every edit is
// atomic: slides and dropped points are the window's own atomic edits, in
// place; an edit beyond them (evicting older keyframes to make room,
// applying a map event) is built into the spare window and swapped in only
// if it succeeded. All storage is sized at construction; no edit allocates.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "keepless/core/config.hpp"
#include "keepless/core/status.hpp"
#include "keepless/core/window.hpp"

namespace keepless::platform {

class SlidingWindow {
 public:
  // `capacities.max_keyframes` is K. `max_observations` bounds one keyframe's
  // observations; `max_event_ids` one list of a map edit.
  SlidingWindow(const core::Capacities& capacities, std::uint32_t max_observations,
                std::uint32_t max_event_ids);
  SlidingWindow(const SlidingWindow&) = delete;
  SlidingWindow& operator=(const SlidingWindow&) = delete;

  const core::Window& window() const { return *active_; }
  std::uint32_t max_keyframes() const { return capacities_.max_keyframes; }

  // What a window holds, or would hold.
  struct Demand {
    std::uint64_t keyframes = 0, points = 0, observations = 0, unmapped = 0;
  };

  // Adds a keyframe, first dropping the oldest when K are held. When the
  // window's points, observations or unmapped keypoints cannot hold it as
  // well, older keyframes go too, oldest first, until they can, so a window
  // beyond capacity never stops the stream: `*evicted` (if given) counts
  // them, beyond the usual slide, and overflow() says what the window would
  // have needed. On any error (a keyframe beyond the window on its own
  // included) the window is unchanged.
  [[nodiscard]] core::Status push(const core::Keyframe& keyframe, const core::Observation* observations,
                                  std::uint32_t count, std::uint32_t* evicted = nullptr);
  // The window the last push that evicted would have made: the usual slide
  // plus the new keyframe.
  const Demand& overflow() const { return overflow_; }

  // Drops every observation of these points (any order, at most the window's
  // point capacity).
  [[nodiscard]] core::Status drop_points(const core::PointId* points, std::uint32_t count);

  // Deletes points, merges points (from[i] -> into[i]; a keyframe left with
  // two observations of one point keeps the first in its order), removes
  // keyframes. Inputs as split by split_map_event (the valid items). Atomic.
  struct Edit {
    const core::PointId* deleted = nullptr;
    std::uint32_t deleted_count = 0;
    const core::PointId* merged_from = nullptr;
    const core::PointId* merged_into = nullptr;
    std::uint32_t merged_count = 0;
    const core::KeyframeId* removed = nullptr;
    std::uint32_t removed_count = 0;
  };
  [[nodiscard]] core::Status edit(const Edit& edit);
  // Of the last successful edit's merges, those whose source the window
  // held (the others changed nothing).
  std::uint32_t merges_effective() const { return merges_effective_; }

  void clear();
  std::size_t memory_bytes() const;

 private:
  struct Merge {
    core::PointId from;
    core::PointId into;
    bool used;  // the window held `from`
  };
  // Copies the active window into the spare, minus `skip_slots` slots from the
  // front, minus removed keyframes, with point ids mapped through the sorted
  // drop/merge tables; then appends `extra` if given. Swaps on success.
  [[nodiscard]] core::Status rebuild(std::uint32_t skip_front, const core::KeyframeId* removed,
                                     std::uint32_t removed_count, std::uint32_t drop_count,
                                     std::uint32_t merge_count, const core::Keyframe* extra,
                                     const core::Observation* extra_observations, std::uint32_t extra_count);

  // What the usual slide (dropping `skip_front` keyframes) plus this keyframe
  // would hold.
  Demand demand(std::uint32_t skip_front, const core::Keyframe& keyframe, const core::Observation* observations,
                std::uint32_t count);

  core::Capacities capacities_;
  Demand overflow_;
  core::Window a_;
  core::Window b_;
  core::Window* active_;
  core::Window* spare_;
  std::vector<core::Observation> obs_scratch_;      // one keyframe
  std::vector<std::uint32_t> order_scratch_;        // one keyframe, for de-duplication
  std::vector<std::uint8_t> keep_scratch_;
  std::vector<std::uint8_t> tracked_scratch_;       // one keyframe's tracked flags, beside obs_scratch_
  std::vector<core::PointQuality> quality_scratch_;  // one keyframe's point quality, beside obs_scratch_
  std::vector<core::PointId> drop_table_;           // sorted
  std::vector<Merge> merge_table_;                  // sorted by from
  std::uint32_t merges_effective_ = 0;
};

}  // namespace keepless::platform
