#pragma once
// A scenario is what every variant of one input sees, identically: the
// keyframes (chosen by a deterministic translation/rotation rule on the
// ground truth), each keyframe's extracted keypoints with their landmark (the
// data association a tracker would make, outliers included), and the noisy
// odometry that gives each new keyframe its initial pose.

#include <cstdint>
#include <string>
#include <vector>

#include "geometry.hpp"
#include "trajectory_io.hpp"

namespace keepless::eval {

struct Camera {
  int width = 640, height = 480;
  double fx = 500, fy = 500, cx = 320, cy = 240;
  double baseline = 0;  // metres; 0 = monocular
};

struct KeyPoint {
  std::uint64_t landmark = 0;  // dense 0 .. landmark_count-1
  double u = 0, v = 0;
  double ur = -1;  // right-image u (stereo / RGB-D virtual stereo); < 0 = monocular
  double response = 0;
};

struct ScenarioFrame {
  Pose gt;                       // T_wc
  std::vector<KeyPoint> keypoints;
  std::size_t source_index = 0;  // index in the input trajectory / image list
};

struct Scenario {
  std::string input;  // file or directory it came from
  std::string name;   // short label (fr1_xyz, MH01, 06, ...)
  std::string group;  // tum, euroc_mh, euroc_v, kitti, kitti_images
  std::string kind;   // trajectory | images
  Camera cam;
  std::vector<ScenarioFrame> frames;
  std::vector<Pose> odometry;  // odometry[k] = noisy T_{k-1,k}; [0] unused
  std::uint64_t landmark_count = 0;
  bool fix_first_two = true;   // gauge: keyframes 0 and 1 at their true poses
};

struct WorldOptions {
  Camera cam;
  double min_depth = 0.5, max_depth = 5.0;
  int keypoints_per_frame = 1000;
  double pixel_noise = 1.0;       // sigma, px
  double outlier_ratio = 0.03;    // gross association errors
  double odom_noise_t = 0.03;     // sigma, fraction of the keyframe step
  double odom_noise_r_deg = 0.3;  // sigma per keyframe
  double kf_translation = 0.1;    // keyframe rule, metres
  double kf_rotation_deg = 10.0;
  int max_keyframes = 0;          // 0 = whole trajectory
  std::uint64_t seed = 1;
};

// Camera, depth range and keyframe rule for each dataset family (the
// sensors of TUM RGB-D, EuRoC stereo and KITTI stereo).
WorldOptions world_defaults(TrajectoryFormat format);

// A synthetic textured world around a real trajectory: patches of points
// (dense high-response clusters, ordinary texture, weak-texture singles)
// spawned until each keyframe sees ~3x the keypoint budget, then per keyframe
// projection, pixel noise, outliers, and ORB-SLAM2-like grid extraction.
Scenario make_synthetic_scenario(const Trajectory& trajectory, const WorldOptions& options,
                                 const std::string& input, const std::string& name,
                                 const std::string& group);

// Noisy odometry for a scenario whose frames are set (shared by the builders).
void add_odometry(Scenario* s, double noise_t, double noise_r_deg, std::uint64_t seed);

}  // namespace keepless::eval
