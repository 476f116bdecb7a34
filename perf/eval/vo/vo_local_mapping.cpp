#include "vo_internals.hpp"

#include <time.h>

#include <algorithm>
#include <cstddef>
#include <utility>

#include "point_quality.hpp"
#include "vo_ba.hpp"
#include "vo_geometry.hpp"

namespace keepless::eval::vo::detail {

namespace {

// This thread's CPU time: what a solve costs whatever else the machine runs.
double thread_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

}  // namespace

int Vo::insert_keyframe(TrackedFrame& cur) {
  KeyFrame k;
  k.frame = cur.index;
  k.Tcw = cur.Tcw;
  k.f = cur.f;
  k.mp.assign(cur.f.keys.size(), -1);
  k.tracked.assign(cur.f.keys.size(), 0);
  map_.kfs.push_back(std::move(k));
  const int id = static_cast<int>(map_.kfs.size()) - 1;
  for (std::size_t i = 0; i < cur.mp.size(); ++i) {
    const int p = cur.mp[i] >= 0 ? map_.resolve(cur.mp[i]) : -1;
    if (p < 0) continue;
    map_.kfs[static_cast<std::size_t>(id)].tracked[i] = 1;
    map_.add_observation(p, id, static_cast<int>(i));
    map_.update_point(p);
  }
  if (seq_.rgbd) {
    // ORB-SLAM2's CreateNewKeyFrame: points from depth, nearest first, all
    // close ones and at least 100.
    KeyFrame& kf = map_.kfs[static_cast<std::size_t>(id)];
    std::vector<int> by_depth;
    for (std::size_t i = 0; i < kf.f.depth.size(); ++i) {
      if (kf.f.depth[i] > 0) by_depth.push_back(static_cast<int>(i));
    }
    std::sort(by_depth.begin(), by_depth.end(), [&](int a, int b) {
      return kf.f.depth[static_cast<std::size_t>(a)] < kf.f.depth[static_cast<std::size_t>(b)];
    });
    const Eigen::Isometry3d Twc = kf.Tcw.inverse();
    int n = 0;
    for (int i : by_depth) {
      const auto si = static_cast<std::size_t>(i);
      const double z = kf.f.depth[si];
      if (z > cam_.close_depth && n > 100) break;
      ++n;
      if (map_.kfs[static_cast<std::size_t>(id)].mp[si] >= 0) continue;
      const cv::Point2f& pt = map_.kfs[static_cast<std::size_t>(id)].f.keys[si].pt;
      const Eigen::Vector3d Xc((pt.x - cam_.cx) * z / cam_.fx, (pt.y - cam_.cy) * z / cam_.fy, z);
      recent_.push_back(map_.new_point(Twc * Xc, id, i));
    }
  }
  cur.mp = map_.kfs[static_cast<std::size_t>(id)].mp;
  last_kf_frame_ = cur.index;
  reference_kf_ = id;
  ++result_.keyframes_created;
  local_mapping(id);
  // The keyframe's points after mapping (fused, culled) and its pose after local BA are what the
  // next frame tracks from: ORB-SLAM2's UpdateLastFrame, since mapping runs in line here and no
  // other frame's reference keyframe moves before the next frame.
  cur.mp = map_.kfs[static_cast<std::size_t>(id)].mp;
  cur.Tcw = map_.kfs[static_cast<std::size_t>(id)].Tcw;
  return id;
}

void Vo::point_culling(int kf) {
  const int th_obs = seq_.rgbd ? 3 : 2;
  std::vector<int> keep;
  for (int p : recent_) {
    MapPoint& m = map_.points[static_cast<std::size_t>(p)];
    if (m.bad) continue;
    if (double(m.found) / m.visible < 0.25) {
      map_.set_bad(p);
    } else if (kf - m.first_kf >= 2 && map_.weighted_observations(p) <= th_obs) {
      map_.set_bad(p);
    } else if (kf - m.first_kf < 3) {
      keep.push_back(p);
    }
  }
  recent_.swap(keep);
}

void Vo::create_points(int kf) {
  const auto cov = map_.covisibles(kf, 1);
  const KeyFrame& k1 = map_.kfs[static_cast<std::size_t>(kf)];
  const Eigen::Vector3d c1 = k1.centre();
  const double ratio_factor = 1.5 * kScaleFactor;
  for (std::size_t n = 0; n < cov.size() && static_cast<int>(n) < neighbours(); ++n) {
    const int other = cov[n].first;
    const KeyFrame& k2 = map_.kfs[static_cast<std::size_t>(other)];
    const Eigen::Vector3d c2 = k2.centre();
    const double baseline = (c2 - c1).norm();
    if (seq_.rgbd) {
      if (baseline < cam_.bf / cam_.fx) continue;
    } else {
      std::vector<double> z;
      for (int p : k2.mp) {
        if (p >= 0 && !map_.points[static_cast<std::size_t>(p)].bad) {
          z.push_back((k2.Tcw * map_.points[static_cast<std::size_t>(p)].X).z());
        }
      }
      if (z.empty()) continue;
      std::nth_element(z.begin(), z.begin() + static_cast<std::ptrdiff_t>(z.size() / 2), z.end());
      if (baseline / z[z.size() / 2] < 0.01) continue;
    }
    const std::vector<std::pair<int, int>> pairs = search_for_triangulation(map_, kf, other, cam_);
    const Eigen::Matrix<double, 3, 4> P1 = K_ * k1.Tcw.matrix().topRows<3>();
    const Eigen::Matrix<double, 3, 4> P2 = K_ * k2.Tcw.matrix().topRows<3>();
    const Eigen::Matrix3d Rwc1 = k1.Tcw.linear().transpose(), Rwc2 = k2.Tcw.linear().transpose();
    for (const auto& [i, j] : pairs) {
      const auto si = static_cast<std::size_t>(i), sj = static_cast<std::size_t>(j);
      if (map_.kfs[static_cast<std::size_t>(kf)].mp[si] >= 0 || map_.kfs[static_cast<std::size_t>(other)].mp[sj] >= 0) continue;
      const cv::KeyPoint& a = k1.f.keys[si];
      const cv::KeyPoint& b = k2.f.keys[sj];
      const Eigen::Vector3d r1 = Rwc1 * Eigen::Vector3d((a.pt.x - cam_.cx) / cam_.fx, (a.pt.y - cam_.cy) / cam_.fy, 1);
      const Eigen::Vector3d r2 = Rwc2 * Eigen::Vector3d((b.pt.x - cam_.cx) / cam_.fx, (b.pt.y - cam_.cy) / cam_.fy, 1);
      const double cos_parallax = r1.dot(r2) / (r1.norm() * r2.norm());
      if (!(cos_parallax > 0 && cos_parallax < 0.9998)) continue;
      Eigen::Vector3d X;
      if (!triangulate(P1, P2, a.pt, b.pt, &X)) continue;
      BaObservation o1{0, 0, a.pt.x, a.pt.y, k1.f.ur[si], a.octave};
      BaObservation o2{0, 0, b.pt.x, b.pt.y, k2.f.ur[sj], b.octave};
      if (chi2(cam_, k1.Tcw, X, o1) > (o1.ur >= 0 ? kChi2Stereo : kChi2Mono)) continue;
      if (chi2(cam_, k2.Tcw, X, o2) > (o2.ur >= 0 ? kChi2Stereo : kChi2Mono)) continue;
      const double d1 = (X - c1).norm(), d2 = (X - c2).norm();
      if (d1 <= 0 || d2 <= 0) continue;
      const double ratio_dist = d2 / d1;
      const double ratio_octave = pyramid().scale[static_cast<std::size_t>(a.octave)] /
                                  pyramid().scale[static_cast<std::size_t>(b.octave)];
      if (ratio_dist * ratio_factor < ratio_octave || ratio_dist > ratio_octave * ratio_factor) continue;
      const int p = map_.new_point(X, kf, i);
      map_.add_observation(p, other, j);
      map_.update_point(p);
      recent_.push_back(p);
    }
  }
}

void Vo::search_in_neighbours(int kf) {
  std::vector<int> targets;
  std::vector<char> in(map_.kfs.size(), 0);
  in[static_cast<std::size_t>(kf)] = 1;
  const auto cov = map_.covisibles(kf, 1);
  for (std::size_t n = 0; n < cov.size() && static_cast<int>(n) < neighbours(); ++n) {
    if (!in[static_cast<std::size_t>(cov[n].first)]) targets.push_back(cov[n].first);
    in[static_cast<std::size_t>(cov[n].first)] = 1;
  }
  const std::size_t first = targets.size();
  for (std::size_t t = 0; t < first; ++t) {
    const auto second = map_.covisibles(targets[t], 1);
    for (std::size_t n = 0; n < second.size() && n < 5; ++n) {
      if (!in[static_cast<std::size_t>(second[n].first)]) {
        in[static_cast<std::size_t>(second[n].first)] = 1;
        targets.push_back(second[n].first);
      }
    }
  }
  std::vector<int> own;
  for (int p : map_.kfs[static_cast<std::size_t>(kf)].mp) {
    if (p >= 0) own.push_back(p);
  }
  for (int t : targets) fuse(map_, t, own, cam_);
  const std::vector<int> theirs = map_.points_of(targets);
  fuse(map_, kf, theirs, cam_);
  for (int p : map_.kfs[static_cast<std::size_t>(kf)].mp) {
    if (p >= 0) map_.update_point(p);
  }
}

std::vector<int> Vo::local_keyframes(int kf, int most) const {
  std::vector<int> local = {kf};
  auto cov = map_.covisibles(kf, 15);
  if (cov.empty()) {
    cov = map_.covisibles(kf, 1);
    if (cov.size() > 1) cov.resize(1);
  }
  for (const auto& c : cov) {
    if (static_cast<int>(local.size()) >= most) break;
    local.push_back(c.first);
  }
  return local;
}

void Vo::local_ba(const std::vector<int>& local, bool fix_first) {
  const Clock::time_point start = Clock::now();
  std::vector<int> pose_of(map_.kfs.size(), -1);
  LocalBaProblem problem;
  std::vector<int> kf_of_pose;
  for (int k : local) {
    pose_of[static_cast<std::size_t>(k)] = static_cast<int>(problem.poses.size());
    problem.poses.push_back(to_block(map_.kfs[static_cast<std::size_t>(k)].Tcw));
    problem.pose_fixed.push_back(k == 0 || (fix_first && k == local.front()));
    kf_of_pose.push_back(k);
  }
  std::vector<int> points = map_.points_of(local);
  // Excluded points (deferred culling) are not in the point blocks: left
  // out, or (defer_fixed) constant landmarks seen only by the local keyframes.
  if (!opt_.defer_fixed) {
    points.erase(std::remove_if(points.begin(), points.end(),
                                [&](int p) { return map_.points[static_cast<std::size_t>(p)].excluded; }),
                 points.end());
  }
  std::vector<char> is_local(map_.kfs.size(), 0);
  for (int k : local) is_local[static_cast<std::size_t>(k)] = 1;
  std::vector<std::pair<int, int>> obs_of;  // (point, kf) per observation
  for (std::size_t pi = 0; pi < points.size(); ++pi) {
    const MapPoint& m = map_.points[static_cast<std::size_t>(points[pi])];
    problem.points.push_back(m.X);
    problem.point_fixed.push_back(m.excluded);
    for (const auto& [k, i] : m.obs) {
      if (map_.kfs[static_cast<std::size_t>(k)].bad) continue;
      if (m.excluded && !is_local[static_cast<std::size_t>(k)]) continue;
      if (pose_of[static_cast<std::size_t>(k)] < 0) {  // a fixed observer
        pose_of[static_cast<std::size_t>(k)] = static_cast<int>(problem.poses.size());
        problem.poses.push_back(to_block(map_.kfs[static_cast<std::size_t>(k)].Tcw));
        problem.pose_fixed.push_back(true);
        kf_of_pose.push_back(k);
      }
      const cv::KeyPoint& kp = map_.kfs[static_cast<std::size_t>(k)].f.keys[static_cast<std::size_t>(i)];
      problem.observations.push_back({pose_of[static_cast<std::size_t>(k)], static_cast<int>(pi), kp.pt.x, kp.pt.y,
                                      map_.kfs[static_cast<std::size_t>(k)].f.ur[static_cast<std::size_t>(i)],
                                      kp.octave});
      obs_of.emplace_back(points[pi], k);
    }
  }
  result_.local_ba_observations += static_cast<std::int64_t>(problem.observations.size());
  // Which points the BA holds: their map track lengths and triangulation angles.
  for (int p : points) {
    if (map_.points[static_cast<std::size_t>(p)].excluded) continue;
    const core::PointQuality q = point_quality(map_, p, local.front(), cam_);
    ++result_.ba_points;
    result_.ba_point_track_sum += q.track_length;
    result_.ba_point_angle_sum += std::max(0.0f, q.triangulation_angle);
  }
  const double cpu0 = thread_cpu_seconds();
  const std::vector<bool> outlier = solve_local_ba(cam_, &problem);
  result_.local_ba_cpu_seconds += thread_cpu_seconds() - cpu0;
  for (std::size_t q = 0; q < problem.poses.size(); ++q) {
    if (!problem.pose_fixed[q]) map_.kfs[static_cast<std::size_t>(kf_of_pose[q])].Tcw = from_block(problem.poses[q]);
  }
  for (std::size_t pi = 0; pi < points.size(); ++pi) {
    if (!problem.point_fixed[pi] && problem.points[pi].allFinite()) {
      map_.points[static_cast<std::size_t>(points[pi])].X = problem.points[pi];
    }
  }
  for (std::size_t o = 0; o < outlier.size(); ++o) {
    if (outlier[o] && !map_.points[static_cast<std::size_t>(obs_of[o].first)].bad) {
      map_.erase_observation(obs_of[o].first, obs_of[o].second);
    }
  }
  for (int p : points) map_.update_point(p);
  result_.local_ba_seconds += seconds_since(start);
  ++result_.local_bas;
}

void Vo::keyframe_culling(int kf) {
  for (const auto& [k, w] : map_.covisibles(kf, 15)) {
    if (k != 0 && k != kf && map_.redundant(k, seq_.rgbd ? cam_.close_depth : 0)) map_.cull_keyframe(k);
  }
}

void Vo::local_mapping(int kf) {
  point_culling(kf);
  create_points(kf);
  search_in_neighbours(kf);
  const std::vector<int> local = local_keyframes(kf, opt_.max_local_keyframes);
  if (opt_.measure_windows) measure_windows(kf);
  if (deferring()) note_matches(kf);
  if (opt_.selector != Selector::kOriginal) remove_culls(select_points(kf, local));
  local_ba(local, false);
  if (deferring()) {
    const double cpu0 = thread_cpu_seconds();
    retriangulate_excluded(local);
    if (opt_.defer_alternate) {
      refine_local_poses(local);
      retriangulate_excluded(local);
    }
    result_.refine_cpu_seconds += thread_cpu_seconds() - cpu0;
  }
  if (opt_.keyframe_culling != KeyframeCulling::kOff) keyframe_culling(kf);
}

}  // namespace keepless::eval::vo::detail
