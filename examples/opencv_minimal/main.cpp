// keepless from an ORB-SLAM-style tracker's own types: cv::KeyPoint, map
// point ids and a Tcw pose go through keepless::opencv into a sliding window
// of K keyframes; after each keyframe the window is decided incrementally
// and the culled map points are deleted, as a local mapper would before its
// local bundle adjustment. The tracker here is synthetic (a camera moving
// along a textured wall), so the example runs anywhere.
//
// Why 300 points per keyframe: the paper's network lets each pair of
// keyframes keep at most M (default 100) of the points they share, and a
// point is culled only when it loses more than half its pairs. With 60
// points per keyframe no pair shares more than 60 < M points, every pair
// keeps all of them, and nothing is culled: M is a budget per keyframe pair,
// so keepless only acts where keyframes share more than M points.

#include <cstdint>
#include <cstdio>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "keepless/core/config.hpp"
#include "keepless/core/sparsifier.hpp"
#include "keepless/opencv/keyframe_adapter.hpp"
#include "keepless/platform/sliding_window.hpp"

namespace {

constexpr std::uint32_t kWindow = 5;                // K keyframes
constexpr std::uint32_t kPointsPerKeyframe = 300;   // see above: more than M shared per pair
constexpr std::uint32_t kStep = 60;                 // new points per keyframe
constexpr std::uint32_t kKeyframes = 12;

// The synthetic tracker: keyframe k sees wall points [k * kStep, k * kStep +
// kPointsPerKeyframe) that the local mapper has not deleted; Tcw moves 0.2 m
// a keyframe along x. Points are spread over a 640 x 480 image.
struct TrackedKeyframe {
  Eigen::Matrix4f Tcw;  // ORB-SLAM3: the KeyFrame's Sophus::SE3f GetPose().matrix()
  std::vector<cv::KeyPoint> keypoints;
  std::vector<keepless::core::PointId> ids;  // keypoints[i] observes map point ids[i]
};

TrackedKeyframe track(std::uint32_t k, const std::vector<bool>& deleted) {
  TrackedKeyframe kf;
  kf.Tcw = Eigen::Matrix4f::Identity();
  kf.Tcw(0, 3) = -0.2f * static_cast<float>(k);  // camera centre at x = 0.2 k
  for (std::uint32_t i = 0; i < kPointsPerKeyframe; ++i) {
    const std::uint32_t id = k * kStep + i;
    if (deleted[id]) continue;
    const float u = 10.0f + static_cast<float>((id * 37) % 620) - 0.5f * static_cast<float>(i);
    const float v = 10.0f + static_cast<float>((id * 53) % 460);
    kf.keypoints.emplace_back(u < 0 ? u + 620 : u, v, 31.0f);
    kf.ids.push_back(id);
  }
  return kf;
}

}  // namespace

int main() {
  std::vector<bool> deleted(kKeyframes * kStep + kPointsPerKeyframe, false);
  std::uint32_t culled_total = 0;
  // snippet-begin: quickstart
  namespace kl = keepless;
  kl::core::Capacities caps;  // fixed at start: nothing allocates per keyframe
  caps.max_keyframes = kWindow;
  caps.max_points = 4096;
  caps.max_observations = kWindow * kPointsPerKeyframe;
  caps.max_pair_arcs = 16384;
  kl::core::Params params;  // the paper's method: M = 100, theta = 0.5, 64x48 box
  kl::platform::SlidingWindow window(caps, kPointsPerKeyframe, /*max_event_ids=*/0);
  kl::core::Sparsifier sparsifier(caps, params, kl::core::SolveMode::kIncremental);
  kl::opencv::KeyframeAdapter adapter(caps);
  kl::opencv::KeyframeRecord record(caps);
  kl::opencv::CameraPose pose;
  std::vector<kl::core::PointId> culled;
  culled.reserve(caps.max_points);
  for (std::uint32_t k = 0; k < kKeyframes; ++k) {
    const TrackedKeyframe kf = track(k, deleted);  // your tracker's new keyframe
    if (kl::opencv::pose_from_tcw(kf.Tcw, &pose) != kl::opencv::Status::kOk ||
        adapter.convert(k, pose, kf.keypoints, kf.ids, nullptr, &record) != kl::opencv::Status::kOk ||
        window.push(record.keyframe, record.observations.data(),
                    static_cast<std::uint32_t>(record.observations.size())) != kl::core::Status::kOk ||
        sparsifier.update(window.window()) != kl::core::Status::kOk) {
      return 1;
    }
    kl::opencv::culled_points(sparsifier, &culled);  // ascending map point ids
    for (kl::core::PointId id : culled) deleted[id] = true;  // your map: SetBadFlag()
    if (window.drop_points(culled.data(), static_cast<std::uint32_t>(culled.size())) != kl::core::Status::kOk) {
      return 1;
    }
    std::printf("keyframe %u: %u points in the window, culled %zu\n", k, sparsifier.summary().points,
                culled.size());
    culled_total += static_cast<std::uint32_t>(culled.size());
  }
  // snippet-end: quickstart
  std::printf("opencv_minimal: culled %u map points over %u keyframes\n", culled_total, kKeyframes);
  return culled_total > 0 ? 0 : 1;  // the example exists to show a cull
}
