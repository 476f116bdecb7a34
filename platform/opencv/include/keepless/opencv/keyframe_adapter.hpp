#pragma once
// keepless::opencv: what an ORB-SLAM-style system holds (cv::KeyPoint, map
// point ids, a pose as cv::Mat Tcw or Eigen) to core::Window keyframes, and
// the Sparsifier's decisions back to sets of map point ids. Every call that
// can fail returns a Status and leaves its outputs and the window unchanged
// (but KeyframeAdapter::last(), the record the window refused).
//
// Unmapped keypoints: the authors' N(p, f) counts every detected keypoint
// near a point, not only the mapped ones. Two ways in (UnmappedAs):
// kReservedIds adds each as a one-view observation of a reserved id (top bit
// set, see kUnmappedBit): one view means the Sparsifier skips it, but every
// cost model that counts observations counts it (the paper's box N(p, f)
// included); they use max_points and max_observations, and the decision sets
// below never contain them. kKeypointList puts them in core's own
// Keyframe::unmapped list (Capacities::max_unmapped_keypoints), which only
// CostModel::kAuthors counts.
//
// Intrinsics and depths (KeyframeExtras) are what CostModel::kInformation
// needs, point quality what CostModel::kTrack needs; the other models
// ignore them.

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "keepless/core/config.hpp"
#include "keepless/core/deferred_culls.hpp"
#include "keepless/core/sparsifier.hpp"
#include "keepless/core/status.hpp"
#include "keepless/core/window.hpp"

