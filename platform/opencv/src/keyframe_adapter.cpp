#include "keepless/opencv/keyframe_adapter.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace keepless::opencv {

const char* to_string(Status s) {
  switch (s) {
    case Status::kOk: return "ok";
    case Status::kBadMatrix: return "bad pose matrix (need 4x4 or 3x4, CV_32F or CV_64F)";
    case Status::kNonFinite: return "non-finite number (or a depth beyond a float's range)";
    case Status::kNotRotation: return "not a rotation";
    case Status::kSizeMismatch: return "point ids, depths, tracked flags or quality not as long as the keypoints";
    case Status::kDuplicatePoint: return "map point id given twice";
    case Status::kReservedPointId: return "map point id uses the reserved top bit";
    case Status::kWindowRejected: return "window rejected the keyframe";
    case Status::kCapacityExceeded: return "more observations or unmapped keypoints than the capacities";
  }
  return "unknown";
}

namespace {

Status pose_from_rotation(const Eigen::Matrix3d& Rcw, const Eigen::Vector3d& tcw, CameraPose* out) {
  if (!Rcw.allFinite() || !tcw.allFinite()) return Status::kNonFinite;
  const double off = (Rcw.transpose() * Rcw - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (off > kRotationTolerance || Rcw.determinant() <= 0) return Status::kNotRotation;
  // Re-orthonormalised through the quaternion: float poses come back unit.
  const Eigen::Matrix3d Rwc = Rcw.transpose();
  const Eigen::Vector3d centre = -(Rwc * tcw);
  if (!centre.allFinite()) return Status::kNonFinite;  // a finite translation near DBL_MAX, rotated
  out->orientation = Eigen::Quaterniond(Rwc).normalized();
  out->centre = centre;
  return Status::kOk;
}

bool finite(const cv::KeyPoint& k) { return std::isfinite(k.pt.x) && std::isfinite(k.pt.y); }

}  // namespace

Status pose_from_tcw(const cv::Mat& Tcw, CameraPose* out) {
  if (Tcw.dims != 2 || Tcw.cols != 4 || (Tcw.rows != 4 && Tcw.rows != 3) || Tcw.channels() != 1 ||
      (Tcw.depth() != CV_32F && Tcw.depth() != CV_64F)) {
    return Status::kBadMatrix;
  }
  // Read in place (a converted copy would allocate per keyframe).
  const bool single = Tcw.depth() == CV_32F;
  const auto at = [&](int r, int c) { return single ? double{Tcw.at<float>(r, c)} : Tcw.at<double>(r, c); };
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) R(r, c) = at(r, c);
    t(r) = at(r, 3);
  }
  if (!R.allFinite() || !t.allFinite()) return Status::kNonFinite;
  if (Tcw.rows == 4) {  // as the Eigen overload: a NaN anywhere is kNonFinite, a wrong last row kBadMatrix
    const double last[4] = {at(3, 0), at(3, 1), at(3, 2), at(3, 3)};
    for (double x : last) {
      if (!std::isfinite(x)) return Status::kNonFinite;
    }
    if (last[0] != 0 || last[1] != 0 || last[2] != 0 || last[3] != 1) return Status::kBadMatrix;
  }
  return pose_from_rotation(R, t, out);
}

Status pose_from_tcw(const Eigen::Isometry3d& Tcw, CameraPose* out) {
  return pose_from_rotation(Tcw.linear(), Tcw.translation(), out);
}

Status pose_from_tcw(const Eigen::Matrix4d& Tcw, CameraPose* out) {
  if (!Tcw.allFinite()) return Status::kNonFinite;
  if (Tcw(3, 0) != 0 || Tcw(3, 1) != 0 || Tcw(3, 2) != 0 || Tcw(3, 3) != 1) return Status::kBadMatrix;
  return pose_from_rotation(Tcw.topLeftCorner<3, 3>(), Tcw.topRightCorner<3, 1>(), out);
}

Status pose_from_tcw(const Eigen::Matrix4f& Tcw, CameraPose* out) {
  return pose_from_tcw(Eigen::Matrix4d(Tcw.cast<double>()), out);
}

Status pose_from_orientation(const Eigen::Quaterniond& q_wc, const Eigen::Vector3d& centre,
                             CameraPose* out) {
  if (!q_wc.coeffs().allFinite() || !centre.allFinite()) return Status::kNonFinite;
  if (std::abs(q_wc.norm() - 1.0) > kRotationTolerance) return Status::kNotRotation;
  out->orientation = q_wc.normalized();
  out->centre = centre;
  return Status::kOk;
}

