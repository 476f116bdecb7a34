#include "real_vo.hpp"

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <numeric>
#include <string>
#include <utility>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "keepless/core/deferred_culls.hpp"
#include "keepless/core/keep_thresholds.hpp"
#include "keepless/core/sparsifier.hpp"
#include "keepless/opencv/keyframe_adapter.hpp"
#include "matching.hpp"
#include "metrics.hpp"
#include "point_quality.hpp"
#include "point_selection.hpp"
#include "prng.hpp"
#include "vo_ba.hpp"

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

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// RealVoOptions::hashed_ids: lowbias32 (C. Wellons' hash prospector) and its
// inverse, a bijection of the 32-bit map indices; the adapter's reserved ids
// of unmapped keypoints (top bit set) pass through.
core::PointId hashed_id(int p) {
  auto x = static_cast<std::uint32_t>(p);
  x ^= x >> 16;
  x *= 0x7feb352dU;
  x ^= x >> 15;
  x *= 0x846ca68bU;
  x ^= x >> 16;
  return x;
}

core::PointId unhashed_id(core::PointId id) {
  if (id >> 32) return id;
  auto x = static_cast<std::uint32_t>(id);
  x ^= x >> 16;
  x *= 0x43021123U;
  x ^= x >> 15 ^ x >> 30;
  x *= 0x1d69e2a5U;
  x ^= x >> 16;
  return x;
}

// This thread's CPU time: what a solve costs whatever else the machine runs.
double thread_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// ORB-SLAM2's tracking thresholds.
constexpr int kMinTrackedInliers = 30;
constexpr int kMinTrackedAfterRelocalisation = 50;

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

// A seeded order for RANSAC's samples: OpenCV's RANSAC has its own fixed
// generator, so the seed acts through the order of the correspondences.
std::vector<int> shuffled(std::size_t n, Rng& rng) {
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  for (std::size_t i = n; i > 1; --i) std::swap(order[i - 1], order[rng.below(static_cast<std::uint32_t>(i))]);
  return order;
}

Eigen::Isometry3d pose_from_cv(const cv::Mat& rvec, const cv::Mat& tvec) {
  cv::Mat R;
  cv::Rodrigues(rvec, R);
  Eigen::Matrix3d Re;
  Eigen::Vector3d te;
  cv::cv2eigen(R, Re);
  cv::cv2eigen(tvec, te);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Re;
  T.translation() = te;
  return T;
}

// A fraction 1/n of a motion (for the velocity over an initialisation gap).
Eigen::Isometry3d motion_fraction(const Eigen::Isometry3d& T, int n) {
  if (n <= 1) return T;
  const Eigen::AngleAxisd aa(Eigen::Matrix3d(T.linear()));
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = Eigen::AngleAxisd(aa.angle() / n, aa.axis()).toRotationMatrix();
  out.translation() = T.translation() / n;
  return out;
}

// The DLT point of rows x * P.row(2) - P.row(0|1), one pair per view: the
// right singular vector of the smallest singular value, dehomogenised.
template <typename Rows>
bool dlt_point(const Rows& A, Eigen::Vector3d* X) {
  Eigen::JacobiSVD<typename Rows::PlainObject> svd(A, Eigen::ComputeFullV);
  const Eigen::Vector4d h = svd.matrixV().col(3);
  if (std::abs(h(3)) < 1e-12) return false;
  *X = h.head<3>() / h(3);
  return X->allFinite();
}

// Linear triangulation (ORB-SLAM2's Initializer::Triangulate).
bool triangulate(const Eigen::Matrix<double, 3, 4>& P1, const Eigen::Matrix<double, 3, 4>& P2,
                 const cv::Point2f& x1, const cv::Point2f& x2, Eigen::Vector3d* X) {
  Eigen::Matrix4d A;
  A.row(0) = x1.x * P1.row(2) - P1.row(0);
  A.row(1) = x1.y * P1.row(2) - P1.row(1);
  A.row(2) = x2.x * P2.row(2) - P2.row(0);
  A.row(3) = x2.y * P2.row(2) - P2.row(1);
  return dlt_point(A, X);
}

