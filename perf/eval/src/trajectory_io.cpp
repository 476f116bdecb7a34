#include "trajectory_io.hpp"

#include <cmath>
#include <fstream>
#include <sstream>

namespace keepless::eval {
namespace {

bool parse_numbers(const std::string& line, char sep, std::vector<long double>* out) {
  out->clear();
  std::string s = line;
  if (sep != ' ')
    for (char& c : s)
      if (c == sep) c = ' ';
  std::istringstream in(s);
  std::string tok;
  while (in >> tok) {
    char* end = nullptr;
    const long double v = std::strtold(tok.c_str(), &end);
    if (end == tok.c_str() || *end != '\0' || !std::isfinite(static_cast<double>(v))) return false;
    out->push_back(v);
  }
  return true;
}

Pose kitti_pose(const std::vector<long double>& v) {
  Eigen::Matrix3d R;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) R(r, c) = static_cast<double>(v[static_cast<std::size_t>(r * 4 + c)]);
  Pose p;
  p.q = Eigen::Quaterniond(R).normalized();
  p.t = Eigen::Vector3d(static_cast<double>(v[3]), static_cast<double>(v[7]), static_cast<double>(v[11]));
  return p;
}

}  // namespace

bool parse_format(const std::string& s, TrajectoryFormat* out) {
  if (s == "tum") *out = TrajectoryFormat::kTum;
  else if (s == "euroc") *out = TrajectoryFormat::kEuroc;
  else if (s == "kitti") *out = TrajectoryFormat::kKitti;
  else return false;
  return true;
}

const char* to_string(TrajectoryFormat f) {
  switch (f) {
    case TrajectoryFormat::kTum: return "tum";
    case TrajectoryFormat::kEuroc: return "euroc";
    case TrajectoryFormat::kKitti: return "kitti";
  }
  return "?";
}

bool read_trajectory(const std::string& path, TrajectoryFormat format, Trajectory* out,
                     std::string* error) {
  std::ifstream in(path);
  if (!in) {
    *error = path + ":0: cannot open";
    return false;
  }
  out->time.clear();
  out->poses.clear();
  std::string line;
  std::vector<long double> v;
  long double t0 = 0;
  int lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    if (format == TrajectoryFormat::kEuroc && !(std::isdigit(static_cast<unsigned char>(line[first]))))
      continue;  // header line
    if (!parse_numbers(line, format == TrajectoryFormat::kEuroc ? ',' : ' ', &v)) {
      *error = path + ":" + std::to_string(lineno) + ": malformed number";
      return false;
    }
    Pose p;
    long double t = 0;
    if (format == TrajectoryFormat::kTum) {
      if (v.size() < 8) { *error = path + ":" + std::to_string(lineno) + ": expected 8 values"; return false; }
      t = v[0];
      p.t = Eigen::Vector3d(double(v[1]), double(v[2]), double(v[3]));
      p.q = Eigen::Quaterniond(double(v[7]), double(v[4]), double(v[5]), double(v[6]));
    } else if (format == TrajectoryFormat::kEuroc) {
      if (v.size() < 8) { *error = path + ":" + std::to_string(lineno) + ": expected >= 8 values"; return false; }
      t = v[0] * 1e-9L;
      p.t = Eigen::Vector3d(double(v[1]), double(v[2]), double(v[3]));
      p.q = Eigen::Quaterniond(double(v[4]), double(v[5]), double(v[6]), double(v[7]));
    } else {
      if (v.size() != 12) { *error = path + ":" + std::to_string(lineno) + ": expected 12 values"; return false; }
      t = static_cast<long double>(out->poses.size()) * 0.1L;
      p = kitti_pose(v);
    }
    if (p.q.norm() < 1e-9) { *error = path + ":" + std::to_string(lineno) + ": zero quaternion"; return false; }
    p.q.normalize();
    if (out->poses.empty()) t0 = t;
    out->time.push_back(static_cast<double>(t - t0));
    out->poses.push_back(p);
  }
  if (out->poses.size() < 2) {
    *error = path + ":" + std::to_string(lineno) + ": fewer than 2 poses";
    return false;
  }
  return true;
}

bool read_kitti_poses(const std::string& path, std::vector<Pose>* out, std::string* error) {
  Trajectory t;
  if (!read_trajectory(path, TrajectoryFormat::kKitti, &t, error)) return false;
  *out = t.poses;
  return true;
}

}  // namespace keepless::eval
