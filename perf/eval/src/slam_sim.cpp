#include "slam_sim.hpp"

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <unordered_map>

#include "keepless/core/keep_thresholds.hpp"
#include "keepless/core/sparsifier.hpp"
#include "keepless/core/window.hpp"
#include "local_ba.hpp"
#include "metrics.hpp"
#include "prng.hpp"
#include "ssc.hpp"

namespace keepless::eval {
namespace {

using Clock = std::chrono::steady_clock;
// This thread's CPU time: what a solve costs whatever else the machine runs.
double thread_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

constexpr double kPi = 3.141592653589793;
constexpr int kMinTrackInliers = 10;     // ORB-SLAM2 TrackWithMotionModel
constexpr int kCovisibilityWeight = 15;  // ORB-SLAM2 UpdateConnections
constexpr double kMinFoundRatio = 0.25;  // ORB-SLAM2 MapPointCulling
constexpr double kMaxScaleRatio = 3.5832;  // 1.2^7: ORB-SLAM2's 8-level pyramid

using Sighting = std::pair<int, int>;  // (keyframe, keypoint index)

struct MapPoint {
  std::array<double, 3> X{};
  std::uint64_t landmark = 0;
  int first_kf = 0;
  bool alive = true;
  int visible = 1, found = 1;  // ORB-SLAM2's counters, 1 at creation
  double max_distance = 0;     // from the creating camera; the frustum test uses it
  std::vector<Sighting> obs;
};

class Engine {
 public:
  Engine(const Scenario& s, const VariantSpec& spec, const SimOptions& o) : s_(s), spec_(spec), o_(o) {}

  RunResult run() {
    const auto t0 = Clock::now();
    RunResult r;
    r.spec = spec_;
    r.sim3 = !metric();
    init_keepless();
    const int n = static_cast<int>(s_.frames.size());
    lm_mp_.assign(s_.landmark_count, -1);
    lm_selector_culled_.assign(s_.landmark_count, 0);
    kf_alive_.assign(static_cast<std::size_t>(n), false);
    kf_kp_mp_.resize(static_cast<std::size_t>(n));
    poses_.resize(static_cast<std::size_t>(n));
    links_.assign(static_cast<std::size_t>(n), CulledLink{});
    for (int k = 0; k < n; ++k) {
      track(k, &r);
      cull_recent_points(k);
      create_points(k);
      const std::vector<int> window = local_keyframes(k, o_.window);
      if (o_.measure_windows) measure_windows(k, &r);
      const auto ts = Clock::now();
      select_points(window, &r);
      r.select_s += seconds_since(ts);
      if (k >= 1) {
        local_ba(window, &r);
        cull_keyframes(window, k);
      }
      local_map_kfs_ = window;
      if (o_.snapshot_frame >= 0 && k == std::min(n - 1, o_.snapshot_frame + o_.window - 1)) take_snapshot(&r);
    }
    r.total_s = seconds_since(t0);
    finish(&r);
    return r;
  }

 private:
  bool metric() const { return s_.cam.baseline > 0; }
  bool stereo(const KeyPoint& p) const { return metric() && p.ur >= 0; }
  Pose est(int k) const { return from_block(poses_[static_cast<std::size_t>(k)].data()); }
  const KeyPoint& kp(int k, int i) const {
    return s_.frames[static_cast<std::size_t>(k)].keypoints[static_cast<std::size_t>(i)];
  }
  MapPoint& mp(int m) { return mps_[static_cast<std::size_t>(m)]; }
  // ORB-SLAM2 MapPoint::Observations(): a stereo observation counts twice.
  int nobs(const MapPoint& p) const {
    int c = 0;
    for (const auto& o : p.obs) c += stereo(kp(o.first, o.second)) ? 2 : 1;
    return c;
  }

