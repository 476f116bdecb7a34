#pragma once
// The three costs of the paper's section III-B, in exact integer arithmetic
// where the paper's formula allows it, and with -ffp-contract=off IEEE double
// where it does not (the baseline), so x86-64 and aarch64 agree bit for bit.

#include <cstdint>

namespace keepless::core {

// c_m(n) for n = 2..m: c_m(m) = 1, c_m(n) = ceil((n+1)/(n-1) * c_m(n+1)).
// Writes table[n] for 2 <= n <= m (table must hold m+1 entries).
void connectivity_costs(std::uint32_t m, std::int64_t* table);

// floor(log10(a*b + 1)) for keypoint counts a, b.
std::int64_t spatial_cost(std::uint64_t a, std::uint64_t b);

// ceil(10 / (0.1*d + 1)), d = |c_j - c_k| in metres.
std::int64_t baseline_cost(const double centre_j[3], const double centre_k[3]);

// The closed box test |du| <= half_w and |dv| <= half_h of the paper's
// 64x48 box, for a box of width w and height h (half = w/2, h/2).
bool in_box(double du, double dv, std::int32_t box_width, std::int32_t box_height);

}  // namespace keepless::core
