#pragma once
// A fixed-capacity memory of the last N distinct ids inserted (FIFO
// eviction), with O(1) membership: the node's memory of the points it culled
// recently, so a keyframe the VO sent before it could apply a decision cannot
// bring those points back. Storage is sized at construction; insert/contains
// allocate nothing.

#include <cstddef>
#include <cstdint>
#include <vector>

namespace keepless::platform {

class RecentIds {
 public:
  explicit RecentIds(std::uint32_t capacity);

  // Remembers `id` (a no-op if already held); the oldest id leaves when full.
  void insert(std::uint64_t id);
  bool contains(std::uint64_t id) const;
  void clear();

  std::uint32_t size() const { return size_; }
  std::uint32_t capacity() const { return capacity_; }
  std::size_t memory_bytes() const;

 private:
  std::size_t slot_of(std::uint64_t id) const;  // the table slot holding id, or npos
  void erase(std::uint64_t id);

  // Open addressing, linear probing, backward-shift deletion; a parallel
  // `used_` flag so every 64-bit id (0 included) is storable.
  std::vector<std::uint64_t> table_;
  std::vector<std::uint8_t> used_;
  std::vector<std::uint64_t> ring_;  // insertion order
  std::uint32_t capacity_ = 0;
  std::uint32_t size_ = 0;
  std::uint32_t head_ = 0;  // oldest entry of ring_
  std::size_t mask_ = 0;
};

}  // namespace keepless::platform