struct FrameRecord {
  int frame = 0, ref_kf = 0;
  Eigen::Isometry3d T_cr = Eigen::Isometry3d::Identity();
};

class Vo {
 public:
  Vo(const RealSequence& s, const RealVoOptions& o)
      : seq_(s), opt_(o), cam_(s.camera),
        extractor_(o.features > 0 ? o.features : (s.rgbd ? 1000 : 2000), s.camera),
        rng_(mix(o.seed, 0x5eed)), adapter_(window_capacities()), window_(window_capacities()),
        sparsifier_(window_capacities(), vo_params(o.params, s.camera)),
        deferred_(window_capacities().max_points, o.params.defer_keyframes),
        fraction_budget_(window_capacities().max_points) {
    K_ << cam_.fx, 0, cam_.cx, 0, cam_.fy, cam_.cy, 0, 0, 1;
    cv::eigen2cv(K_, Kcv_);
  }

  RealRunResult run();

 private:
  bool track(TrackedFrame& cur);
  bool estimate_pose(TrackedFrame& cur, bool guess);
  bool relocalise(TrackedFrame& cur);
  int optimize(TrackedFrame& cur);
  std::vector<int> local_map(const TrackedFrame& cur, int* reference);
  bool initialize_monocular(TrackedFrame& cur);
  void initialize_rgbd(TrackedFrame& cur);
  bool need_keyframe(const TrackedFrame& cur, int inliers) const;
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
  if (inliers < (relocalised || recent ? kMinTrackedAfterRelocalisation : kMinTrackedInliers)) return false;
  for (int p : cur.mp) {
    if (p < 0) continue;
    ++map_.points[static_cast<std::size_t>(p)].found;
    if (map_.points[static_cast<std::size_t>(p)].excluded) ++result_.excluded_matches;
  }
  reference_kf_ = reference;
  if (need_keyframe(cur, inliers)) insert_keyframe(cur);
  return true;
}

bool Vo::need_keyframe(const TrackedFrame& cur, int inliers) const {
  const int kfs = map_.alive_keyframes();
  const int max_frames = static_cast<int>(seq_.fps);
  if (cur.index < relocalised_frame_ + max_frames && kfs > max_frames) return false;
  const int min_obs = kfs <= 2 ? 2 : 3;
  int ref_matches = 0;
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
  const double ratio = kfs < 2 ? 0.4 : (seq_.rgbd ? 0.75 : 0.9);
  // c1a (max frames) and c1b (min frames, mapping idle: always, it runs inline) hold.
  const bool c2 = (inliers < ref_matches * ratio || need_close) && inliers > 15;
  // The translation/rotation rule: a keyframe at least every 20 degrees.
  const Eigen::Isometry3d rel = cur.Tcw * map_.kfs[static_cast<std::size_t>(reference_kf_)].Tcw.inverse();
  const bool turned = Eigen::AngleAxisd(Eigen::Matrix3d(rel.linear())).angle() > 20.0 * M_PI / 180.0;
  const bool c1a = cur.index >= last_kf_frame_ + max_frames;
  return (c2 || ((turned || c1a) && inliers > 15));
}

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
  // The keyframe's points after mapping (fused, culled) are what the next frame tracks.
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

