#pragma once
// The few 3-D types the VO simulator needs. World frame: z up. Camera frame:
// x right, y down, z forward (the usual pinhole convention).

#include <cmath>

namespace keepless::vo_sim {

struct Vec3 {
  double x = 0, y = 0, z = 0;
};
inline Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3 operator*(double s, Vec3 a) { return {s * a.x, s * a.y, s * a.z}; }
inline double dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3 cross(Vec3 a, Vec3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
inline double norm(Vec3 a) { return std::sqrt(dot(a, a)); }
inline Vec3 normalized(Vec3 a) {
  const double n = norm(a);
  return n > 0 ? (1.0 / n) * a : a;
}

// Row-major 3x3.
struct Mat3 {
  double m[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  Vec3 col(int j) const { return {m[0][j], m[1][j], m[2][j]}; }
};
inline Mat3 operator*(const Mat3& a, const Mat3& b) {
  Mat3 r;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) r.m[i][j] = a.m[i][0] * b.m[0][j] + a.m[i][1] * b.m[1][j] + a.m[i][2] * b.m[2][j];
  }
  return r;
}
inline Vec3 operator*(const Mat3& a, Vec3 v) {
  return {a.m[0][0] * v.x + a.m[0][1] * v.y + a.m[0][2] * v.z, a.m[1][0] * v.x + a.m[1][1] * v.y + a.m[1][2] * v.z,
          a.m[2][0] * v.x + a.m[2][1] * v.y + a.m[2][2] * v.z};
}
inline Mat3 transpose(const Mat3& a) {
  Mat3 r;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) r.m[i][j] = a.m[j][i];
  }
  return r;
}
inline Mat3 from_columns(Vec3 a, Vec3 b, Vec3 c) {
  Mat3 r;
  r.m[0][0] = a.x, r.m[1][0] = a.y, r.m[2][0] = a.z;
  r.m[0][1] = b.x, r.m[1][1] = b.y, r.m[2][1] = b.z;
  r.m[0][2] = c.x, r.m[1][2] = c.y, r.m[2][2] = c.z;
  return r;
}

// Unit quaternion (w, x, y, z) <-> rotation matrix.
inline Mat3 quat_to_mat(double w, double x, double y, double z) {
  const double n = std::sqrt(w * w + x * x + y * y + z * z);
  if (n > 0) w /= n, x /= n, y /= n, z /= n;
  Mat3 r;
  r.m[0][0] = 1 - 2 * (y * y + z * z), r.m[0][1] = 2 * (x * y - w * z), r.m[0][2] = 2 * (x * z + w * y);
  r.m[1][0] = 2 * (x * y + w * z), r.m[1][1] = 1 - 2 * (x * x + z * z), r.m[1][2] = 2 * (y * z - w * x);
  r.m[2][0] = 2 * (x * z - w * y), r.m[2][1] = 2 * (y * z + w * x), r.m[2][2] = 1 - 2 * (x * x + y * y);
  return r;
}
inline void mat_to_quat(const Mat3& r, double q[4]) {
  const double tr = r.m[0][0] + r.m[1][1] + r.m[2][2];
  double w, x, y, z;
  if (tr > 0) {
    const double s = std::sqrt(tr + 1.0) * 2;
    w = 0.25 * s, x = (r.m[2][1] - r.m[1][2]) / s, y = (r.m[0][2] - r.m[2][0]) / s, z = (r.m[1][0] - r.m[0][1]) / s;
  } else if (r.m[0][0] > r.m[1][1] && r.m[0][0] > r.m[2][2]) {
    const double s = std::sqrt(1.0 + r.m[0][0] - r.m[1][1] - r.m[2][2]) * 2;
    w = (r.m[2][1] - r.m[1][2]) / s, x = 0.25 * s, y = (r.m[0][1] + r.m[1][0]) / s, z = (r.m[0][2] + r.m[2][0]) / s;
  } else if (r.m[1][1] > r.m[2][2]) {
    const double s = std::sqrt(1.0 + r.m[1][1] - r.m[0][0] - r.m[2][2]) * 2;
    w = (r.m[0][2] - r.m[2][0]) / s, x = (r.m[0][1] + r.m[1][0]) / s, y = 0.25 * s, z = (r.m[1][2] + r.m[2][1]) / s;
  } else {
    const double s = std::sqrt(1.0 + r.m[2][2] - r.m[0][0] - r.m[1][1]) * 2;
    w = (r.m[1][0] - r.m[0][1]) / s, x = (r.m[0][2] + r.m[2][0]) / s, y = (r.m[1][2] + r.m[2][1]) / s, z = 0.25 * s;
  }
  const double n = std::sqrt(w * w + x * x + y * y + z * z);
  q[0] = w / n, q[1] = x / n, q[2] = y / n, q[3] = z / n;
}

// Camera looking along `forward` with the horizon level (world z up).
inline Mat3 look_along(Vec3 forward) {
  const Vec3 f = normalized(forward);
  Vec3 right = cross(f, Vec3{0, 0, 1});
  if (norm(right) < 1e-9) right = {1, 0, 0};
  right = normalized(right);
  const Vec3 down = cross(f, right);
  return from_columns(right, down, f);
}

}  // namespace keepless::vo_sim
