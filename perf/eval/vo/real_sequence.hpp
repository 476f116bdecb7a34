#pragma once
// Real image sequences for the VO: KITTI layout (grey images, a calibration
// with P0 or K, 3x4 camera-to-world poses) and 7-Scenes RGB-D layout
// (frame-NNNNNN.color.jpg, .depth.png in mm, .pose.txt camera-to-world 4x4,
// camera-intrinsics.txt). Frames are read lazily, one at a time.

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "geometry.hpp"

namespace keepless::eval::vo {

struct PinholeCamera {
  double fx = 0, fy = 0, cx = 0, cy = 0;
  int width = 0, height = 0;
  // RGB-D: ORB-SLAM2's virtual stereo baseline times fx (u_r = u - bf / z),
  // and the depth below which a point counts as close (ThDepth * bf / fx).
  double bf = 0;
  double close_depth = 0;
};

struct RealSequence {
  std::string input;  // the directory given
  std::string name;   // e.g. "kitti00_first200_vamr"
  bool rgbd = false;  // kind "rgbd" (metric depth, SE(3) ATE) or "images" (monocular, Sim(3))
  PinholeCamera camera;
  double fps = 10;
  std::vector<std::string> image_files;  // one per frame
  std::vector<std::string> depth_files;  // RGB-D only
  std::vector<Pose> ground_truth;        // camera to world, one per frame

  // Grey image (CV_8U) and, for RGB-D, depth in metres (CV_32F, 0 = none).
  bool load(std::size_t frame, cv::Mat* grey, cv::Mat* depth, std::string* error) const;
  double path_length() const;
};

// Which frames of a sequence to read: those numbered first..last inclusive
// (last < 0: to the end; numbers from the file names, 000600.png /
// frame-000600.color.jpg, wherever the sequence starts), every step-th of
// them from the first (a faster camera over the same scene: the frame rate
// is divided by step), at most max_frames of them (0: all).
struct FrameSelection {
  int first = 0, last = -1;
  int step = 1;
  int max_frames = 0;
};

bool load_kitti_sequence(const std::string& image_dir, const std::string& calib_file,
                         const std::string& poses_file, const FrameSelection& frames, RealSequence* out,
                         std::string* error);
bool load_rgbd_sequence(const std::string& dir, const FrameSelection& frames, RealSequence* out, std::string* error);

// The same sequence seen by a monocular camera: its depth dropped (a third
// real monocular scene, hand-held indoors, beside KITTI's driving), named
// NAME_mono.
void drop_depth(RealSequence* s);

}  // namespace keepless::eval::vo