  void init_keepless() {
    if (spec_.selector == Selector::kNone) return;
    std::uint32_t max_kp = 1;
    for (const auto& f : s_.frames) max_kp = std::max<std::uint32_t>(max_kp, static_cast<std::uint32_t>(f.keypoints.size()));
    const auto W = static_cast<std::uint32_t>(o_.window);
    core::Capacities caps;
    caps.max_keyframes = W;
    caps.max_observations = W * max_kp;
    caps.max_points = W * max_kp;
    caps.max_unmapped_keypoints = W * max_kp;  // CostModel::kAuthors counts every detection
    caps.max_pair_arcs = static_cast<std::uint32_t>(
        std::min<std::uint64_t>(std::uint64_t(caps.max_points) * (W * (W - 1) / 2), 1u << 21));
    core::Params params = spec_.params;
    if (spec_.selector != Selector::kKeepless) params.cost_terms = core::Params{}.cost_terms;  // the count to match
    window_ = std::make_unique<core::Window>(caps);
    sparsifier_ = std::make_unique<core::Sparsifier>(caps, params);
    fraction_budget_ = std::make_unique<core::FractionBudget>(caps.max_points);
    obs_buffer_.reserve(max_kp);
    unmapped_buffer_.reserve(caps.max_unmapped_keypoints);
  }

  // Tracking: the odometry prior refined by motion-only BA against the local
  // map's points the keyframe's keypoints see; inliers become observations.
  void track(int k, RunResult* r) {
    const auto ku = static_cast<std::size_t>(k);
    kf_alive_[ku] = true;
    const auto& kps = s_.frames[ku].keypoints;
    kf_kp_mp_[ku].assign(kps.size(), -1);
    const bool gauge = k == 0 || (k == 1 && s_.fix_first_two);
    poses_[ku] = to_block(gauge ? s_.frames[ku].gt : est(k - 1) * s_.odometry[ku]);
    if (k == 0) return;
    ++stamp_;
    if (mp_stamp_.size() < mps_.size()) mp_stamp_.resize(mps_.size(), 0);
    std::vector<int> local;
    for (int f : local_map_kfs_)
      for (int m : kf_kp_mp_[static_cast<std::size_t>(f)])
        if (m >= 0 && mp_stamp_[static_cast<std::size_t>(m)] != stamp_) {
          mp_stamp_[static_cast<std::size_t>(m)] = stamp_;
          local.push_back(m);
        }
    std::vector<PoseObservation> corr;
    std::vector<std::pair<int, int>> which;  // (map point, keypoint)
    for (int i = 0; i < static_cast<int>(kps.size()); ++i) {
      const int m = lm_mp_[kps[static_cast<std::size_t>(i)].landmark];
      if (m < 0 || mp_stamp_[static_cast<std::size_t>(m)] != stamp_) continue;  // not in the local map
      const KeyPoint& p = kps[static_cast<std::size_t>(i)];
      corr.push_back(PoseObservation{mp(m).X.data(), p.u, p.v, stereo(p) ? p.ur : -1.0});
      which.emplace_back(m, i);
    }
    std::vector<bool> outlier(corr.size(), false);
    if (!gauge) {
      std::array<double, 6> pose = poses_[ku];
      const PoseResult pr = optimize_pose(s_.cam, corr, pose.data());
      if (pr.inliers >= kMinTrackInliers) {
        poses_[ku] = pose;
        outlier = pr.outlier;
      } else {
        ++r->track_failures;  // lost: keep the prior, match nothing
        outlier.assign(corr.size(), true);
      }
    }
    // Visible: in the frustum at the tracked pose, within the scale range.
    const Pose T_wc = est(k), T_cw = T_wc.inverse();
    for (int m : local) {
      MapPoint& p = mp(m);
      const Eigen::Vector3d X(p.X[0], p.X[1], p.X[2]);
      const double dist = (X - T_wc.t).norm();
      if (dist > 1.2 * p.max_distance || dist < 0.8 * p.max_distance / kMaxScaleRatio) continue;
      const Eigen::Vector3d pc = T_cw * X;
      if (pc.z() <= 0) continue;
      const double u = s_.cam.fx * pc.x() / pc.z() + s_.cam.cx, v = s_.cam.fy * pc.y() / pc.z() + s_.cam.cy;
      if (u >= 0 && v >= 0 && u < s_.cam.width && v < s_.cam.height) ++p.visible;
    }
    for (std::size_t j = 0; j < which.size(); ++j)
      if (!outlier[j]) {
        add_obs(which[j].first, k, which[j].second);
        ++mp(which[j].first).found;
      }
  }

