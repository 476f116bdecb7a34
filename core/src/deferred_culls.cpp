#include "keepless/core/deferred_culls.hpp"

#include <algorithm>
#include <vector>

#include "id_table.hpp"

namespace keepless::core {

// Dense arrays of the held points (id, last match) and an id -> index table;
// removal moves the last entry into the hole, so every pass is over size().
struct DeferredCulls::Impl {
  Impl(std::uint32_t capacity, std::uint32_t t) : index(capacity), ids(capacity), last(capacity), defer(t) {}

  // A point not held: held from this tick, or refused when the table is full.
  Status add(PointId point) {
    if (index.insert(point, size) == nullptr) {
      ++refused;
      return Status::kCapacityExceeded;
    }
    ids[size] = point;
    last[size] = clock;
    ++size;
    return Status::kOk;
  }

  void remove_at(std::uint32_t i) {
    const std::uint32_t back = size - 1;
    (void)index.erase(ids[i]);
    if (i != back) {
      ids[i] = ids[back];
      last[i] = last[back];
      *index.find(ids[i]) = i;
    }
    size = back;
  }

  IdTable index;
  std::vector<PointId> ids;
  std::vector<std::uint64_t> last;
  std::uint32_t size = 0;
  std::uint32_t defer = 0;
  std::uint64_t clock = 0;
  std::uint64_t refused = 0;
};

DeferredCulls::DeferredCulls(std::uint32_t capacity, std::uint32_t defer_keyframes)
    : impl_(std::make_unique<Impl>(capacity, defer_keyframes)) {}
DeferredCulls::~DeferredCulls() = default;

void DeferredCulls::begin_keyframe() { ++impl_->clock; }

bool DeferredCulls::observe(PointId point, bool matched) {
  const std::uint32_t* i = impl_->index.find(point);
  if (i == nullptr) return false;
  if (matched) impl_->last[*i] = impl_->clock;
  return true;
}

Status DeferredCulls::exclude(PointId point) {
  return contains(point) ? Status::kOk : impl_->add(point);
}

std::uint32_t DeferredCulls::expire(PointId* out) {
  Impl& d = *impl_;
  std::uint32_t n = 0;
  for (std::uint32_t i = 0; i < d.size;) {
    if (d.clock - d.last[i] >= d.defer) {
      out[n++] = d.ids[i];
      d.remove_at(i);  // the last entry moved into i: look at i again
    } else {
      ++i;
    }
  }
  std::sort(out, out + n);
  return n;
}

std::uint32_t DeferredCulls::defer(const PointId* culled, std::uint32_t n, PointId* excluded,
                                   std::uint32_t* excluded_count, PointId* deleted) {
  std::uint32_t kept = 0, refused = 0;
  for (std::uint32_t i = 0; i < n; ++i) {
    if (contains(culled[i])) continue;  // held already, or a repeat in `culled`: listed once
    if (impl_->add(culled[i]) == Status::kOk) {
      excluded[kept++] = culled[i];
    } else {
      deleted[refused++] = culled[i];
    }
  }
  *excluded_count = kept;
  // A refused id repeated in `culled` is deleted and counted once.
  std::sort(deleted, deleted + refused);
  const auto distinct = static_cast<std::uint32_t>(std::unique(deleted, deleted + refused) - deleted);
  impl_->refused -= refused - distinct;
  const std::uint32_t total = distinct + expire(deleted + distinct);
  std::sort(deleted, deleted + total);  // (inplace_merge may allocate)
  return total;
}

bool DeferredCulls::merge(PointId from, PointId into, bool from_in_window) {
  Impl& d = *impl_;
  const std::uint32_t* i = d.index.find(into);
  if (i == nullptr) return false;
  if (const std::uint32_t* f = d.index.find(from); f != nullptr && f != i) {
    d.last[*i] = std::max(d.last[*i], d.last[*f]);
    d.remove_at(*f);
  } else if (from_in_window) {
    d.last[*i] = d.clock;
  }
  return true;
}

bool DeferredCulls::forget(PointId point) {
  const std::uint32_t* i = impl_->index.find(point);
  if (i == nullptr) return false;
  impl_->remove_at(*i);
  return true;
}

bool DeferredCulls::contains(PointId point) const { return impl_->index.find(point) != nullptr; }

void DeferredCulls::clear() {
  impl_->index.clear();
  impl_->size = 0;
}

std::uint32_t DeferredCulls::size() const { return impl_->size; }
std::uint32_t DeferredCulls::capacity() const { return impl_->index.capacity(); }
std::uint32_t DeferredCulls::defer_keyframes() const { return impl_->defer; }
std::uint64_t DeferredCulls::refused() const { return impl_->refused; }
std::uint64_t DeferredCulls::tick() const { return impl_->clock; }
std::size_t DeferredCulls::memory_bytes() const {
  return sizeof(Impl) + impl_->index.memory_bytes() + impl_->ids.capacity() * sizeof(PointId) +
         impl_->last.capacity() * sizeof(std::uint64_t);
}

}  // namespace keepless::core
