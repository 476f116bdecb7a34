#pragma once
// Ground-truth trajectory readers: TUM (t tx ty tz qx qy qz qw), EuRoC CSV
// (t_ns, p, q w x y z, ... ; raw or ORB-SLAM3's left-camera files) and KITTI
// odometry (3x4 row-major T_wc a line, 10 Hz).

#include <string>
#include <vector>

#include "geometry.hpp"

namespace keepless::eval {

enum class TrajectoryFormat { kTum, kEuroc, kKitti };

struct Trajectory {
  std::vector<double> time;  // seconds from the first pose
  std::vector<Pose> poses;   // T_wc
};

bool parse_format(const std::string& s, TrajectoryFormat* out);
const char* to_string(TrajectoryFormat f);

// Returns false and fills *error ("FILE:LINE: reason") on unreadable input.
bool read_trajectory(const std::string& path, TrajectoryFormat format, Trajectory* out,
                     std::string* error);

// KITTI 3x4 pose lines (also the real-image sequence's poses.txt).
bool read_kitti_poses(const std::string& path, std::vector<Pose>* out, std::string* error);

}  // namespace keepless::eval
