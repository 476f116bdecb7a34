#include "vo_internals.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <functional>
#include <utility>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "vo_ba.hpp"
#include "vo_geometry.hpp"

namespace keepless::eval::vo::detail {

void Vo::initialize_rgbd(TrackedFrame& cur) {
  cur.Tcw = Eigen::Isometry3d::Identity();
  cur.mp.assign(cur.f.keys.size(), -1);
  cur.outlier.assign(cur.f.keys.size(), false);
  KeyFrame k;
  k.frame = cur.index;
  k.f = cur.f;
  k.mp.assign(cur.f.keys.size(), -1);
  map_.kfs.push_back(std::move(k));
  for (std::size_t i = 0; i < cur.f.depth.size(); ++i) {
    const double z = cur.f.depth[i];
    if (z <= 0) continue;
    const cv::Point2f& pt = cur.f.keys[i].pt;
    map_.new_point(Eigen::Vector3d((pt.x - cam_.cx) * z / cam_.fx, (pt.y - cam_.cy) * z / cam_.fy, z), 0,
                   static_cast<int>(i));
  }
  cur.mp = map_.kfs[0].mp;
  reference_kf_ = 0;
  last_kf_frame_ = cur.index;
  result_.keyframes_created = 1;
  initialised_ = true;
}

bool Vo::initialize_monocular(TrackedFrame& cur) {
  if (!have_init_ref_ || cur.f.keys.size() < 100) {
    if (cur.f.keys.size() >= 100) init_ref_ = cur, have_init_ref_ = true, pending_.clear();
    return false;
  }
  // ORB-SLAM2's SearchForInitialization (100 px window, TH_LOW, ratio 0.9),
  // on every level (+-1) instead of level 0 of an extractor with twice the features.
  const Frame& a = init_ref_.f;
  std::vector<int> match(a.keys.size(), -1), best_of(cur.f.keys.size(), -1), best_dist(cur.f.keys.size(), 256);
  std::vector<int> area;
  for (std::size_t i = 0; i < a.keys.size(); ++i) {
    const int level = a.keys[i].octave;
    cur.f.features_in_area(a.keys[i].pt.x, a.keys[i].pt.y, 100, std::max(0, level - 1), level + 1, &area);
    int b1 = 256, b2 = 256, bi = -1;
    for (int j : area) {
      const int d = hamming(a.descriptors, static_cast<int>(i), cur.f.descriptors, j);
      if (d < b1) b2 = b1, b1 = d, bi = j;
      else if (d < b2) b2 = d;
    }
    if (bi < 0 || b1 > kHammingLow || b1 >= 0.9 * b2) continue;
    const auto sj = static_cast<std::size_t>(bi);
    if (b1 < best_dist[sj]) {
      if (best_of[sj] >= 0) match[static_cast<std::size_t>(best_of[sj])] = -1;
      best_of[sj] = static_cast<int>(i), best_dist[sj] = b1, match[i] = bi;
    }
  }
  std::vector<int> pairs;
  for (std::size_t i = 0; i < match.size(); ++i) {
    if (match[i] >= 0) pairs.push_back(static_cast<int>(i));
  }
  if (pairs.size() < 100) {
    init_ref_ = cur;
    pending_.clear();
    return false;
  }
  std::vector<cv::Point2f> p0, p1;
  std::vector<int> order_i;
  for (int k : shuffled(pairs.size(), rng_)) {
    const int i = pairs[static_cast<std::size_t>(k)];
    p0.push_back(a.keys[static_cast<std::size_t>(i)].pt);
    p1.push_back(cur.f.keys[static_cast<std::size_t>(match[static_cast<std::size_t>(i)])].pt);
    order_i.push_back(i);
  }
  cv::Mat mask_e, mask_h;
  const cv::Mat E = cv::findEssentialMat(p0, p1, Kcv_, cv::RANSAC, 0.999, 1.0, mask_e);
  const cv::Mat H = cv::findHomography(p0, p1, cv::RANSAC, 2.0, mask_h);
  if (E.rows != 3 || E.cols != 3) return false;
  const int ne = cv::countNonZero(mask_e), nh = H.empty() ? 0 : cv::countNonZero(mask_h);
  // ORB-SLAM2 picks the homography when it explains the scene (RH > 0.45).
  std::vector<std::pair<cv::Mat, cv::Mat>> hypotheses;  // (R, t) of T_10
  cv::Mat inlier_mask;
  if (nh > 0 && double(nh) / double(nh + ne) > 0.45) {
    std::vector<cv::Mat> Rs, ts, ns;
    cv::decomposeHomographyMat(H, Kcv_, Rs, ts, ns);
    for (std::size_t h = 0; h < Rs.size(); ++h) hypotheses.emplace_back(Rs[h], ts[h]);
    inlier_mask = mask_h;
  } else {
    cv::Mat R, t, cheirality = mask_e.clone();  // recoverPose drops far points from its mask
    cv::recoverPose(E, p0, p1, Kcv_, R, t, cheirality);
    hypotheses.emplace_back(R, t);
    inlier_mask = mask_e;
  }
  // The hypothesis that triangulates most points in front with parallax.
  int best_good = -1;
  Eigen::Isometry3d best_T = Eigen::Isometry3d::Identity();
  std::vector<std::pair<int, Eigen::Vector3d>> best_points;
  double best_parallax = 0;
  for (const auto& [Rcv, tcv] : hypotheses) {
    Eigen::Matrix3d R;
    Eigen::Vector3d t;
    cv::cv2eigen(Rcv, R);
    cv::cv2eigen(tcv, t);
    if (t.norm() <= 0) continue;
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = R;
    T.translation() = t.normalized();
    const Eigen::Matrix<double, 3, 4> P0 = K_ * Eigen::Isometry3d::Identity().matrix().topRows<3>();
    const Eigen::Matrix<double, 3, 4> P1 = K_ * T.matrix().topRows<3>();
    const Eigen::Vector3d C1 = T.inverse().translation();
    std::vector<std::pair<int, Eigen::Vector3d>> good;
    std::vector<double> parallax;
    for (std::size_t k = 0; k < p0.size(); ++k) {
      if (!inlier_mask.at<uchar>(static_cast<int>(k))) continue;
      Eigen::Vector3d X;
      if (!triangulate(P0, P1, p0[k], p1[k], &X)) continue;
      const Eigen::Vector3d X1 = T * X;
      if (X.z() <= 0 || X1.z() <= 0) continue;
      const double e0 = (K_ * X).hnormalized().x() - p0[k].x, f0 = (K_ * X).hnormalized().y() - p0[k].y;
      const double e1 = (K_ * X1).hnormalized().x() - p1[k].x, f1 = (K_ * X1).hnormalized().y() - p1[k].y;
      if (e0 * e0 + f0 * f0 > 4 * kChi2Mono || e1 * e1 + f1 * f1 > 4 * kChi2Mono) continue;
      const double c = X.normalized().dot((X - C1).normalized());
      if (c >= 0.99998) continue;  // ORB-SLAM2 maps only points with some parallax
      parallax.push_back(std::acos(std::clamp(c, -1.0, 1.0)) * 180.0 / M_PI);
      good.emplace_back(order_i[k], X);
    }
    if (static_cast<int>(good.size()) > best_good) {
      best_good = static_cast<int>(good.size());
      best_T = T;
      best_points = good;
      std::sort(parallax.begin(), parallax.end(), std::greater<double>());  // the 50th largest, as ORB-SLAM2
      best_parallax = parallax.empty() ? 0 : parallax[std::min(parallax.size() - 1, std::size_t{50})];
    }
  }
  // ORB-SLAM2: >= 50 triangulated, and the 50th largest parallax >= 1 degree.
  if (best_good < 50 || best_parallax < 1.0) {
    pending_.push_back(cur);
    return false;
  }

  KeyFrame k0, k1;
  k0.frame = init_ref_.index;
  k0.f = init_ref_.f;
  k0.mp.assign(k0.f.keys.size(), -1);
  k1.frame = cur.index;
  k1.Tcw = best_T;
  k1.f = cur.f;
  k1.mp.assign(k1.f.keys.size(), -1);
  map_.kfs.push_back(std::move(k0));
  map_.kfs.push_back(std::move(k1));
  for (const auto& [i, X] : best_points) {
    const int p = map_.new_point(X, 0, i);
    map_.add_observation(p, 1, match[static_cast<std::size_t>(i)]);
    map_.update_point(p);
  }
  local_ba({0, 1}, true);  // the initial map's global BA, KF 0 fixed
  // Scale: median depth 1 in the first keyframe.
  std::vector<double> z;
  for (int p : map_.kfs[0].mp) {
    if (p >= 0 && !map_.points[static_cast<std::size_t>(p)].bad) z.push_back(map_.points[static_cast<std::size_t>(p)].X.z());
  }
  int tracked = 0;
  for (int p : map_.kfs[1].mp) tracked += (p >= 0 && !map_.points[static_cast<std::size_t>(p)].bad) ? 1 : 0;
  if (z.size() < 50 || tracked < 100) {
    map_ = Map();
    init_ref_ = cur;
    pending_.clear();
    return false;
  }
  std::nth_element(z.begin(), z.begin() + static_cast<std::ptrdiff_t>(z.size() / 2), z.end());
  const double s = 1.0 / z[z.size() / 2];
  map_.kfs[1].Tcw.translation() *= s;
  for (MapPoint& m : map_.points) m.X *= s;
  for (std::size_t p = 0; p < map_.points.size(); ++p) map_.update_point(static_cast<int>(p));
  cur.Tcw = map_.kfs[1].Tcw;
  cur.mp = map_.kfs[1].mp;
  cur.outlier.assign(cur.mp.size(), false);
  velocity_ = motion_fraction(cur.Tcw, cur.index - init_ref_.index);
  have_velocity_ = true;
  records_.push_back({init_ref_.index, 0, Eigen::Isometry3d::Identity()});
  // The frames between the initial pair, tracked against the initial map
  // (ORB-SLAM2 leaves them out; here every frame counts).
  std::vector<int> all_points;
  for (std::size_t p = 0; p < map_.points.size(); ++p) {
    if (!map_.points[p].bad) all_points.push_back(static_cast<int>(p));
  }
  for (TrackedFrame& f : pending_) {
    f.Tcw = Eigen::Isometry3d::Identity();
    for (int k = init_ref_.index; k < f.index; ++k) f.Tcw = velocity_ * f.Tcw;
    f.mp.assign(f.f.keys.size(), -1);
    f.outlier.assign(f.f.keys.size(), false);
    search_local_points(f, map_, all_points, cam_, 3);
    if (optimize(f) >= kMinTrackedInliers) {
      records_.push_back({f.index, 0, f.Tcw});
      ++result_.frames_tracked;
    }
  }
  pending_.clear();
  reference_kf_ = 1;
  last_kf_frame_ = cur.index;
  result_.keyframes_created = 2;
  initialised_ = true;
  ++result_.frames_tracked;  // the reference frame (the caller counts `cur`)
  return true;
}

}  // namespace keepless::eval::vo::detail