// window_sizes.hpp: the local and sliding windows at keyframe kf, per K.
void Vo::measure_windows(int kf) {
  WindowMeasure m;
  std::vector<core::PointId> ids;
  const auto measure = [&](const std::vector<int>& window) {
    m.clear();
    for (int k : window) {
      const KeyFrame& f = map_.kfs[static_cast<std::size_t>(k)];
      ids.clear();
      for (int p : f.mp)
        if (p >= 0 && !map_.points[static_cast<std::size_t>(p)].bad) ids.push_back(static_cast<core::PointId>(p));
      m.add_keyframe(ids, f.mp.size() - ids.size());
    }
    return m.size();
  };
  WindowSizes& w = result_.window_sizes;
  for (std::size_t i = 0; i < WindowSizes::kSizes.size(); ++i) {
    const int most = WindowSizes::kSizes[i];
    const std::vector<int> local = local_keyframes(kf, most);
    w.local[i].max_with(measure(local));
    std::vector<int> sliding;
    for (int k = kf; k >= 0 && static_cast<int>(sliding.size()) < most; --k)
      if (!map_.kfs[static_cast<std::size_t>(k)].bad) sliding.push_back(k);
    std::reverse(sliding.begin(), sliding.end());  // oldest first, as a node holds them
    w.sliding[i].max_with(measure(sliding));
    if (most == 20 && opt_.replay_capacities.max_keyframes > 0) {
      replay(local, &replay_local_);
      replay(sliding, &replay_sliding_);
    }
  }
  ++w.steps;
}

// A window as keepless_node would hold it (its mapped observations), decided
// by an incremental Sparsifier at the replay capacities; a capacity refusal
// (the window's or the network's) is counted.
void Vo::replay(const std::vector<int>& keyframes, std::unique_ptr<Replay>* state) {
  const core::Capacities& caps = opt_.replay_capacities;
  if (!*state) {
    *state = std::make_unique<Replay>();
    (*state)->window = std::make_unique<core::Window>(caps);
    (*state)->sparsifier = std::make_unique<core::Sparsifier>(caps, core::Params{}, core::SolveMode::kIncremental);
  }
  Replay& r = **state;
  r.window->clear();
  ++result_.window_sizes.replayed;
  std::vector<core::Observation> obs;
  for (int k : keyframes) {
    const KeyFrame& f = map_.kfs[static_cast<std::size_t>(k)];
    obs.clear();
    for (std::size_t i = 0; i < f.mp.size(); ++i) {
      const int p = f.mp[i];
      if (p < 0 || map_.points[static_cast<std::size_t>(p)].bad) continue;
      obs.push_back({static_cast<core::PointId>(p), f.f.keys[i].pt.x, f.f.keys[i].pt.y, 0.0});
    }
    std::sort(obs.begin(), obs.end(), [](const core::Observation& a, const core::Observation& b) { return a.point < b.point; });
    obs.erase(std::unique(obs.begin(), obs.end(),
                          [](const core::Observation& a, const core::Observation& b) { return a.point == b.point; }),
              obs.end());
    core::Keyframe key;
    key.id = static_cast<core::KeyframeId>(k);
    const Eigen::Vector3d c = f.centre();
    key.centre[0] = c.x();
    key.centre[1] = c.y();
    key.centre[2] = c.z();
    if (r.window->add_keyframe(key, obs.data(), static_cast<std::uint32_t>(obs.size())) != core::Status::kOk) {
      ++result_.window_sizes.refused;
      return;
    }
  }
  if (r.sparsifier->update(*r.window) == core::Status::kCapacityExceeded) ++result_.window_sizes.refused;
}