  // New map points from the keyframe's unmatched keypoints whose landmark
  // has no map point (never mapped, or culled): stereo at once, monocular by
  // triangulation with an earlier sighting; each fused into the local
  // keyframes' unmatched keypoints of the same landmark.
  void create_points(int k) {
    const auto& kps = s_.frames[static_cast<std::size_t>(k)].keypoints;
    const Pose T_wc = est(k);
    for (int i = 0; i < static_cast<int>(kps.size()); ++i) {
      if (kf_kp_mp_[static_cast<std::size_t>(k)][static_cast<std::size_t>(i)] >= 0) continue;
      const KeyPoint& p = kps[static_cast<std::size_t>(i)];
      if (lm_mp_[p.landmark] >= 0) continue;  // mapped, but not matched by tracking
      auto& pend = pending_[p.landmark];
      // Sightings stay candidates while their keyframe is alive and recent.
      pend.erase(std::remove_if(pend.begin(), pend.end(),
                                [&](const Sighting& o) {
                                  return !kf_alive_[static_cast<std::size_t>(o.first)] || k - o.first >= o_.window ||
                                         kf_kp_mp_[static_cast<std::size_t>(o.first)][static_cast<std::size_t>(o.second)] >= 0;
                                }),
                 pend.end());
      const double disparity = p.u - p.ur;
      if (stereo(p) && disparity > 0.5) {
        const double z = s_.cam.fx * s_.cam.baseline / disparity;
        create_mp(p.landmark, k, i, T_wc * Eigen::Vector3d((p.u - s_.cam.cx) / s_.cam.fx * z, (p.v - s_.cam.cy) / s_.cam.fy * z, z));
        continue;
      }
      Eigen::Vector3d X;
      if (!pend.empty() && triangulate(pend.front(), Sighting{k, i}, &X)) create_mp(p.landmark, k, i, X);
      else pend.emplace_back(k, i);
    }
  }

  Eigen::Vector3d ray(int k, int i) const {
    const KeyPoint& a = kp(k, i);
    return (est(k).q * Eigen::Vector3d((a.u - s_.cam.cx) / s_.cam.fx, (a.v - s_.cam.cy) / s_.cam.fy, 1)).normalized();
  }

  // Midpoint of the closest approach of two rays with >= 1 degree parallax.
  bool triangulate(const Sighting& s0, const Sighting& s1, Eigen::Vector3d* X) const {
    const Pose P0 = est(s0.first), P1 = est(s1.first);
    const Eigen::Vector3d d0 = ray(s0.first, s0.second), d1 = ray(s1.first, s1.second);
    if (d0.dot(d1) >= std::cos(1.0 * kPi / 180.0)) return false;
    const Eigen::Vector3d w = P0.t - P1.t;
    const double bb = d0.dot(d1), d = d0.dot(w), e = d1.dot(w);
    const double den = 1.0 - bb * bb;
    const double t0 = (bb * e - d) / den, t1 = (e - bb * d) / den;
    if (t0 <= 0 || t1 <= 0) return false;
    *X = 0.5 * ((P0.t + t0 * d0) + (P1.t + t1 * d1));
    return true;
  }

  void create_mp(std::uint64_t l, int k, int i, const Eigen::Vector3d& X) {
    MapPoint p;
    p.X = {X.x(), X.y(), X.z()};
    p.landmark = l;
    p.first_kf = k;
    p.max_distance = (X - est(k).t).norm();
    const int m = static_cast<int>(mps_.size());
    mps_.push_back(std::move(p));
    lm_mp_[l] = m;
    lm_selector_culled_[l] = 0;
    add_obs(m, k, i);
    recent_.push_back(m);
    auto it = pending_.find(l);
    if (it == pending_.end()) return;
    for (const Sighting& o : it->second)  // fuse (already filtered to alive, recent, unmatched)
      if (o.first != k) add_obs(m, o.first, o.second);
    pending_.erase(it);
  }

