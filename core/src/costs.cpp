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
  // a*b + 1 can exceed 64 bits only for absurd counts; 128 bits keep it exact.
  __extension__ using U128 = unsigned __int128;
  U128 x = static_cast<U128>(a) * b + 1;
  std::int64_t digits = 0;
  while (x >= 10) {  // at most 38 iterations
    x /= 10;
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