std::vector<core::PointId> Vo::select_points(int kf, const std::vector<int>& local) {
  const Clock::time_point start = Clock::now();
  std::vector<int> ordered = local;
  std::sort(ordered.begin(), ordered.end());
  window_.clear();
  std::vector<cv::KeyPoint> keypoints, unmapped;
  std::vector<core::PointId> ids;
  std::vector<double> depths;
  std::vector<std::uint8_t> tracked;
  std::vector<core::PointQuality> quality;
  // The paper's box N(p, f) has counted the unmapped detections as
  // reserved-id observations since the VO first ran; core's native list is
  // what kAuthors' grid reads (and the box does not), so `paper` keeps the
  // reserved ids and its decisions stay as they were.
  opencv::KeyframeExtras extras;
  extras.unmapped = &unmapped;
  extras.unmapped_as = opt_.params.cost_model == core::CostModel::kPaper ? opencv::UnmappedAs::kReservedIds
                                                                          : opencv::UnmappedAs::kKeypointList;
  extras.intrinsics = {cam_.fx, cam_.fy, cam_.cx, cam_.cy};
  extras.depths = &depths;
  const bool send_quality = opt_.params.cost_model == core::CostModel::kTrack;
  extras.quality = send_quality ? &quality : nullptr;
  for (int k : ordered) {
    const KeyFrame& f = map_.kfs[static_cast<std::size_t>(k)];
    keypoints.clear();
    unmapped.clear();
    ids.clear();
    depths.clear();
    tracked.clear();
    quality.clear();
    // Only the new keyframe's flags are read (core::Keyframe::tracked).
    const bool flags = opt_.tracked_flags && k == kf && f.tracked.size() == f.mp.size();
    extras.tracked = flags ? &tracked : nullptr;
    for (std::size_t i = 0; i < f.mp.size(); ++i) {
      // An excluded point is decided already: a detection without a BA point.
      if (f.mp[i] >= 0 && !map_.points[static_cast<std::size_t>(f.mp[i])].bad &&
          !map_.points[static_cast<std::size_t>(f.mp[i])].excluded) {
        keypoints.push_back(f.f.keys[i]);
        ids.push_back(opt_.hashed_ids ? hashed_id(f.mp[i]) : static_cast<core::PointId>(f.mp[i]));
        if (flags) tracked.push_back(f.tracked[i]);
        depths.push_back((f.Tcw * map_.points[static_cast<std::size_t>(f.mp[i])].X).z());
        if (send_quality) quality.push_back(point_quality(map_, f.mp[i], kf, cam_));
      } else {
        unmapped.push_back(f.f.keys[i]);
      }
    }
    opencv::CameraPose pose;
    if (opencv::pose_from_tcw(f.Tcw, &pose) != opencv::Status::kOk ||
        adapter_.add_keyframe(window_, static_cast<core::KeyframeId>(k), pose, keypoints, ids, extras) !=
            opencv::Status::kOk) {
      ++result_.window_rejections;
      result_.selector_seconds += seconds_since(start);
      return {};
    }
  }
  if (sparsifier_.run(window_) != core::Status::kOk) {
    ++result_.window_rejections;
    result_.selector_seconds += seconds_since(start);
    return {};
  }
  result_.selector.add(sparsifier_.summary());
  // The authors' integration: only the new keyframe's points are decided;
  // with the maturity guard A, those of the keyframe that just became A old
  // (as core's Scope::kNewest decides it): deciding the new keyframe's
  // matured points instead would cull exactly those the tracker still sees.
  const std::size_t maturity = opt_.params.maturity_keyframes;
  if (maturity > 0 && ordered.size() <= maturity) {  // every point is young yet
    kept_fraction_sum_ += 1.0;
    result_.selector_seconds += seconds_since(start);
    return {};
  }
  const KeyFrame& f = map_.kfs[static_cast<std::size_t>(maturity > 0 ? ordered[ordered.size() - 1 - maturity] : kf)];
  std::vector<Candidate> candidates;
  // Keepless's culls and every point it evaluated, under the map's indices
  // (hashed_ids), sorted.
  const auto map_ids = [this](std::vector<core::PointId>* ids) {
    if (opt_.hashed_ids)
      for (core::PointId& id : *ids) id = unhashed_id(id);
    std::sort(ids->begin(), ids->end());
  };
  std::vector<core::PointId> keepless_culls, evaluated;
  opencv::culled_points(sparsifier_, &keepless_culls);
  opencv::points_with_verdict(sparsifier_, core::Verdict::kKeep, &evaluated);
  evaluated.insert(evaluated.end(), keepless_culls.begin(), keepless_culls.end());
  map_ids(&keepless_culls);
  map_ids(&evaluated);
  // The candidates: the evaluated points of the decided keyframe, or with
  // decide_window those of every window keyframe, each once, described by
  // its keypoint in the newest keyframe that observes it.
  std::vector<int> deciding = {static_cast<int>(&f - map_.kfs.data())};
  if (opt_.decide_window) deciding.assign(ordered.rbegin(), ordered.rend());
  std::vector<char> listed(opt_.decide_window ? map_.points.size() : 0, 0);
  std::size_t cull = 0;
  std::vector<core::PointId> own_culls;
  for (int k : deciding) {
    const KeyFrame& d = map_.kfs[static_cast<std::size_t>(k)];
    for (std::size_t i = 0; i < d.mp.size(); ++i) {
      const int p = d.mp[i];
      if (p < 0 || map_.points[static_cast<std::size_t>(p)].bad) continue;
      const auto id = static_cast<core::PointId>(p);
      if (!std::binary_search(evaluated.begin(), evaluated.end(), id)) continue;
      if (opt_.decide_window) {
        if (listed[static_cast<std::size_t>(p)]) continue;
        listed[static_cast<std::size_t>(p)] = 1;
      }
      candidates.push_back({id, d.f.keys[i].pt.x, d.f.keys[i].pt.y, d.f.keys[i].response,
                            static_cast<int>(map_.points[static_cast<std::size_t>(p)].obs.size())});
      if (std::binary_search(keepless_culls.begin(), keepless_culls.end(), id)) {
        ++cull;
        own_culls.push_back(id);
      }
    }
  }
  // With a kept fraction every selector keeps the count core::FractionBudget
  // gives on its own map: the share F of the points new to it plus those it
  // kept before (keepless's budget is that rule; its floor may promote on
  // top). Keepless's verdicts go through it too, to count what it evaluated.
  const bool fraction = opt_.params.budget.kind == core::BudgetKind::kFraction && opt_.selector != Selector::kOriginal;
  std::vector<core::PointDecision> budget_view;
  if (fraction) {
    std::vector<core::PointId> ids;
    for (const Candidate& c : candidates) ids.push_back(c.id);
    std::sort(ids.begin(), ids.end());
    budget_view.assign(sparsifier_.decisions(), sparsifier_.decisions() + sparsifier_.decision_count());
    if (opt_.hashed_ids) {  // FractionBudget reads ascending ids
      for (core::PointDecision& d : budget_view) d.point = unhashed_id(d.point);
      std::sort(budget_view.begin(), budget_view.end(),
                [](const core::PointDecision& a, const core::PointDecision& b) { return a.point < b.point; });
    }
    for (core::PointDecision& d : budget_view) {
      d.verdict = std::binary_search(ids.begin(), ids.end(), d.point) ? core::Verdict::kCull : core::Verdict::kSkip;
    }
    const std::uint32_t keep =
        fraction_budget_.take(opt_.params.budget.fraction, budget_view.data(), static_cast<std::uint32_t>(budget_view.size()));
    if (opt_.selector != Selector::kKeepless) cull = candidates.size() - std::min<std::size_t>(keep, candidates.size());
  }
  kept_fraction_sum_ += candidates.empty() ? 1.0 : 1.0 - double(cull) / double(candidates.size());
  std::vector<core::PointId> culls;
  if (opt_.selector == Selector::kKeepless) {
    culls = own_culls;
    std::sort(culls.begin(), culls.end());  // in keypoint order so far
  } else if (opt_.selector != Selector::kOriginal) {
    culls = baseline_culls(opt_.selector, candidates, cull, opt_.seed, cam_.width, cam_.height);
  }
  if (!culls.empty() && culls.size() > marked_culls_) {
    marked_culls_ = culls.size();
    result_.marked_frame = f.frame;
    result_.marks.clear();
    for (std::size_t i = 0; i < f.mp.size(); ++i) {
      KeypointMark mark{f.f.keys[i].pt.x, f.f.keys[i].pt.y, 0};
      if (f.mp[i] >= 0 && !map_.points[static_cast<std::size_t>(f.mp[i])].bad) {
        mark.state = std::binary_search(culls.begin(), culls.end(), static_cast<core::PointId>(f.mp[i])) ? 2 : 1;
      }
      result_.marks.push_back(mark);
    }
  }
  if (fraction) {
    std::vector<core::PointId> sorted = culls;
    std::sort(sorted.begin(), sorted.end());
    for (core::PointDecision& d : budget_view) {
      if (d.verdict == core::Verdict::kCull && !std::binary_search(sorted.begin(), sorted.end(), d.point)) {
        d.verdict = core::Verdict::kKeep;
      }
    }
    fraction_budget_.record(budget_view.data(), static_cast<std::uint32_t>(budget_view.size()));
    result_.points_evaluated = static_cast<std::int64_t>(fraction_budget_.evaluated());
  }
  result_.points_culled_by_selector += static_cast<std::int64_t>(culls.size());
  for (core::PointId id : culls) {
    if (std::find(f.mp.begin(), f.mp.end(), static_cast<int>(id)) == f.mp.end()) ++result_.points_culled_elsewhere;
  }
  result_.selector_seconds += seconds_since(start);
  return culls;
}