  void add_obs(int m, int k, int i) {
    mp(m).obs.emplace_back(k, i);
    kf_kp_mp_[static_cast<std::size_t>(k)][static_cast<std::size_t>(i)] = m;
  }

  // ORB-SLAM2 EraseObservation: a point left with <= 2 observations goes.
  void erase_obs(int m, int k, int i) {
    auto& obs = mp(m).obs;
    obs.erase(std::remove(obs.begin(), obs.end(), Sighting{k, i}), obs.end());
    kf_kp_mp_[static_cast<std::size_t>(k)][static_cast<std::size_t>(i)] = -1;
    if (mp(m).alive && nobs(mp(m)) <= 2) kill(m);
  }

  // Its keypoints become unmatched again: a later keyframe that sees the
  // landmark re-creates the point and fuses them, as ORB-SLAM2 does.
  void kill(int m) {
    MapPoint& p = mp(m);
    if (!p.alive) return;
    p.alive = false;
    auto& pend = pending_[p.landmark];
    for (const auto& o : p.obs) {
      kf_kp_mp_[static_cast<std::size_t>(o.first)][static_cast<std::size_t>(o.second)] = -1;
      if (kf_alive_[static_cast<std::size_t>(o.first)]) pend.push_back(o);
    }
    std::sort(pend.begin(), pend.end());
    p.obs.clear();
    lm_mp_[p.landmark] = -1;
  }

  // ORB-SLAM2 MapPointCulling.
  void cull_recent_points(int k) {
    const int max_obs = metric() ? 3 : 2;
    std::size_t w = 0;
    for (std::size_t r = 0; r < recent_.size(); ++r) {
      const int m = recent_[r];
      MapPoint& p = mp(m);
      if (!p.alive) continue;
      const int age = k - p.first_kf;
      if (double(p.found) / double(p.visible) < kMinFoundRatio || (age >= 2 && nobs(p) <= max_obs)) {
        kill(m);
        continue;
      }
      if (age < 3) recent_[w++] = m;
    }
    recent_.resize(w);
  }

  // Shared map points of keyframe k with every other keyframe.
  std::unordered_map<int, int> covisibility(int k) const {
    std::unordered_map<int, int> w;
    for (int m : kf_kp_mp_[static_cast<std::size_t>(k)])
      if (m >= 0)
        for (const auto& o : mps_[static_cast<std::size_t>(m)].obs)
          if (o.first != k) ++w[o.first];
    return w;
  }

  // The new keyframe and its covisible keyframes (>= 15 shared points, the
  // best one if none), the strongest first, at most W; oldest first.
  std::vector<int> local_keyframes(int k, int most) const {
    std::vector<std::pair<int, int>> cov;  // (-weight, kf)
    for (const auto& [f, wgt] : covisibility(k)) cov.emplace_back(-wgt, f);
    std::sort(cov.begin(), cov.end());
    std::vector<int> w{k};
    for (const auto& [negw, f] : cov) {
      if (static_cast<int>(w.size()) >= most || (-negw < kCovisibilityWeight && w.size() > 1)) break;
      w.push_back(f);
    }
    std::sort(w.begin(), w.end());
    return w;
  }

  // window_sizes.hpp: the local and sliding windows at keyframe k, per K.
  void measure_windows(int k, RunResult* r) {
    WindowMeasure m;
    std::vector<core::PointId> ids;
    const auto measure = [&](const std::vector<int>& window) {
      m.clear();
      for (int f : window) {
        ids.clear();
        std::uint64_t unmapped = 0;
        for (int id : kf_kp_mp_[static_cast<std::size_t>(f)]) {
          if (id >= 0) ids.push_back(static_cast<core::PointId>(id));
          else ++unmapped;
        }
        m.add_keyframe(ids, unmapped);
      }
      return m.size();
    };
    for (std::size_t i = 0; i < WindowSizes::kSizes.size(); ++i) {
      const int most = WindowSizes::kSizes[i];
      r->window_sizes.local[i].max_with(measure(local_keyframes(k, most)));
      std::vector<int> sliding;
      for (int f = k; f >= 0 && static_cast<int>(sliding.size()) < most; --f)
        if (kf_alive_[static_cast<std::size_t>(f)]) sliding.push_back(f);
      r->window_sizes.sliding[i].max_with(measure(sliding));
    }
    ++r->window_sizes.steps;
  }

