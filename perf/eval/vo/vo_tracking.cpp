#include "vo_internals.hpp"

#include <algorithm>

#include <opencv2/calib3d.hpp>

#include "vo_ba.hpp"
#include "vo_geometry.hpp"

namespace keepless::eval::vo::detail {

int Vo::optimize(TrackedFrame& cur) {
  std::vector<Eigen::Vector3d> X;
  std::vector<BaObservation> obs;
  std::vector<int> keypoint;
  for (std::size_t i = 0; i < cur.mp.size(); ++i) {
    const int p = cur.mp[i] >= 0 ? map_.resolve(cur.mp[i]) : -1;
    cur.mp[i] = p;
    if (p < 0) continue;
    X.push_back(map_.points[static_cast<std::size_t>(p)].X);
    BaObservation o;
    o.point = static_cast<int>(X.size()) - 1;
    o.u = cur.f.keys[i].pt.x;
    o.v = cur.f.keys[i].pt.y;
    o.ur = cur.f.ur[i];
    o.level = cur.f.keys[i].octave;
    obs.push_back(o);
    keypoint.push_back(static_cast<int>(i));
  }
  if (obs.size() < 3) return 0;
  std::vector<bool> outlier;
  const int inliers = optimize_pose(cam_, X, obs, &cur.Tcw, &outlier);
  for (std::size_t k = 0; k < obs.size(); ++k) {
    if (outlier[k]) cur.mp[static_cast<std::size_t>(keypoint[k])] = -1;
  }
  return inliers;
}

bool Vo::estimate_pose(TrackedFrame& cur, bool guess) {
  std::vector<cv::Point3f> object;
  std::vector<cv::Point2f> image;
  std::vector<int> keypoint;
  std::vector<int> all;
  for (std::size_t i = 0; i < cur.mp.size(); ++i) {
    if (cur.mp[i] >= 0) all.push_back(static_cast<int>(i));
  }
  if (all.size() < 15) return false;
  for (int k : shuffled(all.size(), rng_)) {
    const int i = all[static_cast<std::size_t>(k)];
    const Eigen::Vector3d& X = map_.points[static_cast<std::size_t>(cur.mp[static_cast<std::size_t>(i)])].X;
    object.emplace_back(float(X.x()), float(X.y()), float(X.z()));
    image.push_back(cur.f.keys[static_cast<std::size_t>(i)].pt);
    keypoint.push_back(i);
  }
  const Eigen::Isometry3d start = cur.Tcw;
  const std::vector<int> matched = cur.mp;
  const PoseBlock b = to_block(cur.Tcw);
  cv::Mat rvec = (cv::Mat_<double>(3, 1) << b[0], b[1], b[2]);
  cv::Mat tvec = (cv::Mat_<double>(3, 1) << b[3], b[4], b[5]);
  std::vector<int> inliers;
  const bool ok = cv::solvePnPRansac(object, image, Kcv_, cv::noArray(), rvec, tvec, guess, guess ? 100 : 300,
                                     4.0f, 0.99, inliers, cv::SOLVEPNP_EPNP);
  const bool from_pnp = ok && inliers.size() >= 10;
  if (from_pnp) {
    cur.Tcw = pose_from_cv(rvec, tvec);
    std::vector<bool> in(keypoint.size(), false);
    for (int k : inliers) in[static_cast<std::size_t>(k)] = true;
    for (std::size_t k = 0; k < keypoint.size(); ++k) {
      if (!in[k]) cur.mp[static_cast<std::size_t>(keypoint[k])] = -1;
    }
  } else if (!guess) {
    return false;
  }
  if (optimize(cur) >= 10) return true;
  if (!from_pnp) return false;
  // solvePnPRansac can report hundreds of inliers and still return a pose far
  // off (EPnP re-solved over them: seen 9e8 away, or turned by 180 degrees),
  // from which the refinement keeps no match. Refine again from where we
  // started, with the matches before PnP, before calling the frame lost
  // (KITTI 00: the original's losses at frames 25 and 41 of seeds 13 and 14).
  cur.Tcw = start;
  cur.mp = matched;
  return optimize(cur) >= 10;
}

bool Vo::relocalise(TrackedFrame& cur) {
  // Every point of the last keyframes, matched by descriptor alone.
  std::vector<int> recent_kfs;
  for (int k = static_cast<int>(map_.kfs.size()) - 1; k >= 0 && recent_kfs.size() < 10; --k) {
    if (!map_.kfs[static_cast<std::size_t>(k)].bad) recent_kfs.push_back(k);
  }
  const std::vector<int> points = map_.points_of(recent_kfs);
  std::fill(cur.mp.begin(), cur.mp.end(), -1);
  std::vector<int> best_dist(cur.mp.size(), 256);
  for (int p : points) {
    const cv::Mat& d = map_.points[static_cast<std::size_t>(p)].descriptor;
    int b1 = 256, b2 = 256, bi = -1;
    for (int j = 0; j < cur.f.descriptors.rows; ++j) {
      const int h = hamming(d, 0, cur.f.descriptors, j);
      if (h < b1) b2 = b1, b1 = h, bi = j;
      else if (h < b2) b2 = h;
    }
    if (bi < 0 || b1 > kHammingLow || b1 > 0.75 * b2) continue;
    if (b1 < best_dist[static_cast<std::size_t>(bi)]) {
      best_dist[static_cast<std::size_t>(bi)] = b1;
      cur.mp[static_cast<std::size_t>(bi)] = p;
    }
  }
  return estimate_pose(cur, false);
}

std::vector<int> Vo::local_map(const TrackedFrame& cur, int* reference) {
  std::vector<int> count(map_.kfs.size(), 0);
  for (int p : cur.mp) {
    if (p < 0) continue;
    for (const auto& o : map_.points[static_cast<std::size_t>(p)].obs) ++count[static_cast<std::size_t>(o.first)];
  }
  std::vector<int> kfs;
  int best = -1;
  for (std::size_t k = 0; k < count.size(); ++k) {
    if (count[k] == 0 || map_.kfs[k].bad) continue;
    kfs.push_back(static_cast<int>(k));
    if (best < 0 || count[k] > count[static_cast<std::size_t>(best)]) best = static_cast<int>(k);
  }
  std::sort(kfs.begin(), kfs.end(), [&](int a, int b) {
    return count[static_cast<std::size_t>(a)] != count[static_cast<std::size_t>(b)]
               ? count[static_cast<std::size_t>(a)] > count[static_cast<std::size_t>(b)]
               : a > b;
  });
  if (kfs.size() > 80) kfs.resize(80);
  std::vector<char> in(map_.kfs.size(), 0);
  for (int k : kfs) in[static_cast<std::size_t>(k)] = 1;
  const std::size_t direct = kfs.size();
  for (std::size_t i = 0; i < direct && kfs.size() < 80; ++i) {
    const auto cov = map_.covisibles(kfs[i], 1);
    for (std::size_t c = 0; c < cov.size() && c < 10; ++c) {
      if (!in[static_cast<std::size_t>(cov[c].first)]) {
        in[static_cast<std::size_t>(cov[c].first)] = 1;
        kfs.push_back(cov[c].first);
        break;  // ORB-SLAM2 takes the first new one of each
      }
    }
  }
  if (best >= 0) *reference = best;
  return map_.points_of(kfs);
}

bool Vo::track(TrackedFrame& cur) {
  trace_ = FrameTrace{};
  cur.mp.assign(cur.f.keys.size(), -1);
  cur.outlier.assign(cur.f.keys.size(), false);
  cur.Tcw = have_velocity_ ? velocity_ * last_.Tcw : last_.Tcw;
  const double th = seq_.rgbd ? 7 : 15;
  bool ok = false;
  if (have_velocity_) {
    int m = search_by_projection(cur, last_, map_, cam_, th);
    if (m < 20) {
      std::fill(cur.mp.begin(), cur.mp.end(), -1);
      m = search_by_projection(cur, last_, map_, cam_, 2 * th);
    }
    ok = m >= 15 && estimate_pose(cur, true);
  }
  bool relocalised = false;
  if (!ok) {
    cur.Tcw = last_.Tcw;
    ok = relocalise(cur);
    relocalised = ok;
    if (ok) relocalised_frame_ = cur.index;
  }
  if (!ok) return false;
  int reference = reference_kf_;
  const std::vector<int> points = local_map(cur, &reference);
  const bool recent = cur.index < relocalised_frame_ + 2;
  search_local_points(cur, map_, points, cam_, recent ? 5 : (seq_.rgbd ? 3 : 1));
  const int inliers = optimize(cur);
  trace_.inliers = inliers;
  trace_.needed = relocalised || recent ? kMinTrackedAfterRelocalisation : kMinTrackedInliers;
  trace_.local_points = static_cast<int>(points.size());
  if (inliers < trace_.needed) return false;
  for (int p : cur.mp) {
    if (p < 0) continue;
    ++map_.points[static_cast<std::size_t>(p)].found;
    if (map_.points[static_cast<std::size_t>(p)].excluded) ++result_.excluded_matches;
  }
  reference_kf_ = reference;
  trace_.keyframe = need_keyframe(cur, inliers, &trace_.ref_matches);
  if (trace_.keyframe) insert_keyframe(cur);
  return true;
}

bool Vo::need_keyframe(const TrackedFrame& cur, int inliers, int* ref_matches_out) const {
  const int kfs = map_.alive_keyframes();
  const int max_frames = static_cast<int>(seq_.fps);
  if (cur.index < relocalised_frame_ + max_frames && kfs > max_frames) return false;
  const int min_obs = kfs <= 2 ? 2 : 3;
  int& ref_matches = *ref_matches_out;
  ref_matches = 0;
  for (int p : map_.kfs[static_cast<std::size_t>(reference_kf_)].mp) {
    if (p >= 0 && !map_.points[static_cast<std::size_t>(p)].bad && map_.weighted_observations(p) >= min_obs) {
      ++ref_matches;
    }
  }
  int tracked_close = 0, untracked_close = 0;
  if (seq_.rgbd) {
    for (std::size_t i = 0; i < cur.f.depth.size(); ++i) {
      if (cur.f.depth[i] > 0 && cur.f.depth[i] < cam_.close_depth) (cur.mp[i] >= 0 ? tracked_close : untracked_close)++;
    }
  }
  const bool need_close = seq_.rgbd && tracked_close < 100 && untracked_close > 70;
  const double ratio = kfs < 2 ? 0.4 : (seq_.rgbd ? 0.75 : opt_.keyframe_ratio);
  // c1a (max frames) and c1b (min frames, mapping idle: always, it runs inline) hold.
  const bool c2 = (inliers < ref_matches * ratio || need_close) && inliers > 15;
  // The translation/rotation rule: a keyframe at least every 20 degrees.
  const Eigen::Isometry3d rel = cur.Tcw * map_.kfs[static_cast<std::size_t>(reference_kf_)].Tcw.inverse();
  const bool turned = Eigen::AngleAxisd(Eigen::Matrix3d(rel.linear())).angle() > 20.0 * M_PI / 180.0;
  const bool c1a = cur.index >= last_kf_frame_ + max_frames;
  const bool weak = inliers < opt_.weak_keyframe;
  return (c2 || ((turned || c1a || weak) && inliers > 15));
}

}  // namespace keepless::eval::vo::detail
