#include "real_vo.hpp"

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core/eigen.hpp>

#include "metrics.hpp"
#include "vo_internals.hpp"

namespace keepless::eval::vo {

const char* to_string(Selector s) {
  switch (s) {
    case Selector::kOriginal: return "original";
    case Selector::kKeepless: return "keepless";
    case Selector::kRandom: return "random";
    case Selector::kLongestTrack: return "longest_track";
    case Selector::kAnms: return "anms";
  }
  return "unknown";
}

namespace detail {
namespace {

core::Capacities window_capacities() {
  core::Capacities c;
  c.max_keyframes = 32;
  c.max_points = 1 << 16;
  c.max_observations = 1 << 16;
  c.max_pair_arcs = 1 << 20;
  c.max_unmapped_keypoints = 1 << 16;  // every keypoint of the window may be unmapped, as for max_observations
  return c;
}

// The options' parameters with the authors' grid laid over this camera's image.
core::Params vo_params(const core::Params& p, const PinholeCamera& cam) {
  core::Params q = p;
  q.image_width = cam.width;
  q.image_height = cam.height;
  return q;
}

}  // namespace

Vo::Vo(const RealSequence& s, const RealVoOptions& o)
    : seq_(s), opt_(o), cam_(s.camera),
      extractor_(o.features > 0 ? o.features : (s.rgbd ? 1000 : 2000), s.camera),
      rng_(mix(o.seed, 0x5eed)), adapter_(window_capacities()), window_(window_capacities()),
      sparsifier_(window_capacities(), vo_params(o.params, s.camera)),
      deferred_(window_capacities().max_points, o.params.defer_keyframes),
      fraction_budget_(window_capacities().max_points) {
  K_ << cam_.fx, 0, cam_.cx, 0, cam_.fy, cam_.cy, 0, 0, 1;
  cv::eigen2cv(K_, Kcv_);
}

// A frame's features depend on its image and the extractor's settings only
// (never on the seed or the selector), and every run of a process reads the
// same frames: each is extracted once per process (an eval process runs the
// original and every selector at every fraction on one sequence).
bool Vo::features_of(int i, Frame* out) {
  static std::map<std::pair<std::string, int>, Frame> cache;  // (image file, features) -> features
  const std::pair<std::string, int> key{seq_.image_files[static_cast<std::size_t>(i)], extractor_.features()};
  const auto hit = cache.find(key);
  if (hit != cache.end()) {
    *out = hit->second;
    out->descriptors = hit->second.descriptors.clone();
    return true;
  }
  cv::Mat grey, depth;
  if (!seq_.load(static_cast<std::size_t>(i), &grey, &depth, &result_.error)) return false;
  extractor_.extract(grey, seq_.rgbd ? &depth : nullptr, out);
  Frame& kept = cache[key];
  kept = *out;
  kept.descriptors = out->descriptors.clone();
  return true;
}

Eigen::Isometry3d Vo::final_pose(int kf) const {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (int hops = 0; kf >= 0 && hops < 10000; ++hops) {
    const KeyFrame& k = map_.kfs[static_cast<std::size_t>(kf)];
    if (!k.bad) return T * k.Tcw;
    T = T * k.T_cp;
    kf = k.parent;
  }
  return T;
}

RealRunResult Vo::run() {
  const Clock::time_point start = Clock::now();
  result_.frames = static_cast<int>(seq_.image_files.size());
  bool was_tracked = false;
  const bool debug = std::getenv("KEEPLESS_EVAL_DEBUG") != nullptr;
  for (int i = 0; i < result_.frames; ++i) {
    TrackedFrame cur;
    cur.index = i;
    if (!features_of(i, &cur.f)) return result_;
    bool tracked = false;
    const bool tracking = initialised_;
    if (!tracking) {
      if (seq_.rgbd) {
        if (cur.f.keys.size() >= 500) {
          initialize_rgbd(cur);
          tracked = true;
        }
      } else {
        tracked = initialize_monocular(cur);
      }
      if (tracked) last_ = cur;
    } else {
      const Eigen::Isometry3d before = last_.Tcw;
      tracked = track(cur);
      // The motion model is one frame's motion: after a lost frame, `before`
      // is several frames back, so the frame relocalised gives none
      // (ORB-SLAM2 clears mVelocity too).
      have_velocity_ = tracked && was_tracked;
      if (have_velocity_) velocity_ = cur.Tcw * before.inverse();
      if (tracked) last_ = cur;
    }
    if (tracked) {
      ++result_.frames_tracked;
      const int ref = reference_kf_;
      records_.push_back({i, ref, cur.Tcw * map_.kfs[static_cast<std::size_t>(ref)].Tcw.inverse()});
    } else {
      if (was_tracked) ++result_.tracking_losses;
      // Scored at the last tracked pose: a lost run cannot look better than
      // it is (frames before the first tracked one have no pose to hold).
      if (!records_.empty()) records_.push_back({i, records_.back().ref_kf, records_.back().T_cr});
    }
    was_tracked = tracked;
    if (debug && tracking && trace_.inliers < 0) {
      std::fprintf(stderr, "  [%s %s] frame %d: lost, no pose (motion model and relocalisation failed)\n",
                   seq_.name.c_str(), to_string(opt_.selector), i);
    } else if (debug && tracking && !tracked) {
      std::fprintf(stderr, "  [%s %s] frame %d: lost, %d inliers of %d local points (needs %d)\n", seq_.name.c_str(),
                   to_string(opt_.selector), i, trace_.inliers, trace_.local_points, trace_.needed);
    } else if (debug && tracking) {
      std::fprintf(stderr, "  [%s %s] frame %d: %d inliers of %d local points, reference keyframe's points seen 3+ "
                   "times %d%s; map %d KFs, %d points\n", seq_.name.c_str(), to_string(opt_.selector), i,
                   trace_.inliers, trace_.local_points, trace_.ref_matches, trace_.keyframe ? ", keyframe" : "",
                   map_.alive_keyframes(), map_.alive_points());
    }
    if (opt_.verbose && (i % 50 == 0 || i + 1 == result_.frames)) {
      std::fprintf(stderr, "  [%s %s] frame %d: tracked %d, %d KFs, %d MPs, %.1f s\n", seq_.name.c_str(),
                   to_string(opt_.selector), i, result_.frames_tracked, map_.alive_keyframes(), map_.alive_points(),
                   seconds_since(start));
    }
  }
  result_.total_seconds = seconds_since(start);
  result_.map_points = map_.alive_points();
  result_.keyframes = map_.alive_keyframes();
  for (const MapPoint& m : map_.points) {
    if (!m.bad) result_.observations += static_cast<std::int64_t>(m.obs.size());
  }
  const double windows = static_cast<double>(result_.selector.windows);
  result_.mean_kept_fraction = windows > 0 ? kept_fraction_sum_ / windows : 1.0;
  std::vector<Pose> estimate, truth;
  for (const FrameRecord& r : records_) {
    const Eigen::Isometry3d Twc = (r.T_cr * final_pose(r.ref_kf)).inverse();
    Pose p;
    p.q = Eigen::Quaterniond(Twc.linear()).normalized();
    p.t = Twc.translation();
    estimate.push_back(p);
    truth.push_back(seq_.ground_truth[static_cast<std::size_t>(r.frame)]);
  }
  if (estimate.empty()) {
    // Never tracked (it never initialised): held still at the origin over
    // every frame, a failure scored as one, never the ATE of nothing (0).
    estimate.assign(seq_.ground_truth.size(), Pose{});
    truth = seq_.ground_truth;
  }
  if (!estimate.empty()) {
    const Ate ate = absolute_trajectory_error(estimate, truth, !seq_.rgbd);
    result_.ate_m = ate.rms_m;
    result_.ate_r_deg = ate.rms_r_deg;
    std::vector<Eigen::Vector3d> src, dst;
    for (std::size_t k = 0; k < estimate.size(); ++k) src.push_back(estimate[k].t), dst.push_back(truth[k].t);
    const Alignment a = umeyama(src, dst, !seq_.rgbd);
    for (Pose& p : estimate) p.t = a.s * (a.R * p.t) + a.t;
  }
  result_.estimate = std::move(estimate);
  result_.ground_truth = std::move(truth);
  return result_;
}

}  // namespace detail

RealRunResult run_real_vo(const RealSequence& sequence, const RealVoOptions& options) {
  cv::setNumThreads(1);
  cv::theRNG().state = options.seed;
  detail::Vo vo(sequence, options);
  return vo.run();
}

}  // namespace keepless::eval::vo
