#include "keepless/core/window.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <vector>

#include "id_table.hpp"

namespace keepless::core {

namespace {

bool finite(const double* x, int n) {
  for (int i = 0; i < n; ++i) {
    if (!std::isfinite(x[i])) return false;
  }
  return true;
}

// Keyframe stamps, unique in the process (see Window::keyframe_stamp); 64
// bits do not wrap in any process's life.
std::atomic<std::uint64_t> next_stamp{1};

}  // namespace

struct Window::Impl {
  Capacities caps;
  std::vector<Keyframe> keyframes;       // [max_keyframes], insertion order
  std::vector<std::uint64_t> stamps;     // [max_keyframes]
  std::vector<std::uint32_t> obs_begin;  // [max_keyframes]
  std::vector<std::uint32_t> obs_count;  // [max_keyframes]
  std::vector<Observation> pool;         // [max_observations], contiguous in slot order
  std::vector<PointId> scratch;          // [keyframe_observation_limit], duplicate check
  std::vector<std::uint8_t> tracked;     // [max_observations], beside pool (Keyframe::tracked)
  std::vector<PointQuality> quality;     // [max_observations], beside pool (Keyframe::quality)
  std::vector<Keypoint> unmapped;        // [max_unmapped_keypoints], contiguous in slot order
  IdTable views;                         // distinct point -> keyframes observing it
  std::uint32_t count = 0;               // keyframes
  std::uint32_t total = 0;               // observations
  std::uint32_t unmapped_total = 0;      // unmapped keypoints

  explicit Impl(const Capacities& c) : caps(c), views(c.max_points) {
    keyframes.resize(c.max_keyframes);
    stamps.resize(c.max_keyframes);
    obs_begin.resize(c.max_keyframes);
    obs_count.resize(c.max_keyframes);
    pool.resize(c.max_observations);
    scratch.resize(keyframe_observation_limit(c));
    tracked.resize(c.max_observations);
    if (c.hold_quality) quality.resize(c.max_observations);
    unmapped.resize(c.max_unmapped_keypoints);
  }

  // Keyframes point at their unmapped keypoints in `unmapped`, in slot order.
  void relink_unmapped() {
    std::uint32_t at = 0;
    for (std::uint32_t s = 0; s < count; ++s) {
      keyframes[s].unmapped = keyframes[s].unmapped_count > 0 ? unmapped.data() + at : nullptr;
      at += keyframes[s].unmapped_count;
    }
  }

  // Removes the keyframe in `slot`, compacting the pool and the keyframe
  // list so both stay in slot order.
  void remove(std::uint32_t slot) {
    const std::uint32_t begin = obs_begin[slot];
    const std::uint32_t n = obs_count[slot];
    for (std::uint32_t i = 0; i < n; ++i) remove_view(pool[begin + i].point);
    const std::uint32_t tail = total - begin - n;
    if (tail > 0) {
      std::memmove(pool.data() + begin, pool.data() + begin + n, tail * sizeof(Observation));
      std::memmove(tracked.data() + begin, tracked.data() + begin + n, tail);
      if (caps.hold_quality) {
        std::memmove(quality.data() + begin, quality.data() + begin + n, tail * sizeof(PointQuality));
      }
    }
    const std::uint32_t dropped = keyframes[slot].unmapped_count;
    if (dropped > 0) {
      const auto from = static_cast<std::size_t>(keyframes[slot].unmapped - unmapped.data());
      std::memmove(unmapped.data() + from, unmapped.data() + from + dropped,
                   (unmapped_total - from - dropped) * sizeof(Keypoint));
      unmapped_total -= dropped;
    }
    for (std::uint32_t s = slot; s + 1 < count; ++s) {
      keyframes[s] = keyframes[s + 1];
      stamps[s] = stamps[s + 1];
      obs_begin[s] = obs_begin[s + 1] - n;
      obs_count[s] = obs_count[s + 1];
      relink_observations(s);
    }
    total -= n;
    --count;
    if (dropped > 0) relink_unmapped();
  }

  // Keyframe `slot`'s tracked flags and quality (if it has them) at its
  // observations' place in the pool.
  void relink_observations(std::uint32_t s) {
    if (keyframes[s].tracked != nullptr) keyframes[s].tracked = tracked.data() + obs_begin[s];
    if (keyframes[s].quality != nullptr) keyframes[s].quality = quality.data() + obs_begin[s];
  }

  bool contains(PointId point) const { return views.find(point) != nullptr; }

  // Callers check the point capacity first, so the insertion cannot fail.
  void add_view(PointId point) {
    if (std::uint32_t* v = views.insert(point, 0)) ++*v;
  }

