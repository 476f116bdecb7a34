#include "keepless/core/costs.hpp"

#include <algorithm>
#include <cmath>

namespace keepless::core {

namespace {

double distance(const double a[3], const double b[3]) {
  const double dx = a[0] - b[0];
  const double dy = a[1] - b[1];
  const double dz = a[2] - b[2];
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

// A keypoint's grid cell along one axis, clamped to [-2, cells + 1] so that
// it fits an int (outside the grid either way).
std::int32_t grid_cell(double x, double per_pixel, std::int32_t cells) {
  const double c = std::round(x * per_pixel);
  if (!(c >= -2.0)) return -2;  // NaN cannot occur: inputs are finite
  if (c > cells + 1.0) return cells + 1;
  return static_cast<std::int32_t>(c);
}

}  // namespace

void connectivity_costs(std::uint32_t m, std::int64_t* table) {
  if (m < 2) return;
  table[m] = 1;
  // ceil(a / b) = (a + b - 1) / b with a = (n+1) c_m(n+1), b = n-1. The
  // ceilings compound: c_m(2) grows about as m^3/10 (840 at m = 20, 1.08e8
  // at m = 1024), not as the m(m-1)/2 of the exact product, and passes the
  // solver's cost bound 2^30 from m = kMaxPointViews + 1 (the networks refuse
  // such a window); int64 holds it for any m below 2^32 (n+1 times it < 2^63).
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
  const double d = distance(centre_j, centre_k);
  return static_cast<std::int64_t>(std::ceil(10.0 / (0.1 * d + 1.0)));
}


std::int64_t authors_spatial_cost(std::uint64_t a, std::uint64_t b) {
  // Counts are keypoints of one frame (< 2^32), so a*b fits 64 bits.
  const std::uint64_t n = a * b;
  const std::int64_t bin = n < 100 ? 0 : n < 500 ? 1 : n < 1200 ? 2 : 3;
  return 2 * bin;
}

std::int64_t authors_baseline_cost(const double centre_j[3], const double centre_k[3]) {
  const double d = distance(centre_j, centre_k);
  for (std::int64_t step = 1; step <= 10; ++step) {
    if (d < 10.0 * static_cast<double>(step)) return 10 * (11 - step);
  }
  return 0;
}

void grid_neighbours(const Keyframe& kf, const Observation* observations, std::uint32_t count,
                     std::int32_t width, std::int32_t height, std::uint32_t* cells,
                     std::uint32_t* out) {
  const double per_u = static_cast<double>(kGridColumns) / width;
  const double per_v = static_cast<double>(kGridRows) / height;
  std::fill(cells, cells + kGridColumns * kGridRows, 0u);
  const auto add = [&](double u, double v) {
    const std::int32_t cu = grid_cell(u, per_u, kGridColumns);
    const std::int32_t cv = grid_cell(v, per_v, kGridRows);
    if (cu >= 0 && cu < kGridColumns && cv >= 0 && cv < kGridRows) ++cells[cv * kGridColumns + cu];
  };
  for (std::uint32_t i = 0; i < count; ++i) add(observations[i].u, observations[i].v);
  for (std::uint32_t i = 0; i < kf.unmapped_count; ++i) add(kf.unmapped[i].u, kf.unmapped[i].v);
  for (std::uint32_t i = 0; i < count; ++i) {
    const std::int32_t cu = grid_cell(observations[i].u, per_u, kGridColumns);
    const std::int32_t cv = grid_cell(observations[i].v, per_v, kGridRows);
    std::uint32_t n = 0;
    for (std::int32_t y = std::max(0, cv - 1); y <= std::min(kGridRows - 1, cv + 1); ++y) {
      for (std::int32_t x = std::max(0, cu - 1); x <= std::min(kGridColumns - 1, cu + 1); ++x) {
        n += cells[y * kGridColumns + x];
      }
    }
    out[i] = n;
  }
}

namespace {

// The two rows of an observation's reprojection Jacobian with respect to a
// perturbation (translation, rotation) of the camera pose, for the point
// at depth z along the ray through (u, v). Their sign convention does not
// matter: leverages are invariant to any reparametrisation of the pose.
void jacobian_rows(const Keyframe& kf, const Observation& o, double ju[6], double jv[6]) {
  const double a = (o.u - kf.cx) / kf.fx;  // x / z
  const double b = (o.v - kf.cy) / kf.fy;  // y / z
  const double r = 1.0 / o.depth;
  ju[0] = kf.fx * r;
  ju[1] = 0.0;
  ju[2] = -kf.fx * a * r;
  ju[3] = -kf.fx * a * b;
  ju[4] = kf.fx * (1.0 + a * a);
  ju[5] = -kf.fx * b;
  jv[0] = 0.0;
  jv[1] = kf.fy * r;
  jv[2] = -kf.fy * b * r;
  jv[3] = -kf.fy * (1.0 + b * b);
  jv[4] = kf.fy * a * b;
  jv[5] = kf.fy * a;
}

// Solves L y = j for the lower-triangular Cholesky factor L (row-major
// 6x6), given the reciprocals of its diagonal.
void forward(const double l[36], const double inverse_diagonal[6], const double j[6], double y[6]) {
  for (int r = 0; r < 6; ++r) {
    double x = j[r];
    for (int c = 0; c < r; ++c) x -= l[6 * r + c] * y[c];
    y[r] = x * inverse_diagonal[r];
  }
}

}  // namespace

void information_levels(const Keyframe& kf, const Observation* observations, std::uint32_t count,
                        std::uint32_t* out) {
  std::fill(out, out + count, kNeutralInformationLevel);
  if (!(kf.fx > 0.0) || !(kf.fy > 0.0)) return;
  const auto usable = [](const Observation& o) { return o.depth > 0.0; };
  // The keyframe's information (lower triangle), summed in observation order.
  double info[36] = {};
  std::uint32_t used = 0;
  for (std::uint32_t i = 0; i < count; ++i) {
    if (!usable(observations[i])) continue;
    double ju[6], jv[6];
    jacobian_rows(kf, observations[i], ju, jv);
    for (int r = 0; r < 6; ++r) {
      for (int c = 0; c <= r; ++c) info[6 * r + c] += ju[r] * ju[c] + jv[r] * jv[c];
    }
    ++used;
  }
  // With 3 observations (6 equations, 6 unknowns) every leverage is exactly
  // 1 (r = 1, a level boundary): the pose is not over-determined, so there
  // is nothing to rank.
  if (used < 4) return;
  // Cholesky; a pivot below 1e-9 of the largest diagonal entry (or not
  // finite) makes the keyframe degenerate: every observation stays neutral.
  double largest = 0.0;
  for (int r = 0; r < 6; ++r) largest = std::max(largest, info[6 * r + r]);
  if (!std::isfinite(largest) || !(largest > 0.0)) return;
  double l[36] = {};
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c <= r; ++c) {
      double x = info[6 * r + c];
      for (int k = 0; k < c; ++k) x -= l[6 * r + k] * l[6 * c + k];
      if (r == c) {
        if (!(x > 1e-9 * largest)) return;
        l[6 * r + r] = std::sqrt(x);
      } else {
        l[6 * r + c] = x / l[6 * c + c];
      }
    }
  }
  double inverse_diagonal[6];
  for (int r = 0; r < 6; ++r) inverse_diagonal[r] = 1.0 / l[6 * r + r];
  // Leverage t = |L^-1 ju|^2 + |L^-1 jv|^2; its mean over the used
  // observations is 6 / used, so r = t * used / 6 has mean 1. Level
  // 2 - floor(log2 r), clamped to [0, 4]: frexp gives floor(log2 r) exactly.
  for (std::uint32_t i = 0; i < count; ++i) {
    if (!usable(observations[i])) continue;
    double ju[6], jv[6], yu[6], yv[6];
    jacobian_rows(kf, observations[i], ju, jv);
    forward(l, inverse_diagonal, ju, yu);
    forward(l, inverse_diagonal, jv, yv);
    double t = 0.0;
    for (int r = 0; r < 6; ++r) t += yu[r] * yu[r] + yv[r] * yv[r];
    const double ratio = t * static_cast<double>(used) / 6.0;
    if (!(ratio > 0.0) || !std::isfinite(ratio)) continue;
    int exponent = 0;
    (void)std::frexp(ratio, &exponent);  // ratio = m * 2^exponent, m in [0.5, 1)
    const int level = 2 - (exponent - 1);
    out[i] = static_cast<std::uint32_t>(std::min(4, std::max(0, level)));
  }
}

