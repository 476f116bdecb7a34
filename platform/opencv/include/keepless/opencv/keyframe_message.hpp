#pragma once
// A KeyframeRecord as the keyframe_t message keepless_node takes. Header-only
// and apart from keyframe_adapter.hpp so that the adapter itself needs no LCM:
// include this only when linking keepless::lcm_types.

#include <algorithm>
#include <cstdint>

#include "keepless/keyframe_t.hpp"
#include "keepless/opencv/keyframe_adapter.hpp"

namespace keepless::opencv {

// Fills `out` (its vectors reused) from `record`. with_unmapped: also send
// the unmapped keypoints as the record holds them (reserved-id observations,
// or the keyframe's native list as unmapped_u/v), so the node's N(p, f)
// counts them as the window's did. The optional arrays carry the observations'
// depths when any is known and the keyframe's intrinsics when set (the
// information cost model), the tracked flags and the point quality (the
// track cost model) when the record has them;
// publisher_id names this process to the node's stream-order policy. No status: the record was validated when it was made.
inline void to_keyframe_message(const KeyframeRecord& record, std::int64_t sequence, std::int64_t utime,
                                std::int32_t image_width, std::int32_t image_height, bool with_unmapped,
                                keepless::keyframe_t* out, std::int64_t publisher_id = 0) {
  const std::uint32_t n =
      with_unmapped ? static_cast<std::uint32_t>(record.observations.size()) : record.mapped;
  out->sequence = sequence;
  out->utime = utime;
  out->keyframe_id = static_cast<std::int64_t>(record.keyframe.id);
  for (int i = 0; i < 3; ++i) out->centre[i] = record.keyframe.centre[i];
  for (int i = 0; i < 4; ++i) out->orientation[i] = record.keyframe.orientation[i];
  out->image_width = image_width;
  out->image_height = image_height;
  out->num_observations = static_cast<std::int32_t>(n);
  out->point_id.resize(n);
  out->u.resize(n);
  out->v.resize(n);
  for (std::uint32_t i = 0; i < n; ++i) {
    const core::Observation& o = record.observations[i];
    out->point_id[i] = static_cast<std::int64_t>(o.point);
    out->u[i] = static_cast<float>(o.u);
    out->v[i] = static_cast<float>(o.v);
  }
  bool any_depth = false;
  for (std::uint32_t i = 0; i < n; ++i) any_depth = any_depth || record.observations[i].depth > 0;
  out->num_depths = any_depth ? static_cast<std::int32_t>(n) : 0;
  out->depth.resize(static_cast<std::size_t>(out->num_depths));
  for (std::size_t i = 0; i < out->depth.size(); ++i) out->depth[i] = static_cast<float>(record.observations[i].depth);
  const core::Keyframe& k = record.keyframe;
  out->num_intrinsics = k.fx > 0 ? 4 : 0;
  out->intrinsics.clear();
  if (k.fx > 0) out->intrinsics = {k.fx, k.fy, k.cx, k.cy};
  const std::size_t m = with_unmapped ? record.unmapped.size() : 0;
  out->num_unmapped = static_cast<std::int32_t>(m);
  out->unmapped_u.resize(m);
  out->unmapped_v.resize(m);
  for (std::size_t i = 0; i < m; ++i) {
    out->unmapped_u[i] = static_cast<float>(record.unmapped[i].u);
    out->unmapped_v[i] = static_cast<float>(record.unmapped[i].v);
  }
  out->publisher_id = publisher_id;
  // Tracked flags (KeyframeExtras::tracked), one per observation sent.
  const bool tracked = !record.tracked.empty();
  out->num_tracked = tracked ? static_cast<std::int32_t>(n) : 0;
  out->tracked.resize(tracked ? n : 0);
  for (std::uint32_t i = 0; tracked && i < n; ++i) out->tracked[i] = static_cast<std::int8_t>(record.tracked[i] != 0);
  // Point quality (KeyframeExtras::quality), one per observation sent.
  const std::uint32_t q = record.quality.empty() ? 0 : n;
  out->num_quality = static_cast<std::int32_t>(q);
  out->track_length.resize(q);
  out->age.resize(q);
  out->reprojection_error.resize(q);
  out->triangulation_angle.resize(q);
  for (std::uint32_t i = 0; i < q; ++i) {
    const core::PointQuality& p = record.quality[i];
    out->track_length[i] = static_cast<std::int32_t>(std::min<std::uint32_t>(p.track_length, INT32_MAX));
    out->age[i] = p.age;
    out->reprojection_error[i] = p.reprojection_error;
    out->triangulation_angle[i] = p.triangulation_angle;
  }
}

}  // namespace keepless::opencv
