#pragma once
// The real VO's pictures: trajectories vs ground truth, and one keyframe's
// keypoints kept/culled. (Its statistics and JSON are issue 11's, run_record.hpp.)

#include <string>

#include "real_vo.hpp"

namespace keepless::eval::vo {

bool write_trajectory_svg(const std::string& path, const std::string& title, const RealRunResult& original,
                          const RealRunResult& ours);
bool write_keypoints_svg(const std::string& path, const std::string& title, const RealRunResult& ours,
                         int width, int height);

}  // namespace keepless::eval::vo
