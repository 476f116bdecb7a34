#include "keepless/platform/sliding_window.hpp"

#include <algorithm>

namespace keepless::platform {

SlidingWindow::SlidingWindow(const core::Capacities& capacities, std::uint32_t max_observations,
                             std::uint32_t max_event_ids)
    : capacities_(capacities), a_(capacities), b_(capacities), active_(&a_), spare_(&b_) {
  // A window keyframe never holds more than one message's observations.
  obs_scratch_.resize(max_observations);
  order_scratch_.resize(max_observations);
  keep_scratch_.resize(max_observations);
  tracked_scratch_.resize(max_observations);
  quality_scratch_.resize(max_observations);
  drop_table_.resize(std::max<std::size_t>(max_event_ids, capacities.max_points));
  merge_table_.resize(max_event_ids);
}

void SlidingWindow::clear() {
  active_->clear();
  spare_->clear();
}

std::size_t SlidingWindow::memory_bytes() const {
  return a_.memory_bytes() + b_.memory_bytes() + obs_scratch_.size() * sizeof(core::Observation) +
         order_scratch_.size() * sizeof(std::uint32_t) + keep_scratch_.size() + tracked_scratch_.size() +
         quality_scratch_.size() * sizeof(core::PointQuality) + drop_table_.size() * sizeof(core::PointId) +
         merge_table_.size() * sizeof(Merge);
}

core::Status SlidingWindow::push(const core::Keyframe& keyframe, const core::Observation* observations,
                                 std::uint32_t count, std::uint32_t* evicted) {
  if (evicted != nullptr) *evicted = 0;
  if (count > obs_scratch_.size()) return core::Status::kCapacityExceeded;
  const std::uint32_t slide = active_->keyframe_count() < capacities_.max_keyframes ? 0 : 1;
  if (active_->find_keyframe(keyframe.id) >= 0) return core::Status::kDuplicateKeyframe;
  // Full: the new keyframe replaces the oldest (both atomic by contract).
  core::Status s = slide == 0 ? active_->add_keyframe(keyframe, observations, count)
                              : active_->slide(keyframe, observations, count);
  if (s != core::Status::kCapacityExceeded) return s;
  // Beyond the window's points, observations or unmapped keypoints: older
  // keyframes make room (at most every one), unless it cannot fit alone.
  if (count > capacities_.max_observations || count > capacities_.max_points ||
      keyframe.unmapped_count > capacities_.max_unmapped_keypoints) {
    return s;
  }
  const Demand need = demand(slide, keyframe, observations, count);
  const std::uint32_t held = active_->keyframe_count();
  for (std::uint32_t skip = slide + 1; skip <= held && s == core::Status::kCapacityExceeded; ++skip) {
    s = rebuild(skip, nullptr, 0, 0, 0, &keyframe, observations, count);
    if (s == core::Status::kOk) {
      overflow_ = need;
      if (evicted != nullptr) *evicted = skip - slide;
    }
  }
  return s;
}

SlidingWindow::Demand SlidingWindow::demand(std::uint32_t skip_front, const core::Keyframe& keyframe,
                                            const core::Observation* observations, std::uint32_t count) {
  const core::Window& w = *active_;
  Demand d;
  d.keyframes = w.keyframe_count() - skip_front + 1;
  d.observations = w.total_observations() + std::uint64_t{count};
  d.unmapped = w.total_unmapped() + std::uint64_t{keyframe.unmapped_count};
  d.points = w.distinct_points();
  // The slid-out keyframe's points seen by it alone leave; the new
  // keyframe's points not in what stays come.
  const core::Observation* old = skip_front > 0 ? w.observations(0) : nullptr;
  const std::uint32_t old_count = skip_front > 0 ? w.observation_count(0) : 0;
  if (skip_front > 0) {
    d.observations -= old_count;
    d.unmapped -= w.keyframe(0).unmapped_count;
  }
  const bool sorted = old_count <= drop_table_.size();
  for (std::uint32_t i = 0; i < old_count; ++i) {
    if (w.point_views(old[i].point) == 1) --d.points;
    if (sorted) drop_table_[i] = old[i].point;
  }
  if (sorted) std::sort(drop_table_.begin(), drop_table_.begin() + old_count);
  const auto in_old = [&](core::PointId p) {
    if (sorted) return std::binary_search(drop_table_.begin(), drop_table_.begin() + old_count, p);
    return std::any_of(old, old + old_count, [p](const core::Observation& o) { return o.point == p; });
  };
  for (std::uint32_t i = 0; i < count; ++i) {
    const std::uint32_t views = w.point_views(observations[i].point);
    if (views == 0 || (views == 1 && old_count > 0 && in_old(observations[i].point))) ++d.points;
  }
  return d;
}

core::Status SlidingWindow::drop_points(const core::PointId* points, std::uint32_t count) {
  if (count == 0) return core::Status::kOk;
  if (count > drop_table_.size()) return core::Status::kCapacityExceeded;
  std::copy(points, points + count, drop_table_.begin());
  std::sort(drop_table_.begin(), drop_table_.begin() + count);
  return active_->remove_points(drop_table_.data(), count);
}

core::Status SlidingWindow::edit(const Edit& e) {
  if (e.deleted_count > drop_table_.size() || e.merged_count > merge_table_.size()) {
    return core::Status::kCapacityExceeded;
  }
  merges_effective_ = 0;
  if (e.deleted_count == 0 && e.merged_count == 0 && e.removed_count == 0) return core::Status::kOk;
  std::copy(e.deleted, e.deleted + e.deleted_count, drop_table_.begin());
  std::sort(drop_table_.begin(), drop_table_.begin() + e.deleted_count);
  for (std::uint32_t i = 0; i < e.merged_count; ++i) merge_table_[i] = {e.merged_from[i], e.merged_into[i], false};
  std::sort(merge_table_.begin(), merge_table_.begin() + e.merged_count,
            [](const Merge& x, const Merge& y) { return x.from < y.from; });
  const core::Status s = rebuild(0, e.removed, e.removed_count, e.deleted_count, e.merged_count, nullptr, nullptr, 0);
  if (s == core::Status::kOk) {
    for (std::uint32_t i = 0; i < e.merged_count; ++i) merges_effective_ += merge_table_[i].used ? 1 : 0;
  }
  return s;
}

core::Status SlidingWindow::rebuild(std::uint32_t skip_front, const core::KeyframeId* removed,
                                    std::uint32_t removed_count, std::uint32_t drop_count,
                                    std::uint32_t merge_count, const core::Keyframe* extra,
                                    const core::Observation* extra_observations, std::uint32_t extra_count) {
  core::Window& from = *active_;
  core::Window& to = *spare_;
  to.clear();
  const auto drop_begin = drop_table_.begin();
  const auto drop_end = drop_table_.begin() + drop_count;
  const auto merge_begin = merge_table_.begin();
  const auto merge_end = merge_table_.begin() + merge_count;

  const std::uint32_t keyframes = from.keyframe_count();
  for (std::uint32_t slot = skip_front; slot < keyframes; ++slot) {
    core::Keyframe kf = from.keyframe(slot);
    if (std::find(removed, removed + removed_count, kf.id) != removed + removed_count) continue;
    // Unchanged keyframes keep their stamps, so that the incremental network
    // knows them without comparing their observations.
    if (drop_count == 0 && merge_count == 0) {
      if (const core::Status s = to.copy_keyframe(from, slot); s != core::Status::kOk) {
        to.clear();
        return s;
      }
      continue;
    }
    const core::Observation* obs = from.observations(slot);
    const std::uint32_t n = from.observation_count(slot);
    if (n > obs_scratch_.size()) {
      to.clear();
      return core::Status::kCapacityExceeded;
    }
    std::uint32_t kept = 0;
    bool merged = false;
    // Tracked flags and quality follow their observations (the window copies them again).
    const std::uint8_t* tracked = kf.tracked;
    std::uint8_t* tracked_out = tracked_scratch_.data();
    const core::PointQuality* quality = kf.quality;
    core::PointQuality* quality_out = quality_scratch_.data();
    for (std::uint32_t i = 0; i < n; ++i) {
      core::Observation o = obs[i];
      if (drop_count > 0 && std::binary_search(drop_begin, drop_end, o.point)) continue;
      if (tracked != nullptr) tracked_out[kept] = tracked[i];
      if (quality != nullptr) quality_out[kept] = quality[i];
      if (merge_count > 0) {
        const auto it = std::lower_bound(merge_begin, merge_end, o.point,
                                         [](const Merge& m, core::PointId p) { return m.from < p; });
        if (it != merge_end && it->from == o.point) {
          o.point = it->into;
          it->used = true;
          merged = true;
        }
      }
      obs_scratch_[kept++] = o;
    }
    if (merged) {
      // Keep the first observation of each point in keyframe order.
      std::uint32_t* order = order_scratch_.data();
      std::uint8_t* keep = keep_scratch_.data();
      for (std::uint32_t i = 0; i < kept; ++i) {
        order[i] = i;
        keep[i] = 1;
      }
      std::sort(order, order + kept, [&](std::uint32_t x, std::uint32_t y) {
        const auto px = obs_scratch_[x].point, py = obs_scratch_[y].point;
        return px != py ? px < py : x < y;
      });
      for (std::uint32_t i = 1; i < kept; ++i) {
        if (obs_scratch_[order[i]].point == obs_scratch_[order[i - 1]].point) keep[order[i]] = 0;
      }
      std::uint32_t j = 0;
      for (std::uint32_t i = 0; i < kept; ++i) {
        if (!keep[i]) continue;
        tracked_out[j] = tracked_out[i];
        quality_out[j] = quality_out[i];
        obs_scratch_[j++] = obs_scratch_[i];
      }
      kept = j;
    }
    if (tracked != nullptr) kf.tracked = tracked_out;
    if (quality != nullptr) kf.quality = quality_out;
    const core::Status s = kept == n && !merged ? to.copy_keyframe(from, slot)
                                                : to.add_keyframe(kf, obs_scratch_.data(), kept);
    if (s != core::Status::kOk) {
      to.clear();
      return s;
    }
  }
  if (extra != nullptr) {
    const core::Status s = to.add_keyframe(*extra, extra_observations, extra_count);
    if (s != core::Status::kOk) {
      to.clear();
      return s;
    }
  }
  std::swap(active_, spare_);  // the old window is cleared when next reused
  return core::Status::kOk;
}

}  // namespace keepless::platform
