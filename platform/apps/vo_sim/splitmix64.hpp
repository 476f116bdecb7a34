#pragma once
// splitmix64 (Steele, Lea, Flood 2014): a tiny PRNG whose output is fixed by
// its seed on every platform, unlike std:: distributions.

#include <cmath>
#include <cstdint>

namespace keepless::vo_sim {

class SplitMix64 {
 public:
  explicit SplitMix64(std::uint64_t seed) : state_(seed) {}

  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  // [0, 1) with 53 random bits.
  double uniform() { return static_cast<double>(next() >> 11) * (1.0 / 9007199254740992.0); }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  // [0, n)
  std::uint64_t below(std::uint64_t n) { return n == 0 ? 0 : next() % n; }
  // Standard normal by Box-Muller (one value per call, no cached state).
  double normal() {
    double u1 = uniform();
    if (u1 < 1e-300) u1 = 1e-300;
    const double u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
  }

 private:
  std::uint64_t state_;
};

// A seed for a sub-stream keyed by integers (a cell, a keyframe): mixes them
// through splitmix64 so neighbouring keys give unrelated streams.
inline std::uint64_t mix_seed(std::uint64_t seed, std::int64_t a, std::int64_t b = 0, std::int64_t c = 0) {
  SplitMix64 m(seed ^ 0x5851f42d4c957f2dull);
  std::uint64_t h = m.next();
  for (std::int64_t k : {a, b, c}) {
    SplitMix64 s(h ^ static_cast<std::uint64_t>(k));
    h = s.next();
  }
  return h;
}

}  // namespace keepless::vo_sim
