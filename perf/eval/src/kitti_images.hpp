#pragma once
// A scenario from real images: ORB features (OpenCV features2d) on each
// frame, matched to the previous frame (Hamming cross-check, descriptor
// distance, and an epipolar check against the noisy odometry) and chained
// into tracks; the tracks are the landmarks. Every frame is a keyframe.

#include <string>

#include "scenario.hpp"

namespace keepless::eval {

struct ImageOptions {
  int max_frames = 0;  // 0 = every image
  int features = 2000;
  double odom_noise_t = 0.03;
  double odom_noise_r_deg = 0.1;
  std::uint64_t seed = 1;
};

bool make_image_scenario(const std::string& image_dir, const std::string& calib_file,
                         const std::string& poses_file, const ImageOptions& options, Scenario* out,
                         std::string* error);

}  // namespace keepless::eval