  void select_points(const std::vector<int>& window, RunResult* r) {
    if (spec_.selector == Selector::kNone || window.size() < 2) return;
    window_->clear();
    unmapped_buffer_.clear();  // one buffer for the window: the Window holds the pointers until clear()
    for (int f : window) {
      obs_buffer_.clear();
      const Pose P = est(f), T_cw = P.inverse();
      const std::size_t first_unmapped = unmapped_buffer_.size();
      const auto& ids = kf_kp_mp_[static_cast<std::size_t>(f)];
      for (std::size_t i = 0; i < ids.size(); ++i) {
        const KeyPoint& p = kp(f, static_cast<int>(i));
        if (ids[i] < 0) {
          unmapped_buffer_.push_back(core::Keypoint{p.u, p.v});  // the authors' N(p,f) counts these too
          continue;
        }
        const MapPoint& m = mps_[static_cast<std::size_t>(ids[i])];
        const double depth = (T_cw * Eigen::Vector3d(m.X[0], m.X[1], m.X[2])).z();  // the estimate, as a SLAM has it
        obs_buffer_.push_back(core::Observation{static_cast<core::PointId>(ids[i]), p.u, p.v, depth});
      }
      core::Keyframe kf;
      kf.fx = s_.cam.fx; kf.fy = s_.cam.fy; kf.cx = s_.cam.cx; kf.cy = s_.cam.cy;
      kf.unmapped = unmapped_buffer_.data() + first_unmapped;
      kf.unmapped_count = static_cast<std::uint32_t>(unmapped_buffer_.size() - first_unmapped);
      kf.id = static_cast<core::KeyframeId>(f);
      kf.centre[0] = P.t.x(); kf.centre[1] = P.t.y(); kf.centre[2] = P.t.z();
      kf.orientation[0] = P.q.w(); kf.orientation[1] = P.q.x(); kf.orientation[2] = P.q.y(); kf.orientation[3] = P.q.z();
      if (window_->add_keyframe(kf, obs_buffer_.data(), static_cast<std::uint32_t>(obs_buffer_.size())) != core::Status::kOk) {
        ++r->selector_errors;
        return;
      }
    }
    if (sparsifier_->run(*window_) != core::Status::kOk) {
      ++r->selector_errors;
      return;
    }
    r->selector.add(sparsifier_->summary());
    const core::PointDecision* d = sparsifier_->decisions();
    const std::uint32_t nd = sparsifier_->decision_count();
    std::vector<int> evaluated;
    std::vector<char> kept;
    for (std::uint32_t i = 0; i < nd; ++i)
      if (d[i].verdict != core::Verdict::kSkip) {
        evaluated.push_back(static_cast<int>(d[i].point));
        kept.push_back(d[i].verdict == core::Verdict::kKeep);
      }
    // Baselines keep exactly as many of the evaluated points as keepless
    // keeps on this same window, by their own rule.
    // With a kept fraction (a keep budget) the count is the budget's rule
    // (core::FractionBudget) on the baseline's own decisions, never one
    // copied from another run.
    if (spec_.selector != Selector::kKeepless) {
      const core::KeepBudget& budget = spec_.params.budget;
      const bool fraction = budget.kind == core::BudgetKind::kFraction;
      std::vector<core::PointDecision> view(d, d + nd);
      const auto keep = fraction ? fraction_budget_->take(budget.fraction, view.data(), nd)
                                 : static_cast<std::uint32_t>(std::count(kept.begin(), kept.end(), 1));
      std::fill(kept.begin(), kept.end(), 0);
      if (spec_.selector == Selector::kAnms) anms_keep(window, evaluated, keep, &kept);
      else priority_keep(evaluated, keep, &kept);
      if (fraction) {
        for (std::uint32_t i = 0, j = 0; i < nd; ++i) {
          if (view[i].verdict == core::Verdict::kSkip) continue;
          view[i].verdict = kept[j++] ? core::Verdict::kKeep : core::Verdict::kCull;
        }
        fraction_budget_->record(view.data(), nd);
      }
    }
    for (std::size_t i = 0; i < evaluated.size(); ++i)
      if (!kept[i]) {
        lm_selector_culled_[mp(evaluated[i]).landmark] = 1;
        kill(evaluated[i]);
        ++r->selector_culled;
      }
  }