KeyframeRecord::KeyframeRecord(const core::Capacities& capacities) {
  observations.reserve(capacities.max_observations);
  unmapped.reserve(capacities.max_unmapped_keypoints);
  tracked.reserve(capacities.max_observations);
  quality.reserve(capacities.max_observations);
}

std::size_t KeyframeRecord::memory_bytes() const {
  return observations.capacity() * sizeof(core::Observation) + unmapped.capacity() * sizeof(core::Keypoint) +
         tracked.capacity() * sizeof(std::uint8_t) + quality.capacity() * sizeof(core::PointQuality);
}

std::size_t KeyframeAdapter::memory_bytes() const {
  return record_.memory_bytes() + sorted_.capacity() * sizeof(core::PointId);
}

KeyframeAdapter::KeyframeAdapter(const core::Capacities& capacities)
    : max_observations_(capacities.max_observations),
      max_unmapped_(capacities.max_unmapped_keypoints),
      record_(capacities) {
  sorted_.reserve(capacities.max_observations);
}

Status KeyframeAdapter::convert(core::KeyframeId id, const CameraPose& pose,
                                const std::vector<cv::KeyPoint>& keypoints,
                                const std::vector<core::PointId>& point_ids, const KeyframeExtras& extras,
                                KeyframeRecord* out) {
  const std::vector<cv::KeyPoint>* unmapped = extras.unmapped;
  const std::vector<double>* depths = extras.depths;
  if (keypoints.size() != point_ids.size()) return Status::kSizeMismatch;
  const bool as_list = unmapped != nullptr && extras.unmapped_as == UnmappedAs::kKeypointList;
  const std::size_t listed = as_list ? unmapped->size() : 0;
  const std::size_t reserved_ids = unmapped != nullptr ? unmapped->size() - listed : 0;
  if (keypoints.size() + reserved_ids > max_observations_ || listed > max_unmapped_) {
    return Status::kCapacityExceeded;
  }
  if (depths != nullptr && depths->size() != point_ids.size()) return Status::kSizeMismatch;
  if (extras.tracked != nullptr && extras.tracked->size() != point_ids.size()) return Status::kSizeMismatch;
  if (extras.quality != nullptr) {
    if (extras.quality->size() != point_ids.size()) return Status::kSizeMismatch;
    for (const core::PointQuality& q : *extras.quality) {
      if (!std::isfinite(q.reprojection_error) || !std::isfinite(q.triangulation_angle)) return Status::kNonFinite;
    }
  }
  if (!pose.centre.allFinite() || !pose.orientation.coeffs().allFinite()) return Status::kNonFinite;
  if (std::abs(pose.orientation.norm() - 1.0) > kRotationTolerance) return Status::kNotRotation;
  const Intrinsics& in = extras.intrinsics;
  if (!std::isfinite(in.fx) || !std::isfinite(in.fy) || !std::isfinite(in.cx) || !std::isfinite(in.cy)) {
    return Status::kNonFinite;
  }
  for (const cv::KeyPoint& k : keypoints) {
    if (!finite(k)) return Status::kNonFinite;
  }
  if (unmapped != nullptr) {
    for (const cv::KeyPoint& k : *unmapped) {
      if (!finite(k)) return Status::kNonFinite;
    }
  }
  if (depths != nullptr) {
    for (double z : *depths) {  // keyframe_t carries depths as floats
      if (!(std::abs(z) <= static_cast<double>(std::numeric_limits<float>::max()))) return Status::kNonFinite;
    }
  }
  sorted_.assign(point_ids.begin(), point_ids.end());
  std::sort(sorted_.begin(), sorted_.end());
  if (!sorted_.empty() && (sorted_.back() & kUnmappedBit) != 0) return Status::kReservedPointId;
  if (std::adjacent_find(sorted_.begin(), sorted_.end()) != sorted_.end()) return Status::kDuplicatePoint;

  out->keyframe.id = id;
  for (int i = 0; i < 3; ++i) out->keyframe.centre[i] = pose.centre[i];
  const Eigen::Quaterniond q = pose.orientation.normalized();
  out->keyframe.orientation[0] = q.w();
  out->keyframe.orientation[1] = q.x();
  out->keyframe.orientation[2] = q.y();
  out->keyframe.orientation[3] = q.z();
  out->keyframe.fx = in.fx;
  out->keyframe.fy = in.fy;
  out->keyframe.cx = in.cx;
  out->keyframe.cy = in.cy;
  out->observations.clear();
  for (std::size_t i = 0; i < keypoints.size(); ++i) {
    out->observations.push_back(
        {point_ids[i], keypoints[i].pt.x, keypoints[i].pt.y, depths != nullptr ? (*depths)[i] : 0.0});
  }
  out->mapped = static_cast<std::uint32_t>(keypoints.size());
  out->unmapped.clear();
  if (unmapped != nullptr) {
    for (const cv::KeyPoint& k : *unmapped) {
      if (extras.unmapped_as == UnmappedAs::kKeypointList) {
        out->unmapped.push_back({k.pt.x, k.pt.y});
      } else {
        out->observations.push_back({kUnmappedBit | next_unmapped_, k.pt.x, k.pt.y});
        next_unmapped_ = (next_unmapped_ + 1) & ~kUnmappedBit;
      }
    }
  }
  out->keyframe.unmapped = out->unmapped.empty() ? nullptr : out->unmapped.data();
  out->keyframe.unmapped_count = static_cast<std::uint32_t>(out->unmapped.size());
  // Tracked flags: the mapped keypoints' as given, 0 for reserved-id unmapped ones.
  out->tracked.clear();
  if (extras.tracked != nullptr) {
    for (const std::uint8_t t : *extras.tracked) out->tracked.push_back(t != 0 ? 1 : 0);
    out->tracked.resize(out->observations.size(), 0);
  }
  out->keyframe.tracked = out->tracked.empty() ? nullptr : out->tracked.data();
  out->quality.clear();
  if (extras.quality != nullptr) {
    out->quality.assign(extras.quality->begin(), extras.quality->end());
    out->quality.resize(out->observations.size());
  }
  out->keyframe.quality = out->quality.empty() ? nullptr : out->quality.data();
  return Status::kOk;
}

