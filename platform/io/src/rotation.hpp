#pragma once
// The two rotation conventions of the formats read here, written out (the
// io target has no dependencies beyond core).

#include <cmath>

namespace keepless::io::detail {

// out = R(r) p for an angle-axis vector r (Rodrigues; BAL, as Ceres'
// AngleAxisRotatePoint, first order near zero).
inline void angle_axis_rotate(const double r[3], const double p[3], double out[3]) {
  const double theta2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
  const double cross[3] = {r[1] * p[2] - r[2] * p[1], r[2] * p[0] - r[0] * p[2], r[0] * p[1] - r[1] * p[0]};
  if (theta2 > 1e-30) {
    const double theta = std::sqrt(theta2);
    const double c = std::cos(theta), s = std::sin(theta);
    const double k[3] = {r[0] / theta, r[1] / theta, r[2] / theta};
    const double kp = k[0] * p[0] + k[1] * p[1] + k[2] * p[2];
    for (int i = 0; i < 3; ++i) out[i] = p[i] * c + (cross[i] / theta) * s + k[i] * kp * (1 - c);
  } else {
    for (int i = 0; i < 3; ++i) out[i] = p[i] + cross[i];
  }
}

// |q|, scaled by its largest component first, so that neither a huge nor a
// subnormal quaternion over- or underflows on the way (0 for a zero one).
inline double quaternion_norm(const double q[4]) {
  double m = 0;
  for (int i = 0; i < 4; ++i) m = std::fmax(m, std::fabs(q[i]));
  if (!(m > 0) || !std::isfinite(m)) return m;
  double sum = 0;
  for (int i = 0; i < 4; ++i) sum += (q[i] / m) * (q[i] / m);
  return m * std::sqrt(sum);
}

// Row-major R(q) of a quaternion (w, x, y, z), normalised first.
inline void quaternion_matrix(const double q_in[4], double m[9]) {
  const double n = quaternion_norm(q_in);
  const double w = q_in[0] / n, x = q_in[1] / n, y = q_in[2] / n, z = q_in[3] / n;
  m[0] = 1 - 2 * (y * y + z * z);
  m[1] = 2 * (x * y - w * z);
  m[2] = 2 * (x * z + w * y);
  m[3] = 2 * (x * y + w * z);
  m[4] = 1 - 2 * (x * x + z * z);
  m[5] = 2 * (y * z - w * x);
  m[6] = 2 * (x * z - w * y);
  m[7] = 2 * (y * z + w * x);
  m[8] = 1 - 2 * (x * x + y * y);
}

}  // namespace keepless::io::detail
