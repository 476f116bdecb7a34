#include "trajectory.hpp"

#include <cerrno>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "keepless/core/window_file.hpp"
#include "splitmix64.hpp"

namespace keepless::vo_sim {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Splits on spaces, tabs and commas; false if any token is not a finite number.
bool numbers(const std::string& line, std::vector<double>& out, std::vector<std::string>& tokens) {
  out.clear();
  tokens.clear();
  std::string tok;
  auto flush = [&]() -> bool {
    if (tok.empty()) return true;
    double v = 0;  // plain decimal, as every model reader takes it
    if (!keepless::core::parse_finite_double(tok, &v)) return false;
    out.push_back(v);
    tokens.push_back(tok);
    tok.clear();
    return true;
  };
  for (char ch : line) {
    if (ch == ' ' || ch == '\t' || ch == ',' || ch == '\r') {
      if (!flush()) return false;
    } else {
      tok += ch;
    }
  }
  return flush();
}

// "1403636580863555584.0000000000" -> ns without going through a double.
bool integer_ns(const std::string& tok, std::int64_t& ns) {
  const std::string digits = tok.substr(0, tok.find('.'));
  errno = 0;
  char* end = nullptr;
  const long long v = std::strtoll(digits.c_str(), &end, 10);
  if (errno != 0 || *end != '\0' || digits.empty()) return false;
  ns = v;
  return true;
}

// KITTI's world is its first camera frame (x right, y down, z forward); the
// simulator's has z up: (x, y, z)_sim = (z, -x, -y)_kitti.
const Mat3 kKittiToSim = [] {
  Mat3 a;
  a.m[0][0] = 0, a.m[0][1] = 0, a.m[0][2] = 1;
  a.m[1][0] = -1, a.m[1][1] = 0, a.m[1][2] = 0;
  a.m[2][0] = 0, a.m[2][1] = -1, a.m[2][2] = 0;
  return a;
}();

// EuRoC MAV cam0 extrinsics T_BS (sensor.yaml of every EuRoC sequence).
const Mat3 kEurocBodyToCam0 = [] {
  Mat3 r;
  const double v[9] = {0.0148655429818, -0.999880929698, 0.00414029679422, 0.999557249008, 0.0149672133247,
                       0.025715529948,  -0.0257744366974, 0.00375618835797, 0.999660727178};
  for (int i = 0; i < 9; ++i) r.m[i / 3][i % 3] = v[i];
  return r;
}();
const Vec3 kEurocBodyToCam0Translation{-0.0216401454975, -0.064676986768, 0.00981073058801};

}  // namespace

bool parse_format(const std::string& text, TrajectoryFormat& out) {
  if (text == "tum") out = TrajectoryFormat::kTum;
  else if (text == "euroc") out = TrajectoryFormat::kEuroc;
  else if (text == "euroc-cam") out = TrajectoryFormat::kEurocCam;
  else if (text == "kitti") out = TrajectoryFormat::kKitti;
  else return false;
  return true;
}

bool load_trajectory(const std::string& path, TrajectoryFormat format, std::vector<Pose>& out,
                     std::string& error) {
  out.clear();
  std::ifstream in(path);
  if (!in) {
    error = path + ": cannot open";
    return false;
  }
  std::string line;
  std::vector<double> v;
  std::vector<std::string> tok;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    const std::string where = path + ":" + std::to_string(line_no) + ": ";
    if (!numbers(line, v, tok)) {
      // EuRoC files may start with an uncommented header.
      if (out.empty() && (format == TrajectoryFormat::kEuroc || format == TrajectoryFormat::kEurocCam)) continue;
      error = where + "not a list of numbers";
      return false;
    }
    Pose p;
    switch (format) {
      case TrajectoryFormat::kTum: {
        if (v.size() != 8) {
          error = where + "expected 8 numbers (t tx ty tz qx qy qz qw), got " + std::to_string(v.size());
          return false;
        }
        p.utime = static_cast<std::int64_t>(std::llround(v[0] * 1e6));
        p.centre = {v[1], v[2], v[3]};
        p.rotation = quat_to_mat(v[7], v[4], v[5], v[6]);
        break;
      }
      case TrajectoryFormat::kEuroc:
      case TrajectoryFormat::kEurocCam: {
        if (v.size() < 8) {
          error = where + "expected at least 8 numbers (t_ns x y z qw qx qy qz), got " + std::to_string(v.size());
          return false;
        }
        std::int64_t ns = 0;
        if (!integer_ns(tok[0], ns)) {
          error = where + "bad timestamp '" + tok[0] + "'";
          return false;
        }
        p.utime = ns / 1000;
        const Vec3 pos{v[1], v[2], v[3]};
        if (format == TrajectoryFormat::kEuroc) {
          const Mat3 body = quat_to_mat(v[4], v[5], v[6], v[7]);
          p.rotation = body * kEurocBodyToCam0;
          p.centre = pos + body * kEurocBodyToCam0Translation;
        } else {
          p.rotation = quat_to_mat(v[4], -v[5], -v[6], -v[7]);
          p.centre = pos;
        }
        break;
      }
      case TrajectoryFormat::kKitti: {
        if (v.size() != 12) {
          error = where + "expected 12 numbers ([R|t] row-major), got " + std::to_string(v.size());
          return false;
        }
        Mat3 r;
        for (int i = 0; i < 3; ++i) {
          for (int j = 0; j < 3; ++j) r.m[i][j] = v[static_cast<std::size_t>(i * 4 + j)];
        }
        p.rotation = kKittiToSim * r;
        p.centre = kKittiToSim * Vec3{v[3], v[7], v[11]};
        p.utime = static_cast<std::int64_t>(out.size()) * 100000;  // 10 Hz
        break;
      }
    }
    out.push_back(p);
  }
  if (out.empty()) {
    error = path + ": no poses";
    return false;
  }
  return true;
}