// Immediate culling deletes the culls; deferred culling excludes them and
// deletes what core::DeferredCulls' rule says at this keyframe (also when
// the window was refused and nothing was culled, so no deletion is late).
void Vo::remove_culls(const std::vector<core::PointId>& culls) {
  if (!deferring()) {
    for (core::PointId id : culls) delete_cull(static_cast<int>(id));
    return;
  }
  // Out of local BA now, out of the map when the rule says (core::DeferredCulls).
  std::vector<core::PointId> excluded, deleted;
  opencv::defer_culls(culls, deferred_, &excluded, &deleted);
  const std::uint64_t now = deferred_.tick();
  for (core::PointId id : excluded) {
    map_.points[static_cast<std::size_t>(id)].excluded = true;
    map_.points[static_cast<std::size_t>(id)].matched_tick = now;
  }
  for (core::PointId id : deleted) {
    MapPoint& m = map_.points[static_cast<std::size_t>(id)];
    // Not before T unmatched keyframes (a refused cull, never excluded, goes at once).
    if (m.excluded && !m.bad && now - m.matched_tick < opt_.params.defer_keyframes) ++result_.defer_rule_violations;
    delete_cull(static_cast<int>(id));
  }
  // Nor after: no excluded point the map still holds has gone T unmatched keyframes.
  for (const MapPoint& m : map_.points) {
    if (m.excluded && !m.bad && now - m.matched_tick >= opt_.params.defer_keyframes) ++result_.defer_rule_violations;
  }
  result_.points_deleted_deferred += static_cast<std::int64_t>(deleted.size());
}

