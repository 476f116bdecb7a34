#include "keepless/platform/latency_histogram.hpp"

#include <cmath>

namespace keepless::platform {

namespace {
constexpr std::uint64_t kSub = 1ull << LatencyHistogram::kSubBits;

int floor_log2(std::uint64_t v) { return 63 - __builtin_clzll(v); }
}  // namespace

// Values below 16 get a bucket each; above, bucket = (exponent, top 4 bits
// after the leading one).
int LatencyHistogram::bucket_of(std::uint64_t value) {
  if (value < kSub) return static_cast<int>(value);
  const int e = floor_log2(value);
  const int shift = e - kSubBits;
  const std::uint64_t sub = (value >> shift) & (kSub - 1);
  return static_cast<int>(kSub) * (shift + 1) + static_cast<int>(sub);
}

std::uint64_t LatencyHistogram::bucket_upper(int bucket) {
  if (bucket < static_cast<int>(kSub)) return static_cast<std::uint64_t>(bucket);
  const int shift = bucket / static_cast<int>(kSub) - 1;
  const std::uint64_t sub = static_cast<std::uint64_t>(bucket) % kSub;
  const std::uint64_t lower = (kSub + sub) << shift;
  return lower + ((1ull << shift) - 1);
}

void LatencyHistogram::record(std::uint64_t value) {
  ++buckets_[bucket_of(value)];
  ++count_;
  if (value > max_) max_ = value;
}

void LatencyHistogram::clear() {
  for (auto& b : buckets_) b = 0;
  count_ = 0;
  max_ = 0;
}

std::uint64_t LatencyHistogram::quantile(double q) const {
  if (count_ == 0) return 0;
  if (!(q > 0)) q = 0;
  if (q > 1) q = 1;
  // Rank of the quantile, 1-based: the smallest value with at least q of the
  // samples at or below it.
  std::uint64_t rank = static_cast<std::uint64_t>(std::ceil(q * static_cast<double>(count_)));
  if (rank < 1) rank = 1;
  std::uint64_t seen = 0;
  for (int b = 0; b < kBuckets; ++b) {
    seen += buckets_[b];
    if (seen >= rank) {
      const std::uint64_t upper = bucket_upper(b);
      return upper < max_ ? upper : max_;
    }
  }
  return max_;
}

}  // namespace keepless::platform