  // Random: a fixed priority per landmark, so a point's fate is stable across
  // windows (a fresh draw each window would cull far more). Longest track:
  // most observing keyframes first, then the older point.
  void priority_keep(const std::vector<int>& evaluated, std::uint32_t keep, std::vector<char>* kept) {
    std::vector<std::uint32_t> order(evaluated.size());
    for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
    auto key = [&](std::uint32_t i) {
      const MapPoint& p = mps_[static_cast<std::size_t>(evaluated[i])];
      if (spec_.selector == Selector::kRandom) return std::make_tuple(std::uint64_t{0}, mix(o_.seed, p.landmark), p.landmark);
      return std::make_tuple(~std::uint64_t(p.obs.size()), std::uint64_t(p.first_kf), p.landmark);
    };
    std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return key(a) < key(b); });
    for (std::uint32_t i = 0; i < keep && i < order.size(); ++i) (*kept)[order[i]] = 1;
  }

  // ANMS: each point is judged in the newest window keyframe that sees it, by
  // SSC on keypoint responses; keyframes share the count in proportion to
  // their points (largest remainder).
  void anms_keep(const std::vector<int>& window, const std::vector<int>& evaluated, std::uint32_t keep,
                 std::vector<char>* kept) {
    std::unordered_map<int, std::uint32_t> index_of;
    for (std::uint32_t i = 0; i < evaluated.size(); ++i) index_of[evaluated[i]] = i;
    std::vector<int> home(evaluated.size(), -1), home_kp(evaluated.size(), -1);
    for (int f : window) {
      const auto& ids = kf_kp_mp_[static_cast<std::size_t>(f)];
      for (std::size_t i = 0; i < ids.size(); ++i) {
        if (ids[i] < 0) continue;
        auto it = index_of.find(ids[i]);
        if (it == index_of.end()) continue;
        home[it->second] = f;
        home_kp[it->second] = static_cast<int>(i);
      }
    }
    std::vector<std::vector<std::uint32_t>> per(window.size());
    for (std::uint32_t i = 0; i < evaluated.size(); ++i) {
      const auto slot = static_cast<std::size_t>(std::find(window.begin(), window.end(), home[i]) - window.begin());
      per[slot].push_back(i);
    }
    std::vector<std::vector<SscPoint>> groups(window.size());
    for (std::size_t sl = 0; sl < window.size(); ++sl) {
      for (std::uint32_t i : per[sl]) {
        const KeyPoint& p = kp(home[i], home_kp[i]);
        groups[sl].push_back(SscPoint{p.u, p.v, p.response, static_cast<std::uint64_t>(evaluated[i])});
      }
    }
    const auto chosen = ssc_select_shared(groups, keep, s_.cam.width, s_.cam.height);
    for (std::size_t sl = 0; sl < window.size(); ++sl) {
      for (std::uint32_t j : chosen[sl]) (*kept)[per[sl][j]] = 1;
    }
  }

