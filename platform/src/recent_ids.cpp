#include "keepless/platform/recent_ids.hpp"

#include <algorithm>
#include <limits>

namespace keepless::platform {

namespace {

constexpr std::size_t kNone = ~std::size_t{0};

// splitmix64's finaliser: point ids are often dense counters.
std::uint64_t mix(std::uint64_t x) {
  x ^= x >> 30;
  x *= 0xbf58476d1ce4e5b9ull;
  x ^= x >> 27;
  x *= 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

}  // namespace

RecentIds::RecentIds(std::uint32_t capacity) : capacity_(capacity) {
  // Load factor <= 1/2. Sized in 64 bits: with a 32-bit size_t, 2 * capacity
  // wraps from 2^31 on and the doubling never ended; a table beyond the
  // address space saturates and the vector refuses it (length_error).
  std::uint64_t slots = 2;
  while (slots < 2 * std::uint64_t{capacity}) slots <<= 1;
  const auto size = static_cast<std::size_t>(std::min<std::uint64_t>(slots, std::numeric_limits<std::size_t>::max()));
  table_.assign(size, 0);
  used_.assign(size, 0);
  ring_.assign(capacity, 0);
  mask_ = size - 1;
}

std::size_t RecentIds::memory_bytes() const {
  return table_.size() * sizeof(std::uint64_t) + used_.size() + ring_.size() * sizeof(std::uint64_t);
}

std::size_t RecentIds::slot_of(std::uint64_t id) const {
  // Bounded: the table is never full, so an empty slot ends every probe.
  for (std::size_t i = mix(id) & mask_, n = 0; n <= mask_; i = (i + 1) & mask_, ++n) {
    if (!used_[i]) return kNone;
    if (table_[i] == id) return i;
  }
  return kNone;
}

bool RecentIds::contains(std::uint64_t id) const { return capacity_ > 0 && slot_of(id) != kNone; }

void RecentIds::erase(std::uint64_t id) {
  std::size_t hole = slot_of(id);
  if (hole == kNone) return;
  used_[hole] = 0;
  // Backward shift: move later members of the probe run into the hole.
  for (std::size_t i = (hole + 1) & mask_; used_[i]; i = (i + 1) & mask_) {
    const std::size_t home = mix(table_[i]) & mask_;
    // Movable iff its home is not cyclically within (hole, i].
    const bool stays = hole <= i ? (hole < home && home <= i) : (hole < home || home <= i);
    if (stays) continue;
    table_[hole] = table_[i];
    used_[hole] = 1;
    used_[i] = 0;
    hole = i;
  }
}

void RecentIds::insert(std::uint64_t id) {
  if (capacity_ == 0 || slot_of(id) != kNone) return;
  if (size_ == capacity_) {
    erase(ring_[head_]);
    head_ = (head_ + 1) % capacity_;
    --size_;
  }
  std::size_t i = mix(id) & mask_;
  while (used_[i]) i = (i + 1) & mask_;
  table_[i] = id;
  used_[i] = 1;
  ring_[(head_ + size_) % capacity_] = id;
  ++size_;
}

void RecentIds::clear() {
  std::fill(used_.begin(), used_.end(), std::uint8_t{0});
  size_ = 0;
  head_ = 0;
}

}  // namespace keepless::platform
