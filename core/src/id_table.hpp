#pragma once
// A map from 64-bit ids (points) to 32-bit values with a capacity fixed at
// construction, for the window's distinct points and the incremental
// network's point slots.
//
// Open addressing with linear probing over a power-of-two table of at least
// twice the capacity (load <= 1/2), from a fixed hash, so the layout is a
// function of the calls made. Deletion shifts later members of the cluster
// back (no tombstones), so probe lengths do not grow as ids come and go.
// Every probe is bounded by the table size; nothing allocates after the
// constructor.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace keepless::core {

class IdTable {
 public:
  // Room for `capacity` ids at once.
  explicit IdTable(std::uint32_t capacity) : capacity_(capacity) {
    // Sized in 64 bits: with a 32-bit size_t, 2 * capacity wraps from 2^31
    // on and the doubling reached 0 and never ended. A table beyond the
    // address space saturates, and the vector refuses it (length_error).
    std::uint64_t size = 2;
    while (size < 2 * std::uint64_t{capacity}) size <<= 1;
    slots_.assign(static_cast<std::size_t>(std::min<std::uint64_t>(size, std::numeric_limits<std::size_t>::max())),
                  Slot{});
    mask_ = slots_.size() - 1;
  }

  // splitmix64's finaliser: a fixed, platform-independent hash.
  static std::uint64_t mix(std::uint64_t x) {
    x += 0x9e3779b97f4a7c15ULL;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
    return x ^ (x >> 31);
  }

  // Starts loading the slot where a probe for `id` begins (a hint only).
  void prefetch(std::uint64_t id) const {
#if defined(__GNUC__)
    __builtin_prefetch(&slots_[mix(id) & mask_]);
#else
    (void)id;
#endif
  }

  // The value of `id`, or null.
  std::uint32_t* find(std::uint64_t id) { return at(probe(id)); }
  const std::uint32_t* find(std::uint64_t id) const {
    const Slot& s = slots_[probe(id)];
    return s.used ? &s.value : nullptr;
  }

  // Adds `id` with `value` unless it is present. Returns the id's value (the
  // old one if it was present), or null when capacity() ids are held already.
  std::uint32_t* insert(std::uint64_t id, std::uint32_t value) {
    const std::size_t i = probe(id);
    Slot& s = slots_[i];
    if (s.used) return &s.value;
    if (size_ >= capacity_) return nullptr;
    s = Slot{id, value, 1};
    ++size_;
    return &s.value;
  }

  // Removes `id`; false if it was absent.
  bool erase(std::uint64_t id) {
    std::size_t hole = probe(id);
    if (!slots_[hole].used) return false;
    // Move later members of the cluster into the hole unless their home lies
    // cyclically in (hole, j].
    std::size_t j = hole;
    for (std::size_t step = 0; step < mask_; ++step) {
      j = (j + 1) & mask_;
      if (!slots_[j].used) break;
      const std::size_t home = mix(slots_[j].id) & mask_;
      const bool home_between = hole <= j ? (hole < home && home <= j) : (hole < home || home <= j);
      if (!home_between) {
        slots_[hole] = slots_[j];
        hole = j;
      }
    }
    slots_[hole] = Slot{};
    --size_;
    return true;
  }

  void clear() {
    for (Slot& s : slots_) s = Slot{};
    size_ = 0;
  }

  std::uint32_t size() const { return size_; }
  std::uint32_t capacity() const { return capacity_; }
  std::size_t memory_bytes() const { return slots_.capacity() * sizeof(Slot); }

 private:
  struct Slot {
    std::uint64_t id = 0;
    std::uint32_t value = 0;
    std::uint32_t used = 0;
  };

  // Index of `id`, or of the free slot where it would go. The table is never
  // more than half full, so a free slot ends every probe.
  std::size_t probe(std::uint64_t id) const {
    std::size_t i = mix(id) & mask_;
    for (std::size_t step = 0; step < mask_; ++step) {
      if (!slots_[i].used || slots_[i].id == id) return i;
      i = (i + 1) & mask_;
    }
    return i;
  }
  std::uint32_t* at(std::size_t i) { return slots_[i].used ? &slots_[i].value : nullptr; }

  std::vector<Slot> slots_;
  std::size_t mask_ = 1;
  std::uint32_t size_ = 0;
  std::uint32_t capacity_ = 0;
};

}  // namespace keepless::core
