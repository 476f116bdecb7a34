#pragma once
// What the VO's map knows about a point beyond the window, as
// core::PointQuality (CostModel::kTrack): its observations in the map, its
// age in keyframes, its reprojection error at the current poses (the local
// BA's residual) and the largest angle between its observing rays.

#include "keepless/core/window.hpp"
#include "real_sequence.hpp"
#include "vo_map.hpp"

namespace keepless::eval::vo {

// `kf`: the keyframe being decided (ages count from the point's first).
core::PointQuality point_quality(const Map& map, int p, int kf, const PinholeCamera& cam);

}  // namespace keepless::eval::vo