bool in_box(double du, double dv, std::int32_t box_width, std::int32_t box_height) {
  return std::fabs(du) <= 0.5 * box_width && std::fabs(dv) <= 0.5 * box_height;
}

namespace {

// 4 - min(4, floor(log2 x)) for x >= 1.
std::uint32_t log2_level(std::uint64_t x) {
  std::uint32_t bits = 0;
  while (x > 1 && bits < 4) {
    x >>= 1;
    ++bits;
  }
  return 4 - bits;
}

// The index of the first limit x is below (ascending limits), or 4.
std::uint32_t below_level(float x, const float (&limits)[4]) {
  std::uint32_t level = 0;
  while (level < 4 && !(x < limits[level])) ++level;
  return level;
}

// The index of the first limit x reaches (descending limits), or 4.
std::uint32_t reach_level(float x, const float (&limits)[4]) {
  std::uint32_t level = 0;
  while (level < 4 && !(x >= limits[level])) ++level;
  return level;
}

std::uint32_t quality_level(const PointQuality& q, std::uint8_t terms) {
  static constexpr float kErrorLimits[4] = {0.5f, 1.f, 2.f, 4.f};
  static constexpr float kAngleLimits[4] = {8.f, 4.f, 2.f, 1.f};
  std::uint32_t sum = 0;
  if (terms & kTrackLength) {
    sum += q.track_length > 0 ? log2_level(q.track_length) : kNeutralTrackLevel;
  }
  if (terms & kTrackAge) {
    sum += q.age >= 0 ? log2_level(static_cast<std::uint64_t>(q.age) + 1) : kNeutralTrackLevel;
  }
  if (terms & kTrackError) {
    sum += q.reprojection_error >= 0.f ? below_level(q.reprojection_error, kErrorLimits)
                                       : kNeutralTrackLevel;
  }
  if (terms & kTrackAngle) {
    sum += q.triangulation_angle > 0.f ? reach_level(q.triangulation_angle, kAngleLimits)
                                       : kNeutralTrackLevel;
  }
  return sum;
}

}  // namespace

void track_levels(const Keyframe& kf, std::uint32_t count, std::uint8_t terms,
                  std::uint32_t* out) {
  const PointQuality unknown{};
  for (std::uint32_t i = 0; i < count; ++i) {
    out[i] = quality_level(kf.quality != nullptr ? kf.quality[i] : unknown, terms);
  }
}

}  // namespace keepless::core