std::vector<Pose> select_keyframes(const std::vector<Pose>& poses, double min_distance, double min_angle_deg,
                                   std::size_t max_keyframes) {
  std::vector<Pose> kfs;
  const double cos_limit = std::cos(min_angle_deg * kPi / 180.0);
  for (const Pose& p : poses) {
    if (kfs.size() >= max_keyframes) break;
    if (kfs.empty()) {
      kfs.push_back(p);
      continue;
    }
    const Pose& last = kfs.back();
    const double moved = norm(p.centre - last.centre);
    const double turned_cos = dot(p.rotation.col(2), last.rotation.col(2));
    if (moved >= min_distance || turned_cos <= cos_limit) kfs.push_back(p);
  }
  return kfs;
}

std::vector<Pose> street_path(std::size_t keyframes, std::uint64_t seed) {
  // A rectangular city-block loop, 90 x 60 m, corners rounded with radius 8 m,
  // driven anticlockwise; the camera sways a little like a hand-held rig.
  const double w = 90, h = 60, r = 8;
  const double straight_x = w - 2 * r, straight_y = h - 2 * r, arc = 0.5 * kPi * r;
  const double loop = 2 * straight_x + 2 * straight_y + 4 * arc;
  SplitMix64 rng(mix_seed(seed, 1));
  const double sway_phase = rng.uniform(0, 2 * kPi);
  std::vector<Pose> out;
  for (std::size_t i = 0; i < keyframes; ++i) {
    double s = std::fmod(0.4 * static_cast<double>(i), loop);
    Vec3 c, tangent;
    // Segments: bottom (+x), corner, right (+y), corner, top (-x), corner, left (-y), corner.
    const double segs[8] = {straight_x, arc, straight_y, arc, straight_x, arc, straight_y, arc};
    int k = 0;
    while (k < 7 && s > segs[k]) s -= segs[k++];
    const double corners[4][2] = {{w - r, r}, {w - r, h - r}, {r, h - r}, {r, r}};
    switch (k) {
      case 0: c = {r + s, 0, 0}, tangent = {1, 0, 0}; break;
      case 2: c = {w, r + s, 0}, tangent = {0, 1, 0}; break;
      case 4: c = {w - r - s, h, 0}, tangent = {-1, 0, 0}; break;
      case 6: c = {0, h - r - s, 0}, tangent = {0, -1, 0}; break;
      default: {
        const int corner = k / 2;
        const double a0 = -0.5 * kPi + 0.5 * kPi * corner;
        const double a = a0 + s / r;
        c = {corners[corner][0] + r * std::cos(a), corners[corner][1] + r * std::sin(a), 0};
        tangent = {-std::sin(a), std::cos(a), 0};
      }
    }
    const double t = static_cast<double>(i);
    const Vec3 left{-tangent.y, tangent.x, 0};
    c = c + (0.3 * std::sin(0.05 * t + sway_phase)) * left;
    c.z = 1.5 + 0.05 * std::sin(0.3 * t);
    const double yaw = 0.08 * std::sin(0.07 * t + sway_phase);
    const Vec3 forward = normalized(std::cos(yaw) * tangent + std::sin(yaw) * left + Vec3{0, 0, -0.05});
    Pose p;
    p.utime = static_cast<std::int64_t>(i) * 100000;
    p.centre = c;
    p.rotation = look_along(forward);
    out.push_back(p);
  }
  return out;
}

std::vector<Pose> room_path(std::size_t keyframes, std::uint64_t seed) {
  // An ellipse inside an 8 x 6 m room; the camera looks outwards and ahead,
  // sweeping the walls and the tiled floor.
  SplitMix64 rng(mix_seed(seed, 2));
  const double phase = rng.uniform(0, 2 * kPi);
  std::vector<Pose> out;
  for (std::size_t i = 0; i < keyframes; ++i) {
    const double t = static_cast<double>(i);
    const double a = phase + 0.05 / 2.5 * t;  // ~5 cm a keyframe
    const Vec3 c{2.5 * std::cos(a), 1.6 * std::sin(a), 1.4 + 0.1 * std::sin(0.2 * t)};
    const Vec3 tangent = normalized(Vec3{-2.5 * std::sin(a), 1.6 * std::cos(a), 0});
    const Vec3 outward = normalized(Vec3{std::cos(a), std::sin(a), 0});
    const Vec3 forward = normalized(tangent + 0.8 * outward + Vec3{0, 0, -0.35});
    Pose p;
    p.utime = static_cast<std::int64_t>(i) * 100000;
    p.centre = c;
    p.rotation = look_along(forward);
    out.push_back(p);
  }
  return out;
}

}  // namespace keepless::vo_sim
