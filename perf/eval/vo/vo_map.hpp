#pragma once
// The VO's map, as ORB-SLAM2 keeps it: keyframes with their keypoints and
// the map point each one observes, map points with their observations,
// descriptor, viewing direction and scale range, and bad flags instead of
// deletion (indices stay valid; a fused point names its replacement).

#include <cstdint>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "orb_frame.hpp"

namespace keepless::eval::vo {

struct MapPoint {
  Eigen::Vector3d X = Eigen::Vector3d::Zero();
  cv::Mat descriptor;                      // 1 x 32, the most distinctive observation's
  std::vector<std::pair<int, int>> obs;    // (keyframe, keypoint)
  int first_kf = 0;                        // creation sequence number of the keyframe that made it
  bool bad = false;
  int replaced_by = -1;
  int visible = 1, found = 1;              // ORB-SLAM2's found ratio
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  double min_distance = 0, max_distance = 0;
  int last_seen_frame = -1;                // tracking scratch
  // Deferred culling: culled, kept for tracking but out of local BA's point
  // blocks (re-triangulated after each local BA) until deleted.
  bool excluded = false;
  // The deferral clock's tick at its exclusion or last match since, as the VO
  // records it: the rule's deletions are checked against it.
  std::uint64_t matched_tick = 0;
  // Deleted by the selector (KeyframeCulling::kCountCulled): its observations then.
  std::vector<std::pair<int, int>> culled_obs;
};

struct KeyFrame {
  int frame = 0;  // image index
  Eigen::Isometry3d Tcw = Eigen::Isometry3d::Identity();
  Frame f;
  std::vector<int> mp;  // per keypoint, -1 = unmapped
  // Per keypoint: the tracker matched its map point in the frame that became
  // this keyframe (before the keyframe's own new points were made).
  std::vector<std::uint8_t> tracked;
  // (keypoint, point) for each point the selector deleted while this keyframe
  // observed it (KeyframeCulling::kCountCulled).
  std::vector<std::pair<int, int>> culled;
  bool bad = false;
  int parent = -1;                                          // set when culled
  Eigen::Isometry3d T_cp = Eigen::Isometry3d::Identity();  // pose relative to the parent then
  Eigen::Vector3d centre() const { return Tcw.inverse().translation(); }
};

class Map {
 public:
  std::vector<KeyFrame> kfs;
  std::vector<MapPoint> points;

  int new_point(const Eigen::Vector3d& X, int kf, int keypoint);
  void add_observation(int p, int kf, int keypoint);
  // ORB-SLAM2's EraseObservation: a point left with <= 2 observations dies.
  void erase_observation(int p, int kf);
  void set_bad(int p);
  // set_bad, remembering p's observations in culled_obs and its keyframes' culled.
  void cull_remembered(int p);
  void replace(int p, int by);  // p's observations move to `by`
  int resolve(int p) const;     // follows replacements; -1 if bad
  // ORB-SLAM2's Observations(): an RGB-D observation counts twice.
  int weighted_observations(int p) const;
  void update_point(int p);  // descriptor, normal, distance range
  // Keyframes sharing >= min_weight points with kf, by weight then index.
  std::vector<std::pair<int, int>> covisibles(int kf, int min_weight) const;
  void cull_keyframe(int kf);  // parent = best covisible; observations erased
  // ORB-SLAM2's KeyFrameCulling test: more than 90 % of kf's points are seen
  // by at least three other keyframes at the same or a finer scale. Its points
  // are the alive ones and those deleted by cull_remembered, with the
  // observations they had then. close_depth > 0 (RGB-D): only keypoints with
  // a depth up to it count.
  bool redundant(int kf, double close_depth) const;
  // The alive points the keyframes observe, each once, in order of first sight.
  std::vector<int> points_of(const std::vector<int>& keyframes) const;
  int alive_points() const;
  int alive_keyframes() const;
  bool in_frustum(int p, const Eigen::Isometry3d& Tcw, const PinholeCamera& cam, double* u, double* v,
                  int* level, double* view_cos) const;
};

// ORB-SLAM2's PredictScale: the level at which a point at `distance` is seen.
int predict_level(const MapPoint& p, double distance);

}  // namespace keepless::eval::vo
