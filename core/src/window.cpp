#include "keepless/core/window.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "id_hash.hpp"

namespace keepless::core {

namespace {

bool finite(const double* x, int n) {
  for (int i = 0; i < n; ++i) {
    if (!std::isfinite(x[i])) return false;
  }
  return true;
}

}  // namespace

struct Window::Impl {
  // Distinct points with the number of window keyframes observing each: open
  // addressing with linear probing, load <= 1/2, backward-shift deletion (no
  // tombstones, so probe lengths never degrade as the window slides).
  struct Slot {
    PointId point;
    std::uint32_t views;  // 0 = empty
  };

  Capacities caps;
  std::vector<Keyframe> keyframes;           // [max_keyframes], insertion order
  std::vector<std::uint32_t> obs_begin;      // [max_keyframes]
  std::vector<std::uint32_t> obs_count;      // [max_keyframes]
  std::vector<Observation> pool;             // [max_observations], contiguous in slot order
  std::vector<PointId> scratch;              // [max_observations], duplicate check
  std::vector<Slot> table;                   // power of two >= 2 * max_points
  std::uint64_t mask = 0;
  std::uint32_t count = 0;    // keyframes
  std::uint32_t total = 0;    // observations
  std::uint32_t distinct = 0; // points

  explicit Impl(const Capacities& c) : caps(c) {
    keyframes.resize(c.max_keyframes);
    obs_begin.resize(c.max_keyframes);
    obs_count.resize(c.max_keyframes);
    pool.resize(c.max_observations);
    scratch.resize(c.max_observations);
    std::uint64_t size = 2;
    while (size < 2ULL * c.max_points) size <<= 1;
    table.assign(size, Slot{0, 0});
    mask = size - 1;
  }

  // Index of `point` or of the empty slot where it would go. The table is never
  // full (load <= 1/2), so the probe ends within table.size() steps.
  std::uint64_t probe(PointId point) const {
    std::uint64_t i = mix(point) & mask;
    for (std::uint64_t step = 0; step <= mask; ++step) {
      if (table[i].views == 0 || table[i].point == point) return i;
      i = (i + 1) & mask;
    }
    return i;  // unreachable while load <= 1/2
  }

  bool contains(PointId point) const { return table[probe(point)].views != 0; }

  void add_view(PointId point) {
    Slot& s = table[probe(point)];
    if (s.views == 0) {
      s.point = point;
      ++distinct;
    }
    ++s.views;
  }

  void remove_view(PointId point) {
    std::uint64_t i = probe(point);
    if (table[i].views == 0) return;  // not present: cannot happen
    if (--table[i].views != 0) return;
    --distinct;
    // Backward-shift deletion: pull later members of the cluster into the hole
    // when their home position allows it.
    std::uint64_t hole = i;
    std::uint64_t j = i;
    for (std::uint64_t step = 0; step <= mask; ++step) {
      j = (j + 1) & mask;
      if (table[j].views == 0) break;
      const std::uint64_t home = mix(table[j].point) & mask;
      // Move j into the hole unless its home lies cyclically in (hole, j].
      const bool home_between =
          hole <= j ? (hole < home && home <= j) : (hole < home || home <= j);
      if (!home_between) {
        table[hole] = table[j];
        hole = j;
      }
    }
    table[hole].views = 0;
  }
};

Window::Window(const Capacities& capacities) : impl_(std::make_unique<Impl>(capacities)) {}
Window::~Window() = default;

Status Window::add_keyframe(const Keyframe& keyframe, const Observation* observations,
                            std::uint32_t count) {
  Impl& w = *impl_;
  // Validate everything first; commit only when nothing can fail.
  if (w.count >= w.caps.max_keyframes) return Status::kCapacityExceeded;
  if (count > w.caps.max_observations - w.total) return Status::kCapacityExceeded;
  if (count > 0 && observations == nullptr) return Status::kInvalidArgument;
  if (!finite(keyframe.centre, 3) || !finite(keyframe.orientation, 4)) {
    return Status::kInvalidArgument;
  }
  for (std::uint32_t i = 0; i < count; ++i) {
    if (!std::isfinite(observations[i].u) || !std::isfinite(observations[i].v)) {
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
  if (fresh > w.caps.max_points - w.distinct) return Status::kCapacityExceeded;

  const std::uint32_t slot = w.count;
  w.keyframes[slot] = keyframe;
  w.obs_begin[slot] = w.total;
  w.obs_count[slot] = count;
  if (count > 0) std::memcpy(w.pool.data() + w.total, observations, count * sizeof(Observation));
  for (std::uint32_t i = 0; i < count; ++i) w.add_view(observations[i].point);
  w.total += count;
  ++w.count;
  return Status::kOk;
}

Status Window::remove_keyframe(KeyframeId id) {
  Impl& w = *impl_;
  const std::int32_t found = find_keyframe(id);
  if (found < 0) return Status::kUnknownKeyframe;
  const auto slot = static_cast<std::uint32_t>(found);
  const std::uint32_t begin = w.obs_begin[slot];
  const std::uint32_t n = w.obs_count[slot];
  for (std::uint32_t i = 0; i < n; ++i) w.remove_view(w.pool[begin + i].point);
  // Compact the pool and the keyframe list so both stay in slot order.
  const std::uint32_t tail = w.total - begin - n;
  if (tail > 0) {
    std::memmove(w.pool.data() + begin, w.pool.data() + begin + n, tail * sizeof(Observation));
  }
  for (std::uint32_t s = slot; s + 1 < w.count; ++s) {
    w.keyframes[s] = w.keyframes[s + 1];
    w.obs_begin[s] = w.obs_begin[s + 1] - n;
    w.obs_count[s] = w.obs_count[s + 1];
  }
  w.total -= n;
  --w.count;
  return Status::kOk;
}

void Window::clear() {
  Impl& w = *impl_;
  std::fill(w.table.begin(), w.table.end(), Impl::Slot{0, 0});
  w.count = 0;
  w.total = 0;
  w.distinct = 0;
}

std::uint32_t Window::keyframe_count() const { return impl_->count; }
const Keyframe& Window::keyframe(std::uint32_t slot) const { return impl_->keyframes[slot]; }
const Observation* Window::observations(std::uint32_t slot) const {
  return impl_->pool.data() + impl_->obs_begin[slot];
}
std::uint32_t Window::observation_count(std::uint32_t slot) const { return impl_->obs_count[slot]; }
std::uint32_t Window::total_observations() const { return impl_->total; }
std::uint32_t Window::distinct_points() const { return impl_->distinct; }

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
         (w.obs_begin.capacity() + w.obs_count.capacity()) * sizeof(std::uint32_t) +
         w.pool.capacity() * sizeof(Observation) + w.scratch.capacity() * sizeof(PointId) +
         w.table.capacity() * sizeof(Impl::Slot);
}

}  // namespace keepless::core