Status KeyframeAdapter::add_keyframe(core::Window& window, core::KeyframeId id, const CameraPose& pose,
                                     const std::vector<cv::KeyPoint>& keypoints,
                                     const std::vector<core::PointId>& point_ids,
                                     const KeyframeExtras& extras) {
  window_status_ = core::Status::kOk;
  const Status converted = convert(id, pose, keypoints, point_ids, extras, &record_);
  if (converted != Status::kOk) return converted;
  window_status_ = window.add_keyframe(record_.keyframe, record_.observations.data(),
                                       static_cast<std::uint32_t>(record_.observations.size()));
  return window_status_ == core::Status::kOk ? Status::kOk : Status::kWindowRejected;
}

void points_with_verdict(const core::Sparsifier& sparsifier, core::Verdict verdict,
                         std::vector<core::PointId>* out) {
  out->clear();
  const core::PointDecision* d = sparsifier.decisions();
  for (std::uint32_t i = 0; i < sparsifier.decision_count(); ++i) {
    if (d[i].verdict == verdict && (d[i].point & kUnmappedBit) == 0) out->push_back(d[i].point);
  }
}

Status note_keyframe(core::DeferredCulls& deferred, const std::vector<core::PointId>& point_ids,
                     const std::vector<std::uint8_t>* tracked) {
  if (tracked != nullptr && tracked->size() != point_ids.size()) return Status::kSizeMismatch;
  deferred.begin_keyframe();
  for (std::size_t i = 0; i < point_ids.size(); ++i) {
    (void)deferred.observe(point_ids[i], tracked == nullptr || (*tracked)[i] != 0);
  }
  return Status::kOk;
}

void defer_culls(const std::vector<core::PointId>& culled, core::DeferredCulls& deferred,
                 std::vector<core::PointId>* excluded, std::vector<core::PointId>* deleted) {
  excluded->resize(culled.size());
  deleted->resize(culled.size() + deferred.capacity());
  std::uint32_t n_excluded = 0;
  const auto n = static_cast<std::uint32_t>(culled.size());
  deleted->resize(deferred.defer(culled.data(), n, excluded->data(), &n_excluded, deleted->data()));
  excluded->resize(n_excluded);
  std::sort(excluded->begin(), excluded->end());
}

}  // namespace keepless::opencv