namespace keepless::opencv {

enum class [[nodiscard]] Status : std::uint8_t {
  kOk = 0,
  kBadMatrix,        // a pose cv::Mat that is not 4x4 or 3x4 CV_32F/CV_64F
  kNonFinite,        // NaN or infinity in a pose, keypoint or extra; a depth beyond a float's range
  kNotRotation,      // rotation not orthonormal with det +1, or quaternion not unit
  kSizeMismatch,     // point ids, depths, tracked flags or quality not as long as the keypoints
  kDuplicatePoint,   // a map point id given twice for one keyframe
  kReservedPointId,  // a map point id with kUnmappedBit set
  kWindowRejected,   // core::Window::add_keyframe refused it (see window_status())
  kCapacityExceeded,  // more observations or unmapped keypoints than the adapter's capacities
};

const char* to_string(Status s);

// Map point ids must leave this bit clear: it marks unmapped keypoints.
constexpr core::PointId kUnmappedBit = core::PointId{1} << 63;

// Tolerance on |R^T R - I| (max abs entry) and |1 - |q||: float poses from
// ORB-SLAM pass, a scaled or sheared matrix does not.
constexpr double kRotationTolerance = 1e-4;

// A keyframe pose as the window and keyframe_t hold it: the camera centre in
// the world and the world-from-camera unit quaternion.
struct CameraPose {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  // R_wc
};

// From ORB-SLAM's Tcw (world to camera), 4x4 or 3x4, CV_32F or CV_64F.
[[nodiscard]] Status pose_from_tcw(const cv::Mat& Tcw, CameraPose* out);
// From Tcw as an Eigen isometry (pass Twc.inverse() for camera-to-world).
[[nodiscard]] Status pose_from_tcw(const Eigen::Isometry3d& Tcw, CameraPose* out);
// From Tcw as a 4x4 matrix, e.g. ORB-SLAM3's Sophus::SE3f through .matrix()
// (so this header needs no Sophus); the last row must be 0 0 0 1.
[[nodiscard]] Status pose_from_tcw(const Eigen::Matrix4f& Tcw, CameraPose* out);
[[nodiscard]] Status pose_from_tcw(const Eigen::Matrix4d& Tcw, CameraPose* out);
// From the world-from-camera rotation and the centre; q is re-normalised.
[[nodiscard]] Status pose_from_orientation(const Eigen::Quaterniond& q_wc, const Eigen::Vector3d& centre,
                                           CameraPose* out);

// Pinhole intrinsics of the (undistorted) keypoints, pixels; fx = 0: unknown.
struct Intrinsics {
  double fx = 0, fy = 0, cx = 0, cy = 0;
};

enum class UnmappedAs : std::uint8_t { kReservedIds, kKeypointList };

// What a keyframe may carry beside its mapped keypoints, all optional.
struct KeyframeExtras {
  const std::vector<cv::KeyPoint>* unmapped = nullptr;  // the keyframe's other detections
  UnmappedAs unmapped_as = UnmappedAs::kReservedIds;
  Intrinsics intrinsics;  // non-finite: kNonFinite
  // Per mapped keypoint (in point_ids' order), the map point's depth z in
  // this camera, metres, as the SLAM estimates it. As in core, <= 0 means
  // unknown (the observation costs the neutral level); NaN, infinity or a
  // magnitude beyond a float's (keyframe_t carries floats) is refused
  // (kNonFinite), a length other than point_ids' is kSizeMismatch.
  const std::vector<double>* depths = nullptr;
  // Per mapped keypoint (in point_ids' order), nonzero if the tracker matched
  // its map point in its latest frames (core::Keyframe::tracked): on the
  // newest window keyframe those points are never culled. A length other
  // than point_ids' is kSizeMismatch.
  const std::vector<std::uint8_t>* tracked = nullptr;
  // Per mapped keypoint (in point_ids' order), what the map knows about its
  // point (core::PointQuality: map observations, age, reprojection error,
  // triangulation angle) for CostModel::kTrack; reserved-id unmapped
  // keypoints get the unknown quality. A non-finite error or angle is
  // kNonFinite, a length other than point_ids' kSizeMismatch.
  const std::vector<core::PointQuality>* quality = nullptr;
};

// A keyframe converted for the window: what add_keyframe and keyframe_t take.
// Constructed from the capacities it holds room for every keyframe that fits
// them, so that convert() never allocates.
struct KeyframeRecord {
  KeyframeRecord() = default;
  explicit KeyframeRecord(const core::Capacities& capacities);
  // keyframe's pointers are into this record's own vectors: a copy would
  // point into the original's, a move takes the buffers with them.
  KeyframeRecord(const KeyframeRecord&) = delete;
  KeyframeRecord& operator=(const KeyframeRecord&) = delete;
  KeyframeRecord(KeyframeRecord&&) = default;
  KeyframeRecord& operator=(KeyframeRecord&&) = default;
  core::Keyframe keyframe;  // keyframe.unmapped/.tracked/.quality point into the vectors below
  std::vector<core::Observation> observations;  // mapped first, then reserved-id unmapped
  std::uint32_t mapped = 0;                     // observations[0, mapped) are map points
  std::vector<core::Keypoint> unmapped;         // UnmappedAs::kKeypointList
  std::vector<std::uint8_t> tracked;            // per observation, or empty (keyframe.tracked points here)
  std::vector<core::PointQuality> quality;      // per observation, or empty (keyframe.quality points here)
  std::size_t memory_bytes() const;             // the four buffers' reserved bytes
};

// Converts keyframes into a window. Its buffers are reserved once from the
// capacities: a keyframe with more observations (mapped keypoints plus
// reserved-id unmapped ones) than max_observations, or more listed unmapped
// keypoints than max_unmapped_keypoints, is kCapacityExceeded before any
// buffer grows.
class KeyframeAdapter {
 public:
  explicit KeyframeAdapter(const core::Capacities& capacities);