  void local_ba(const std::vector<int>& window, RunResult* r) {
    BaInput in;
    std::unordered_map<int, int> pose_index;
    auto add_pose = [&](int k, bool fixed) {
      auto it = pose_index.find(k);
      if (it != pose_index.end()) return it->second;
      const int idx = static_cast<int>(in.poses.size());
      pose_index[k] = idx;
      in.poses.push_back(poses_[static_cast<std::size_t>(k)].data());
      in.pose_fixed.push_back(fixed);
      return idx;
    };
    for (int f : window) add_pose(f, s_.fix_first_two ? f < 2 : f == 0);
    std::vector<int> local;
    ++stamp_;
    if (mp_stamp_.size() < mps_.size()) mp_stamp_.resize(mps_.size(), 0);
    for (int f : window)
      for (int m : kf_kp_mp_[static_cast<std::size_t>(f)])
        if (m >= 0 && mp_stamp_[static_cast<std::size_t>(m)] != stamp_) {
          mp_stamp_[static_cast<std::size_t>(m)] = stamp_;
          local.push_back(m);
        }
    std::vector<std::pair<int, Sighting>> refs;  // (mp, sighting) per observation
    for (std::size_t j = 0; j < local.size(); ++j) {
      MapPoint& p = mp(local[j]);
      in.points.push_back(p.X.data());
      for (const auto& o : p.obs) {
        const int pi = add_pose(o.first, true);  // observers outside the window stay fixed
        const KeyPoint& q = kp(o.first, o.second);
        in.observations.push_back(BaObservation{pi, static_cast<int>(j), q.u, q.v, stereo(q) ? q.ur : -1.0});
        refs.emplace_back(local[j], o);
      }
    }
    const double cpu0 = thread_cpu_seconds();
    const BaResult res = solve_local_ba(s_.cam, in, o_.ba_robust_iterations, o_.ba_iterations);
    r->ba_cpu_s += thread_cpu_seconds() - cpu0;
    r->ba_s += res.seconds;
    r->ba_observations += in.observations.size();
    ++r->ba_calls;
    for (std::size_t i = 0; i < refs.size(); ++i)
      if (res.outlier[i] && mp(refs[i].first).alive) erase_obs(refs[i].first, refs[i].second.first, refs[i].second.second);
  }

  // ORB-SLAM2 KeyFrameCulling on the local keyframes (not the newest, not the
  // gauge keyframes); for stereo only close points (with a right match) count.
  void cull_keyframes(const std::vector<int>& window, int newest) {
    for (int f : window) {
      if (f == newest || f < 2) continue;
      int n = 0, redundant = 0;
      const auto& ids = kf_kp_mp_[static_cast<std::size_t>(f)];
      for (std::size_t i = 0; i < ids.size(); ++i) {
        if (ids[i] < 0 || (metric() && !stereo(kp(f, static_cast<int>(i))))) continue;
        ++n;
        if (mps_[static_cast<std::size_t>(ids[i])].obs.size() >= 4) ++redundant;  // >= 3 others
      }
      if (n == 0 || redundant <= 0.9 * n) continue;
      // Parent: the alive keyframe sharing the most points (ORB-SLAM2's
      // spanning tree); the culled pose follows it from now on.
      int parent = -1, best = 0;
      for (const auto& [g, wgt] : covisibility(f))
        if (kf_alive_[static_cast<std::size_t>(g)] && (wgt > best || (wgt == best && g < parent))) {
          parent = g;
          best = wgt;
        }
      if (parent < 0) continue;
      links_[static_cast<std::size_t>(f)] = CulledLink{parent, est(parent).inverse() * est(f)};
      kf_alive_[static_cast<std::size_t>(f)] = false;
      for (std::size_t i = 0; i < ids.size(); ++i)
        if (ids[i] >= 0) erase_obs(ids[i], f, static_cast<int>(i));
      kf_kp_mp_[static_cast<std::size_t>(f)].clear();
    }
  }

  void take_snapshot(RunResult* r) const {
    const int k = o_.snapshot_frame;
    r->snapshot.clear();
    for (const KeyPoint& p : s_.frames[static_cast<std::size_t>(k)].keypoints) {
      int state = 0;
      if (lm_mp_[p.landmark] >= 0) state = 1;
      else if (lm_selector_culled_[p.landmark]) state = 2;
      r->snapshot.push_back(SnapshotPoint{p.u, p.v, state});
    }
  }

