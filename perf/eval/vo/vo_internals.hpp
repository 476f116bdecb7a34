// The real VO's class, shared by its files: real_vo.cpp (the run),
// vo_tracking.cpp, vo_initialization.cpp, vo_local_mapping.cpp and
// vo_culls.cpp (what each selector culls, and deferred culling).
#pragma once

#include <chrono>
#include <memory>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "keepless/core/deferred_culls.hpp"
#include "keepless/core/keep_thresholds.hpp"
#include "keepless/core/sparsifier.hpp"
#include "keepless/core/window.hpp"
#include "keepless/opencv/keyframe_adapter.hpp"
#include "matching.hpp"
#include "prng.hpp"
#include "real_vo.hpp"
#include "vo_map.hpp"

namespace keepless::eval::vo::detail {

using Clock = std::chrono::steady_clock;
inline double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// ORB-SLAM2's tracking thresholds.
constexpr int kMinTrackedInliers = 30;
constexpr int kMinTrackedAfterRelocalisation = 50;

struct FrameRecord {
  int frame = 0, ref_kf = 0;
  Eigen::Isometry3d T_cr = Eigen::Isometry3d::Identity();
};

class Vo {
 public:
  Vo(const RealSequence& s, const RealVoOptions& o);

  RealRunResult run();

 private:
  bool track(TrackedFrame& cur);
  bool estimate_pose(TrackedFrame& cur, bool guess);
  bool relocalise(TrackedFrame& cur);
  int optimize(TrackedFrame& cur);
  std::vector<int> local_map(const TrackedFrame& cur, int* reference);
  bool initialize_monocular(TrackedFrame& cur);
  void initialize_rgbd(TrackedFrame& cur);
  bool need_keyframe(const TrackedFrame& cur, int inliers, int* ref_matches) const;
  int insert_keyframe(TrackedFrame& cur);
  void local_mapping(int kf);
  void point_culling(int kf);
  void create_points(int kf);
  void search_in_neighbours(int kf);
  std::vector<int> local_keyframes(int kf, int most) const;
  void measure_windows(int kf);
  struct Replay {
    std::unique_ptr<core::Window> window;
    std::unique_ptr<core::Sparsifier> sparsifier;
  };
  void replay(const std::vector<int>& keyframes, std::unique_ptr<Replay>* state);
  // The points the selector culls at keyframe kf (none when its window is refused).
  std::vector<core::PointId> select_points(int kf, const std::vector<int>& local);
  void remove_culls(const std::vector<core::PointId>& culls);
  void delete_cull(int p);
  // fix_first: hold local.front() too (the two-view start's gauge).
  void local_ba(const std::vector<int>& local, bool fix_first);
  bool deferring() const { return opt_.params.defer_keyframes > 0 && opt_.selector != Selector::kOriginal; }
  void note_matches(int kf);
  void retriangulate_excluded(const std::vector<int>& local);
  void refine_local_poses(const std::vector<int>& local);
  void keyframe_culling(int kf);
  Eigen::Isometry3d final_pose(int kf) const;
  bool features_of(int i, Frame* out);
  int neighbours() const { return seq_.rgbd ? 10 : 20; }

  const RealSequence& seq_;
  const RealVoOptions& opt_;
  const PinholeCamera cam_;
  OrbExtractor extractor_;
  Rng rng_;
  Eigen::Matrix3d K_;
  cv::Mat Kcv_;
  Map map_;
  std::vector<int> recent_;  // ORB-SLAM2's mlpRecentAddedMapPoints
  TrackedFrame last_;
  bool have_velocity_ = false;
  Eigen::Isometry3d velocity_ = Eigen::Isometry3d::Identity();
  int last_kf_frame_ = -1000, reference_kf_ = -1, relocalised_frame_ = -1000;
  bool initialised_ = false;
  TrackedFrame init_ref_;
  bool have_init_ref_ = false;
  std::vector<TrackedFrame> pending_;  // frames after init_ref_ while initialisation waits for parallax
  std::vector<FrameRecord> records_;
  // The last frame's tracking, printed per frame under KEEPLESS_EVAL_DEBUG
  // (why a run lost tracking: inliers against those needed).
  struct FrameTrace {
    int inliers = -1, needed = 0, local_points = 0, ref_matches = 0;
    bool keyframe = false;
  } trace_;

  opencv::KeyframeAdapter adapter_;
  core::Window window_;
  core::Sparsifier sparsifier_;
  core::DeferredCulls deferred_;  // params.defer_keyframes: excluded points until deleted
  core::FractionBudget fraction_budget_;  // a kept fraction's count for this run's selector (keepless's is the core's)
  double kept_fraction_sum_ = 0;
  std::unique_ptr<Replay> replay_local_, replay_sliding_;  // measure_windows with replay_capacities
  std::size_t marked_culls_ = 0;
  RealRunResult result_;
};

}  // namespace keepless::eval::vo::detail
