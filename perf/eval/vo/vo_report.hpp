#pragma once
// keepless_vo_eval's output: per-run lines, the per-input summary (mean and
// sd over seeds, equal kept fraction), the JSON contract of issue 11, and
// the SVGs (trajectories; one keyframe's keypoints kept/culled).

#include <cstdint>
#include <string>
#include <vector>

#include "real_vo.hpp"

namespace keepless::eval::vo {

struct MeanSd {
  double mean = 0, sd = 0;
};
MeanSd mean_sd(const std::vector<double>& x);

// One input at one M over its seeds: runs[s] per variant.
struct Comparison {
  std::string input, name;
  bool rgbd = false;
  std::int64_t M = 0;
  int frames = 0;
  std::vector<RealRunResult> original, keepless, random, longest, anms;
};

std::string json_run(const Comparison& c);
void print_table(const std::vector<Comparison>& all);
bool write_trajectory_svg(const std::string& path, const std::string& title, const RealRunResult& original,
                          const RealRunResult& ours);
bool write_keypoints_svg(const std::string& path, const std::string& title, const RealRunResult& ours,
                         int width, int height);

}  // namespace keepless::eval::vo