  void remove_view(PointId point) {
    std::uint32_t* v = views.find(point);
    if (v != nullptr && --*v == 0) views.erase(point);
  }
};

Window::Window(const Capacities& capacities) : impl_(std::make_unique<Impl>(capacities)) {}
Window::~Window() = default;

Status Window::add_keyframe(const Keyframe& keyframe, const Observation* observations,
                            std::uint32_t count) {
  return add(keyframe, observations, count, 0, false);
}

Status Window::slide(const Keyframe& keyframe, const Observation* observations, std::uint32_t count) {
  return add(keyframe, observations, count, 0, true);
}

Status Window::copy_keyframe(const Window& from, std::uint32_t slot) {
  if (slot >= from.keyframe_count()) return Status::kInvalidArgument;
  return add(from.keyframe(slot), from.observations(slot), from.observation_count(slot),
             from.keyframe_stamp(slot), false);
}

Status Window::add(const Keyframe& keyframe, const Observation* observations, std::uint32_t count,
                   std::uint64_t stamp, bool slide) {
  Impl& w = *impl_;
  if (slide && w.count == 0) return Status::kInvalidArgument;
  // Validate everything first, against what stays (all but the oldest when
  // sliding); commit only when nothing can fail.
  const std::uint32_t staying = w.count - (slide ? 1 : 0);
  const std::uint32_t total = w.total - (slide ? w.obs_count[0] : 0);
  const std::uint32_t unmapped_total = w.unmapped_total - (slide ? w.keyframes[0].unmapped_count : 0);
  if (staying >= w.caps.max_keyframes) return Status::kCapacityExceeded;
  if (count > w.caps.max_observations - total || count > w.scratch.size()) {
    return Status::kCapacityExceeded;
  }
  if (count > 0 && observations == nullptr) return Status::kInvalidArgument;
  if (keyframe.unmapped_count > w.caps.max_unmapped_keypoints - unmapped_total) {
    return Status::kCapacityExceeded;
  }
  if (keyframe.unmapped_count > 0 && keyframe.unmapped == nullptr) return Status::kInvalidArgument;
  const double intrinsics[4] = {keyframe.fx, keyframe.fy, keyframe.cx, keyframe.cy};
  if (!finite(keyframe.centre, 3) || !finite(keyframe.orientation, 4) || !finite(intrinsics, 4)) {
    return Status::kInvalidArgument;
  }
  for (std::uint32_t i = 0; i < count; ++i) {
    if (!std::isfinite(observations[i].u) || !std::isfinite(observations[i].v) ||
        !std::isfinite(observations[i].depth)) {
      return Status::kInvalidArgument;
    }
  }
  for (std::uint32_t i = 0; keyframe.quality != nullptr && i < count; ++i) {
    if (!std::isfinite(keyframe.quality[i].reprojection_error) ||
        !std::isfinite(keyframe.quality[i].triangulation_angle)) {
      return Status::kInvalidArgument;
    }
  }
  for (std::uint32_t i = 0; i < keyframe.unmapped_count; ++i) {
    if (!std::isfinite(keyframe.unmapped[i].u) || !std::isfinite(keyframe.unmapped[i].v)) {
      return Status::kInvalidArgument;
    }
  }
  if (find_keyframe(keyframe.id) >= 0) return Status::kDuplicateKeyframe;

  PointId* ids = w.scratch.data();
  for (std::uint32_t i = 0; i < count; ++i) ids[i] = observations[i].point;
  std::sort(ids, ids + count);
  std::uint32_t fresh = 0;
  for (std::uint32_t i = 0; i < count; ++i) {
    if (i > 0 && ids[i] == ids[i - 1]) return Status::kDuplicateObservation;
    if (!w.contains(ids[i])) ++fresh;
  }
  std::uint32_t points = w.views.size();
  if (slide) {
    // The oldest's points seen by it alone leave; those this keyframe sees
    // come back as fresh ones.
    const Observation* old = w.pool.data() + w.obs_begin[0];
    for (std::uint32_t i = 0; i < w.obs_count[0]; ++i) {
      if (point_views(old[i].point) != 1) continue;
      --points;
      if (std::binary_search(ids, ids + count, old[i].point)) ++fresh;
    }
  }
  if (fresh > w.caps.max_points - points) return Status::kCapacityExceeded;

  if (slide) w.remove(0);
  const std::uint32_t slot = w.count;
  w.keyframes[slot] = keyframe;
  // A stamp vouches for what this window holds: a copy that drops the
  // quality (hold_quality off) holds other contents, so it gets a new stamp.
  const bool drops_quality = count > 0 && keyframe.quality != nullptr && !w.caps.hold_quality;
  w.stamps[slot] = stamp != 0 && !drops_quality ? stamp : next_stamp.fetch_add(1, std::memory_order_relaxed);
  w.obs_begin[slot] = w.total;
  w.obs_count[slot] = count;
  if (count > 0) std::memcpy(w.pool.data() + w.total, observations, count * sizeof(Observation));
  if (count > 0 && keyframe.tracked != nullptr) {
    std::memcpy(w.tracked.data() + w.total, keyframe.tracked, count);
    w.keyframes[slot].tracked = w.tracked.data() + w.total;
  } else {
    w.keyframes[slot].tracked = nullptr;
  }
  if (count > 0 && keyframe.quality != nullptr && w.caps.hold_quality) {
    std::memcpy(w.quality.data() + w.total, keyframe.quality, count * sizeof(PointQuality));
    w.keyframes[slot].quality = w.quality.data() + w.total;
  } else {
    w.keyframes[slot].quality = nullptr;
  }
  for (std::uint32_t i = 0; i < count; ++i) w.add_view(observations[i].point);
  w.total += count;
  if (keyframe.unmapped_count > 0) {
    std::memcpy(w.unmapped.data() + w.unmapped_total, keyframe.unmapped,
                keyframe.unmapped_count * sizeof(Keypoint));
    w.keyframes[slot].unmapped = w.unmapped.data() + w.unmapped_total;
    w.unmapped_total += keyframe.unmapped_count;
  } else {
    w.keyframes[slot].unmapped = nullptr;
  }
  ++w.count;
  return Status::kOk;
}

Status Window::remove_keyframe(KeyframeId id) {
  const std::int32_t found = find_keyframe(id);
  if (found < 0) return Status::kUnknownKeyframe;
  impl_->remove(static_cast<std::uint32_t>(found));
  return Status::kOk;
}

Status Window::remove_points(const PointId* sorted_points, std::uint32_t count) {
  if (count == 0) return Status::kOk;
  if (sorted_points == nullptr) return Status::kInvalidArgument;
  for (std::uint32_t i = 1; i < count; ++i) {
    if (sorted_points[i] < sorted_points[i - 1]) return Status::kInvalidArgument;
  }
  Impl& w = *impl_;
  // Compact the pool (and the arrays beside it) in one pass, in slot order.
  std::uint32_t at = 0;
  for (std::uint32_t s = 0; s < w.count; ++s) {
    const std::uint32_t begin = w.obs_begin[s];
    const std::uint32_t n = w.obs_count[s];
    w.obs_begin[s] = at;
    for (std::uint32_t i = begin; i < begin + n; ++i) {
      const PointId p = w.pool[i].point;
      if (std::binary_search(sorted_points, sorted_points + count, p)) {
        w.remove_view(p);
        continue;
      }
      w.pool[at] = w.pool[i];
      w.tracked[at] = w.tracked[i];
      if (w.caps.hold_quality) w.quality[at] = w.quality[i];
      ++at;
    }
    const std::uint32_t kept = at - w.obs_begin[s];
    if (kept != n) {
      w.obs_count[s] = kept;
      w.stamps[s] = next_stamp.fetch_add(1, std::memory_order_relaxed);
    }
    if (kept == 0) {  // as add_keyframe holds a keyframe without observations
      w.keyframes[s].tracked = nullptr;
      w.keyframes[s].quality = nullptr;
    }
    w.relink_observations(s);
  }
  w.total = at;
  return Status::kOk;
}

void Window::clear() {
  Impl& w = *impl_;
  w.views.clear();
  w.count = 0;
  w.total = 0;
  w.unmapped_total = 0;
}

std::uint32_t Window::keyframe_count() const { return impl_->count; }
const Keyframe& Window::keyframe(std::uint32_t slot) const { return impl_->keyframes[slot]; }
const Observation* Window::observations(std::uint32_t slot) const {
  return impl_->pool.data() + impl_->obs_begin[slot];
}
std::uint32_t Window::observation_count(std::uint32_t slot) const { return impl_->obs_count[slot]; }
std::uint32_t Window::total_observations() const { return impl_->total; }
std::uint32_t Window::total_unmapped() const { return impl_->unmapped_total; }
std::uint32_t Window::distinct_points() const { return impl_->views.size(); }

std::uint32_t Window::point_views(PointId point) const {
  const std::uint32_t* v = impl_->views.find(point);
  return v != nullptr ? *v : 0;
}

std::uint64_t Window::pair_arcs() const {
  // Each observation of a point seen n times adds n - 1: n(n - 1) per point.
  const Impl& w = *impl_;
  std::uint64_t twice = 0;
  for (std::uint32_t s = 0; s < w.count; ++s) {
    const Observation* obs = w.pool.data() + w.obs_begin[s];
    for (std::uint32_t i = 0; i < w.obs_count[s]; ++i) twice += point_views(obs[i].point) - 1;
  }
  return twice / 2;
}
std::uint64_t Window::keyframe_stamp(std::uint32_t slot) const { return impl_->stamps[slot]; }

std::int32_t Window::find_keyframe(KeyframeId id) const {
  for (std::uint32_t s = 0; s < impl_->count; ++s) {
    if (impl_->keyframes[s].id == id) return static_cast<std::int32_t>(s);
  }
  return -1;
}

const Capacities& Window::capacities() const { return impl_->caps; }

std::size_t Window::memory_bytes() const {
  const Impl& w = *impl_;
  return sizeof(Window) + sizeof(Impl) + w.keyframes.capacity() * sizeof(Keyframe) +
         w.stamps.capacity() * sizeof(std::uint64_t) +
         (w.obs_begin.capacity() + w.obs_count.capacity()) * sizeof(std::uint32_t) +
         w.pool.capacity() * sizeof(Observation) + w.scratch.capacity() * sizeof(PointId) +
         w.tracked.capacity() + w.quality.capacity() * sizeof(PointQuality) +
         w.unmapped.capacity() * sizeof(Keypoint) +
         w.views.memory_bytes();
}

}  // namespace keepless::core
