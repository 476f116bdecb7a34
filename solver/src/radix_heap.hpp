#pragma once
// Monotone radix heap over node ids with decrease-key, in storage sized once.
// Dijkstra's keys never drop below the last popped key, so a key lives in
// bucket bit_width(key ^ last): O(log C) amortised moves per node, no
// comparisons between unrelated nodes, and no allocation after construction.

#include <cstddef>
#include <cstdint>
#include <vector>

namespace keepless::solver {

class RadixHeap {
 public:
  explicit RadixHeap(std::size_t max_items)
      : key_(max_items), next_(max_items), prev_(max_items), bucket_(max_items) {
    clear();
  }

  void clear() {
    for (auto& h : head_) h = -1;
    size_ = 0;
    last_ = 0;
  }
  bool empty() const { return size_ == 0; }

  void push(std::int32_t item, std::uint64_t key) {
    key_[item] = key;
    link(item, bucket_index(key));
    ++size_;
  }

  void decrease(std::int32_t item, std::uint64_t key) {
    unlink(item);
    key_[item] = key;
    link(item, bucket_index(key));
  }

  std::uint64_t key_of(std::int32_t item) const { return key_[item]; }

  // Pops an item of minimum key; among equal keys, the most recently linked.
  std::int32_t pop_min() {
    if (head_[0] < 0) {
      int b = 1;
      while (head_[b] < 0) ++b;  // size_ > 0, so some bucket is non-empty
      std::uint64_t low = key_[head_[b]];
      for (std::int32_t i = head_[b]; i >= 0; i = next_[i]) low = key_[i] < low ? key_[i] : low;
      last_ = low;
      std::int32_t i = head_[b];
      head_[b] = -1;
      while (i >= 0) {  // every item moves to a lower bucket
        const std::int32_t n = next_[i];
        link(i, bucket_index(key_[i]));
        i = n;
      }
    }
    const std::int32_t item = head_[0];
    unlink(item);
    --size_;
    return item;
  }

  // Its buffers (the object itself, head_ included, is its owner's).
  std::size_t memory_bytes() const {
    return key_.capacity() * sizeof(std::uint64_t) +
           (next_.capacity() + prev_.capacity() + bucket_.capacity()) * sizeof(std::int32_t);
  }

 private:
  int bucket_index(std::uint64_t key) const {
    const std::uint64_t x = key ^ last_;
    return x == 0 ? 0 : 64 - __builtin_clzll(x);
  }
  void link(std::int32_t item, int b) {
    bucket_[item] = b;
    prev_[item] = -1;
    next_[item] = head_[b];
    if (head_[b] >= 0) prev_[head_[b]] = item;
    head_[b] = item;
  }
  void unlink(std::int32_t item) {
    const int b = bucket_[item];
    if (prev_[item] >= 0) {
      next_[prev_[item]] = next_[item];
    } else {
      head_[b] = next_[item];
    }
    if (next_[item] >= 0) prev_[next_[item]] = prev_[item];
  }

  std::vector<std::uint64_t> key_;
  std::vector<std::int32_t> next_, prev_, bucket_;
  std::int32_t head_[65];
  std::size_t size_ = 0;
  std::uint64_t last_ = 0;
};

}  // namespace keepless::solver
