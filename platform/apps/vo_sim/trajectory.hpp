#pragma once
// Camera trajectories for the VO simulator: built-in scenes, or real ground
// truth read from TUM, EuRoC or KITTI files, converted to the simulator's
// frame (world z up; camera x right, y down, z forward).

#include <cstdint>
#include <string>
#include <vector>

#include "sim_math.hpp"

namespace keepless::vo_sim {

struct Pose {
  std::int64_t utime = 0;  // microseconds
  Vec3 centre;             // world, metres
  Mat3 rotation;           // world from camera
};

enum class TrajectoryFormat { kTum, kEuroc, kEurocCam, kKitti };
// "tum", "euroc", "euroc-cam", "kitti"
bool parse_format(const std::string& text, TrajectoryFormat& out);

// Reads every pose of FILE. On failure returns false with "FILE:LINE: why".
//  tum:       "t tx ty tz qx qy qz qw" (seconds; '#' comments), camera poses.
//  euroc:     "t_ns,x,y,z,qw,qx,qy,qz[,...]" body (IMU) poses; the cam0
//             mounting of the EuRoC sensor (T_BS) is applied.
//  euroc-cam: same columns, poses already of the left camera with the
//             quaternion stored conjugated (ORB-SLAM3's EuRoC_left_cam files).
//  kitti:     12 numbers a line, [R|t] row-major, camera poses (x right,
//             y down, z forward), 10 Hz timestamps assumed.
bool load_trajectory(const std::string& path, TrajectoryFormat format, std::vector<Pose>& out,
                     std::string& error);

// Keyframes of a dense trajectory: a pose becomes a keyframe once the camera
// moved `min_distance` metres or turned `min_angle_deg` since the last one.
std::vector<Pose> select_keyframes(const std::vector<Pose>& poses, double min_distance, double min_angle_deg,
                                   std::size_t max_keyframes);

// Built-in scenes' camera paths, one pose per keyframe.
//  street: forward along a city block loop at 0.4 m a keyframe, 1.5 m high.
//  room:   around an 8 x 6 m room, 5 cm a keyframe, looking at the walls.
std::vector<Pose> street_path(std::size_t keyframes, std::uint64_t seed);
std::vector<Pose> room_path(std::size_t keyframes, std::uint64_t seed);

}  // namespace keepless::vo_sim