  void finish(RunResult* r) {
    const std::size_t n = s_.frames.size();
    r->kfs_total = static_cast<std::uint32_t>(n);
    r->mps_created = mps_.size();
    std::vector<Pose> own(n), gt(n);
    for (std::size_t k = 0; k < n; ++k) {
      own[k] = est(static_cast<int>(k));
      gt[k] = s_.frames[k].gt;
      if (kf_alive_[k]) ++r->kfs;
    }
    r->estimate = resolve_keyframe_poses(own, links_);
    const Ate ate = absolute_trajectory_error(r->estimate, gt, r->sim3);
    if (std::getenv("KEEPLESS_EVAL_DEBUG"))
      for (std::size_t k = 0; k < n; ++k)
        std::fprintf(stderr, "  kf %zu%s: pos err %.4f rot err %.3f deg\n", k, kf_alive_[k] ? "" : " (culled)",
                     (r->estimate[k].t - gt[k].t).norm(), rotation_angle(gt[k].q.conjugate() * r->estimate[k].q) * 57.29578);
    r->ate_m = ate.rms_m;
    r->ate_r_deg = ate.rms_r_deg;
    double c = 0, fsum = 0;
    for (const MapPoint& p : mps_) {
      if (!p.alive) continue;
      ++r->mps;
      c += double(p.obs.size());
      int lo = 1 << 30, hi = -1;
      for (const auto& o : p.obs) {
        lo = std::min(lo, o.first);
        hi = std::max(hi, o.first);
      }
      if (hi >= lo) fsum += hi - lo;
    }
    if (r->mps > 0) {
      r->C = c / r->mps;
      r->F = fsum / r->mps;
    }
    // S: occupancy of a 64x48 grid of cells over the image, per keyframe.
    double ssum = 0;
    int nk = 0;
    std::vector<char> cells(64 * 48);
    for (std::size_t k = 0; k < n; ++k) {
      if (!kf_alive_[k]) continue;
      std::fill(cells.begin(), cells.end(), 0);
      int occ = 0;
      for (std::size_t i = 0; i < kf_kp_mp_[k].size(); ++i) {
        if (kf_kp_mp_[k][i] < 0) continue;
        const KeyPoint& p = s_.frames[k].keypoints[i];
        const int cx = std::clamp(static_cast<int>(p.u * 64.0 / s_.cam.width), 0, 63);
        const int cy = std::clamp(static_cast<int>(p.v * 48.0 / s_.cam.height), 0, 47);
        if (!cells[static_cast<std::size_t>(cy * 64 + cx)]++) ++occ;
      }
      ssum += 100.0 * occ / (64.0 * 48.0);
      ++nk;
    }
    if (nk > 0) r->S = ssum / nk;
  }

  const Scenario& s_;
  VariantSpec spec_;
  SimOptions o_;
  std::vector<int> lm_mp_;                  // landmark -> alive map point, or -1
  std::vector<std::uint8_t> lm_selector_culled_;
  std::unordered_map<std::uint64_t, std::vector<Sighting>> pending_;  // unmatched sightings per landmark
  std::vector<MapPoint> mps_;
  std::vector<int> recent_;
  std::vector<int> local_map_kfs_;          // the previous local keyframes: tracking's local map
  std::vector<bool> kf_alive_;
  std::vector<std::vector<int>> kf_kp_mp_;
  std::vector<std::array<double, 6>> poses_;
  std::vector<CulledLink> links_;
  std::vector<std::uint32_t> mp_stamp_;
  std::uint32_t stamp_ = 0;
  std::unique_ptr<core::Window> window_;
  std::unique_ptr<core::Sparsifier> sparsifier_;
  std::unique_ptr<core::FractionBudget> fraction_budget_;  // a kept fraction's count for a baseline
  std::vector<core::Observation> obs_buffer_;
  std::vector<core::Keypoint> unmapped_buffer_;
};

}  // namespace

const char* to_string(Selector s) {
  switch (s) {
    case Selector::kNone: return "none";
    case Selector::kKeepless: return "keepless";
    case Selector::kAnms: return "anms";
    case Selector::kRandom: return "random";
    case Selector::kLongestTrack: return "longest_track";
  }
  return "?";
}

RunResult run_slam(const Scenario& scenario, const VariantSpec& spec, const SimOptions& options) {
  Engine e(scenario, spec, options);
  return e.run();
}

}  // namespace keepless::eval
