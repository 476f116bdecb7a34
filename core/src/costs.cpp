#include "keepless/core/costs.hpp"

#include <cmath>

namespace keepless::core {

void connectivity_costs(std::uint32_t m, std::int64_t* table) {
  if (m < 2) return;
  table[m] = 1;
  // ceil(a / b) = (a + b - 1) / b with a = (n+1) c_m(n+1), b = n-1. The
  // values stay near m^2/2, far from overflow for any window size.
  for (std::uint32_t n = m - 1; n >= 2; --n) {
    const std::int64_t nn = n;
    table[n] = ((nn + 1) * table[n + 1] + (nn - 2)) / (nn - 1);
  }
}

std::int64_t spatial_cost(std::uint64_t a, std::uint64_t b) {
  // a*b + 1 exactly, as four 32-bit limbs (most significant first): 64-bit
  // arithmetic only, because 32-bit ARM has no unsigned __int128.
  constexpr std::uint64_t kLow = 0xffffffffu;
  const std::uint64_t p0 = (a & kLow) * (b & kLow), p1 = (a & kLow) * (b >> 32);
  const std::uint64_t p2 = (a >> 32) * (b & kLow), p3 = (a >> 32) * (b >> 32);
  const std::uint64_t mid = (p0 >> 32) + (p1 & kLow) + (p2 & kLow);
  std::uint64_t lo = (mid << 32) | (p0 & kLow);
  std::uint64_t hi = p3 + (p1 >> 32) + (p2 >> 32) + (mid >> 32);
  if (++lo == 0) ++hi;
  std::uint64_t limb[4] = {hi >> 32, hi & kLow, lo >> 32, lo & kLow};
  std::int64_t digits = 0;
  // While x >= 10: x /= 10 by long division over the limbs (at most 38 times).
  while (limb[0] != 0 || limb[1] != 0 || limb[2] != 0 || limb[3] >= 10) {
    std::uint64_t remainder = 0;
    for (std::uint64_t& l : limb) {
      const std::uint64_t current = (remainder << 32) | l;
      l = current / 10;
      remainder = current % 10;
    }
    ++digits;
  }
  return digits;
}

std::int64_t baseline_cost(const double centre_j[3], const double centre_k[3]) {
  const double dx = centre_j[0] - centre_k[0];
  const double dy = centre_j[1] - centre_k[1];
  const double dz = centre_j[2] - centre_k[2];
  const double d = std::sqrt(dx * dx + dy * dy + dz * dz);
  return static_cast<std::int64_t>(std::ceil(10.0 / (0.1 * d + 1.0)));
}

bool in_box(double du, double dv, std::int32_t box_width, std::int32_t box_height) {
  return std::fabs(du) <= 0.5 * box_width && std::fabs(dv) <= 0.5 * box_height;
}

}  // namespace keepless::core