void Vo::delete_cull(int p) {
  if (opt_.keyframe_culling == KeyframeCulling::kCountCulled) {
    map_.cull_remembered(p);
  } else {
    map_.set_bad(p);
  }
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

// Deferred culling's clock: one tick per keyframe; the points its tracker
// matched (its tracked flags) are matched at this tick.
void Vo::note_matches(int kf) {
  const KeyFrame& f = map_.kfs[static_cast<std::size_t>(kf)];
  std::vector<core::PointId> ids;
  std::vector<std::uint8_t> tracked;
  for (std::size_t i = 0; i < f.mp.size() && i < f.tracked.size(); ++i) {
    const int p = f.mp[i] >= 0 ? map_.resolve(f.mp[i]) : -1;
    if (p < 0) continue;
    ids.push_back(static_cast<core::PointId>(p));
    tracked.push_back(f.tracked[i]);
  }
  (void)opencv::note_keyframe(deferred_, ids, &tracked);  // the lengths agree
  for (std::size_t j = 0; j < ids.size(); ++j) {
    MapPoint& m = map_.points[ids[j]];
    if (m.excluded && tracked[j] != 0) m.matched_tick = deferred_.tick();
  }
}

// Excluded points left out of the local BA keep a refined structure: each
// one the local keyframes observe is re-triangulated from all its
// observations with the adjusted poses (N-view DLT); a solution behind a
// camera or not finite leaves it where it was. With defer_refine the
// solution is then refined as local BA would refine it with the poses held
// (refine_point), and the observations it finds outliers are erased.
void Vo::retriangulate_excluded(const std::vector<int>& local) {
  std::vector<Eigen::Isometry3d> tcw;
  std::vector<BaObservation> obs;
  std::vector<int> observer;
  std::vector<bool> outlier;
  for (int p : map_.points_of(local)) {
    MapPoint& m = map_.points[static_cast<std::size_t>(p)];
    if (!m.excluded || m.bad) continue;
    Eigen::MatrixXd A(2 * m.obs.size(), 4);
    Eigen::Index rows = 0;
    tcw.clear();
    obs.clear();
    observer.clear();
    for (const auto& [k, i] : m.obs) {
      const KeyFrame& f = map_.kfs[static_cast<std::size_t>(k)];
      if (f.bad) continue;
      const Eigen::Matrix<double, 3, 4> P = K_ * f.Tcw.matrix().topRows<3>();
      const cv::KeyPoint& kp = f.f.keys[static_cast<std::size_t>(i)];
      A.row(rows++) = kp.pt.x * P.row(2) - P.row(0);
      A.row(rows++) = kp.pt.y * P.row(2) - P.row(1);
      tcw.push_back(f.Tcw);
      obs.push_back({0, 0, kp.pt.x, kp.pt.y, f.f.ur[static_cast<std::size_t>(i)], kp.octave});
      observer.push_back(k);
    }
    Eigen::Vector3d X;
    if (rows < 4 || !dlt_point(A.topRows(rows), &X)) continue;
    bool in_front = true;
    for (const Eigen::Isometry3d& T : tcw) in_front = in_front && (T * X).z() > 0;
    if (!in_front) continue;
    if (opt_.defer_refine) {
      if (!refine_point(cam_, tcw, obs, &X, &outlier)) continue;
      for (std::size_t o = 0; o < outlier.size() && !m.bad; ++o) {
        if (outlier[o]) map_.erase_observation(p, observer[o]);
      }
      if (m.bad) {
        (void)deferred_.forget(static_cast<core::PointId>(p));  // the map deleted it, not the rule
        continue;
      }
    }
    m.X = X;
    map_.update_point(p);
  }
}

// defer_alternate: each local keyframe but the first of the map, motion-only
// against every point it observes (kept and excluded), as tracking refines a
// frame; a solution with fewer than 15 inliers leaves the pose as it was.
void Vo::refine_local_poses(const std::vector<int>& local) {
  std::vector<Eigen::Vector3d> X;
  std::vector<BaObservation> obs;
  std::vector<bool> outlier;
  for (int k : local) {
    KeyFrame& f = map_.kfs[static_cast<std::size_t>(k)];
    if (k == 0 || f.bad) continue;
    X.clear();
    obs.clear();
    for (std::size_t i = 0; i < f.mp.size(); ++i) {
      const int p = f.mp[i] >= 0 ? map_.resolve(f.mp[i]) : -1;
      if (p < 0 || map_.points[static_cast<std::size_t>(p)].bad) continue;
      X.push_back(map_.points[static_cast<std::size_t>(p)].X);
      const cv::KeyPoint& kp = f.f.keys[i];
      obs.push_back({0, static_cast<int>(X.size()) - 1, kp.pt.x, kp.pt.y, f.f.ur[i], kp.octave});
    }
    if (obs.size() < 15) continue;
    Eigen::Isometry3d T = f.Tcw;
    if (optimize_pose(cam_, X, obs, &T, &outlier) >= 15) f.Tcw = T;
  }
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
  for (int i = 0; i < result_.frames; ++i) {
    TrackedFrame cur;
    cur.index = i;
    if (!features_of(i, &cur.f)) return result_;
    bool tracked = false;
    if (!initialised_) {
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
      if (tracked) {
        velocity_ = cur.Tcw * before.inverse();
        have_velocity_ = true;
        last_ = cur;
      } else {
        have_velocity_ = false;
      }
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

}  // namespace

RealRunResult run_real_vo(const RealSequence& sequence, const RealVoOptions& options) {
  cv::setNumThreads(1);
  cv::theRNG().state = options.seed;
  Vo vo(sequence, options);
  return vo.run();
}

}  // namespace keepless::eval::vo
