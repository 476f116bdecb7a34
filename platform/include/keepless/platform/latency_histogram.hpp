#pragma once
// A fixed-size log-linear latency histogram: 16 sub-buckets per power of two,
// so a quantile is reported within 1/16 (6.25 %) of the true value. Inline
// storage, no allocation, O(1) record; the exact maximum is kept apart.

#include <cstdint>

namespace keepless::platform {

class LatencyHistogram {
 public:
  void record(std::uint64_t value);
  void clear();

  std::uint64_t count() const { return count_; }
  std::uint64_t max() const { return max_; }
  // Upper edge of the bucket holding the q-quantile (0 <= q <= 1), capped at
  // max(); 0 when empty.
  std::uint64_t quantile(double q) const;

  static constexpr int kSubBits = 4;
  static constexpr int kBuckets = (64 - kSubBits + 1) << kSubBits;

 private:
  static int bucket_of(std::uint64_t value);
  static std::uint64_t bucket_upper(int bucket);

  std::uint64_t buckets_[kBuckets] = {};
  std::uint64_t count_ = 0;
  std::uint64_t max_ = 0;
};

}  // namespace keepless::platform
