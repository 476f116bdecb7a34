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

// q / |q|, scaled by its largest component first, so that neither a huge
// nor a subnormal quaternion over- or underflows on the way (the product
// m |q / m| of a component near DBL_MAX is infinite). q must not be zero.
inline void unit_quaternion(const double q[4], double u[4]) {
  double m = 0;
  for (int i = 0; i < 4; ++i) m = std::fmax(m, std::fabs(q[i]));
  double sum = 0;
  for (int i = 0; i < 4; ++i) {
    u[i] = q[i] / m;
    sum += u[i] * u[i];
  }
  const double n = std::sqrt(sum);
  for (int i = 0; i < 4; ++i) u[i] /= n;
}

// Row-major R(q) of a quaternion (w, x, y, z), normalised first.
inline void quaternion_matrix(const double q_in[4], double m[9]) {
  double u[4];
  unit_quaternion(q_in, u);
  const double w = u[0], x = u[1], y = u[2], z = u[3];
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