  // keypoints[i] observes map point point_ids[i]. Validates, then fills `out`
  // (allocation-free when `out` was constructed from the same capacities).
  [[nodiscard]] Status convert(core::KeyframeId id, const CameraPose& pose,
                               const std::vector<cv::KeyPoint>& keypoints,
                               const std::vector<core::PointId>& point_ids, const KeyframeExtras& extras,
                               KeyframeRecord* out);
  // `unmapped` (may be null) as reserved ids, no intrinsics or depths.
  [[nodiscard]] Status convert(core::KeyframeId id, const CameraPose& pose,
                               const std::vector<cv::KeyPoint>& keypoints,
                               const std::vector<core::PointId>& point_ids,
                               const std::vector<cv::KeyPoint>* unmapped, KeyframeRecord* out) {
    return convert(id, pose, keypoints, point_ids, as_reserved_ids(unmapped), out);
  }

  // convert() then window.add_keyframe(); on kWindowRejected, window_status()
  // says why (e.g. kCapacityExceeded, kDuplicateKeyframe).
  [[nodiscard]] Status add_keyframe(core::Window& window, core::KeyframeId id, const CameraPose& pose,
                                    const std::vector<cv::KeyPoint>& keypoints,
                                    const std::vector<core::PointId>& point_ids, const KeyframeExtras& extras);
  [[nodiscard]] Status add_keyframe(core::Window& window, core::KeyframeId id, const CameraPose& pose,
                                    const std::vector<cv::KeyPoint>& keypoints,
                                    const std::vector<core::PointId>& point_ids,
                                    const std::vector<cv::KeyPoint>* unmapped = nullptr) {
    return add_keyframe(window, id, pose, keypoints, point_ids, as_reserved_ids(unmapped));
  }
  core::Status window_status() const { return window_status_; }
  // The last record add_keyframe() converted, also one the window then
  // refused (kWindowRejected: what it was sent).
  const KeyframeRecord& last() const { return record_; }
  // Bytes reserved at construction (the record's buffers and the duplicate
  // check's), fixed from then on.
  std::size_t memory_bytes() const;

 private:
  static KeyframeExtras as_reserved_ids(const std::vector<cv::KeyPoint>* unmapped) {
    KeyframeExtras e;
    e.unmapped = unmapped;
    return e;
  }
  std::uint32_t max_observations_;
  std::uint32_t max_unmapped_;
  KeyframeRecord record_;
  std::vector<core::PointId> sorted_;    // duplicate check
  std::uint64_t next_unmapped_ = 0;      // unique reserved ids across keyframes
  core::Status window_status_ = core::Status::kOk;
};

// The map point ids the last run()/update() gave `verdict`, ascending (use
// std::binary_search), without unmapped keypoints. `out` is replaced.
void points_with_verdict(const core::Sparsifier& sparsifier, core::Verdict verdict,
                         std::vector<core::PointId>* out);
inline void culled_points(const core::Sparsifier& s, std::vector<core::PointId>* out) {
  points_with_verdict(s, core::Verdict::kCull, out);
}

// Deferred culling (core::Params::defer_keyframes, core::DeferredCulls; the
// rule is in keepless/core/deferred_culls.hpp). Leave `deferred`'s excluded
// points out of the windows you build (they are decided, and out of BA).
//
// A new keyframe: one tick of the clock; each of its map points the tracker
// matched (tracked[i] nonzero, in point_ids' order; every one when `tracked`
// is null) is matched now. kSizeMismatch (nothing changed) for a `tracked`
// of another length.
[[nodiscard]] Status note_keyframe(core::DeferredCulls& deferred, const std::vector<core::PointId>& point_ids,
                                   const std::vector<std::uint8_t>* tracked);
// After a decision: the `culled` map points become excluded (`excluded`:
// leave them out of local BA, keep them for tracking); those `deferred`
// cannot hold, and those its rule deletes at this tick, are `deleted`
// (remove them from the map). Both ascending; outputs replaced. Allocation-free
// when `excluded` has capacity for the culls and `deleted` for the culls plus
// deferred.capacity() (reserve them once: max_points, max_points + deferred.capacity()).
void defer_culls(const std::vector<core::PointId>& culled, core::DeferredCulls& deferred,
                 std::vector<core::PointId>* excluded, std::vector<core::PointId>* deleted);

}  // namespace keepless::opencv
