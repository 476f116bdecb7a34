#include "slam_sim.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <unordered_map>

#include "keepless/core/sparsifier.hpp"
#include "keepless/core/window.hpp"
#include "local_ba.hpp"
#include "metrics.hpp"
#include "prng.hpp"
#include "ssc.hpp"

namespace keepless::eval {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

enum LmState : std::uint8_t { kNew = 0, kPending, kMapped, kSelectorCulled, kSlamCulled };

struct MapPoint {
  std::array<double, 3> X{};
  std::uint64_t landmark = 0;
  int first_kf = 0;
  bool alive = true;
  std::vector<std::pair<int, int>> obs;  // (keyframe, keypoint index)
};

class Engine {
 public:
  Engine(const Scenario& s, const VariantSpec& spec, const SimOptions& o) : s_(s), spec_(spec), o_(o) {}

  RunResult run() {
    const auto t0 = Clock::now();
    RunResult r;
    r.spec = spec_;
    init_keepless();
    const int n = static_cast<int>(s_.frames.size());
    lm_state_.assign(s_.landmark_count, kNew);
    lm_mp_.assign(s_.landmark_count, -1);
    kf_alive_.assign(static_cast<std::size_t>(n), false);
    kf_kp_mp_.resize(static_cast<std::size_t>(n));
    poses_.resize(static_cast<std::size_t>(n));
    for (int k = 0; k < n; ++k) {
      insert_keyframe(k);
      cull_recent_points(k);
      std::vector<int> window = window_keyframes();
      const auto ts = Clock::now();
      select_points(window, &r);
      r.select_s += seconds_since(ts);
      if (k >= 1) {
        local_ba(window, &r);
        cull_keyframes(window, k);
      }
      if (o_.snapshot_frame >= 0 && k == std::min(n - 1, o_.snapshot_frame + o_.window - 1)) take_snapshot(&r);
    }
    r.total_s = seconds_since(t0);
    finish(&r);
    return r;
  }

 private:
  Pose est(int k) const { return from_block(poses_[static_cast<std::size_t>(k)].data()); }
  const KeyPoint& kp(int k, int i) const {
    return s_.frames[static_cast<std::size_t>(k)].keypoints[static_cast<std::size_t>(i)];
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
    caps.max_pair_arcs = static_cast<std::uint32_t>(
        std::min<std::uint64_t>(std::uint64_t(caps.max_points) * (W * (W - 1) / 2), 1u << 21));
    core::Params params;
    params.pair_capacity = spec_.M;
    params.cost_terms = spec_.selector == Selector::kKeepless ? spec_.cost_terms : std::uint8_t{7};
    window_ = std::make_unique<core::Window>(caps);
    sparsifier_ = std::make_unique<core::Sparsifier>(caps, params);
    obs_buffer_.reserve(max_kp);
  }

  void insert_keyframe(int k) {
    const auto ku = static_cast<std::size_t>(k);
    kf_alive_[ku] = true;
    if (k < 2 && s_.fix_first_two) poses_[ku] = to_block(s_.frames[ku].gt);
    else if (k == 0) poses_[ku] = to_block(s_.frames[0].gt);
    else poses_[ku] = to_block(est(k - 1) * s_.odometry[ku]);
    const Pose T_wc = est(k);
    const auto& kps = s_.frames[ku].keypoints;
    kf_kp_mp_[ku].assign(kps.size(), -1);
    for (int i = 0; i < static_cast<int>(kps.size()); ++i) {
      const KeyPoint& p = kps[static_cast<std::size_t>(i)];
      const std::uint64_t l = p.landmark;
      switch (lm_state_[l]) {
        case kMapped: add_obs(lm_mp_[l], k, i); break;
        case kNew:
        case kPending: {
          const double disparity = p.u - p.ur;
          if (p.ur >= 0 && s_.cam.baseline > 0 && disparity > 0.5) {
            const double z = s_.cam.fx * s_.cam.baseline / disparity;
            const Eigen::Vector3d pc((p.u - s_.cam.cx) / s_.cam.fx * z, (p.v - s_.cam.cy) / s_.cam.fy * z, z);
            create_mp(l, k, i, T_wc * pc);
          } else {
            try_triangulate(l, k, i);
          }
          break;
        }
        default: break;  // culled: the feature is not used again
      }
    }
  }

  void try_triangulate(std::uint64_t l, int k, int i) {
    auto& pend = pending_[l];
    // Drop observations from keyframes culled meanwhile.
    pend.erase(std::remove_if(pend.begin(), pend.end(),
                              [&](const std::pair<int, int>& o) { return !kf_alive_[static_cast<std::size_t>(o.first)]; }),
               pend.end());
    lm_state_[l] = kPending;
    if (!pend.empty()) {
      const auto [k0, i0] = pend.front();
      const Pose P0 = est(k0), P1 = est(k);
      const KeyPoint& a = kp(k0, i0);
      const KeyPoint& b = kp(k, i);
      const Eigen::Vector3d d0 = (P0.q * Eigen::Vector3d((a.u - s_.cam.cx) / s_.cam.fx, (a.v - s_.cam.cy) / s_.cam.fy, 1)).normalized();
      const Eigen::Vector3d d1 = (P1.q * Eigen::Vector3d((b.u - s_.cam.cx) / s_.cam.fx, (b.v - s_.cam.cy) / s_.cam.fy, 1)).normalized();
      const double cos_par = d0.dot(d1);
      if (cos_par < std::cos(1.0 * 3.141592653589793 / 180.0)) {  // >= 1 degree parallax
        // Midpoint of the closest approach of the two rays.
        const Eigen::Vector3d w = P0.t - P1.t;
        const double bb = d0.dot(d1), d = d0.dot(w), e = d1.dot(w);
        const double den = 1.0 - bb * bb;
        const double s0 = (bb * e - d) / den, s1 = (e - bb * d) / den;
        if (s0 > 0 && s1 > 0) {
          const Eigen::Vector3d X = 0.5 * ((P0.t + s0 * d0) + (P1.t + s1 * d1));
          create_mp(l, k, i, X);  // takes the pending observations (pend is gone)
          return;
        }
      }
    }
    pend.emplace_back(k, i);
  }

  int create_mp(std::uint64_t l, int k, int i, const Eigen::Vector3d& X) {
    MapPoint mp;
    mp.X = {X.x(), X.y(), X.z()};
    mp.landmark = l;
    mp.first_kf = k;
    const int m = static_cast<int>(mps_.size());
    mps_.push_back(std::move(mp));
    lm_state_[l] = kMapped;
    lm_mp_[l] = m;
    add_obs(m, k, i);
    recent_.push_back(m);
    auto it = pending_.find(l);
    if (it != pending_.end()) {
      for (const auto& o : it->second)
        if (kf_alive_[static_cast<std::size_t>(o.first)] && o.first != k) add_obs(m, o.first, o.second);
      pending_.erase(it);
    }
    return m;
  }

  void add_obs(int m, int k, int i) {
    mps_[static_cast<std::size_t>(m)].obs.emplace_back(k, i);
    kf_kp_mp_[static_cast<std::size_t>(k)][static_cast<std::size_t>(i)] = m;
  }

  void remove_obs(int m, int k, int i) {
    auto& obs = mps_[static_cast<std::size_t>(m)].obs;
    obs.erase(std::remove(obs.begin(), obs.end(), std::make_pair(k, i)), obs.end());
    kf_kp_mp_[static_cast<std::size_t>(k)][static_cast<std::size_t>(i)] = -1;
  }

  void kill(int m, LmState why) {
    MapPoint& mp = mps_[static_cast<std::size_t>(m)];
    if (!mp.alive) return;
    mp.alive = false;
    for (const auto& o : mp.obs)
      kf_kp_mp_[static_cast<std::size_t>(o.first)][static_cast<std::size_t>(o.second)] = -1;
    mp.obs.clear();
    // A point the selector culls is gone for good (its feature is judged
    // redundant); one the SLAM's own culling drops may be mapped again later,
    // as ORB-SLAM2 re-triangulates unmatched keypoints.
    lm_state_[mp.landmark] = why == kSlamCulled ? kNew : why;
  }

  // ORB-SLAM2 MapPointCulling: two keyframes after creation, a point seen by
  // fewer than three keyframes is removed.
  void cull_recent_points(int k) {
    std::size_t w = 0;
    for (std::size_t r = 0; r < recent_.size(); ++r) {
      const int m = recent_[r];
      MapPoint& mp = mps_[static_cast<std::size_t>(m)];
      if (!mp.alive) continue;
      const int age = k - mp.first_kf;
      if (age >= 2 && mp.obs.size() < 3) {
        kill(m, kSlamCulled);
        continue;
      }
      if (age < 3) recent_[w++] = m;
    }
    recent_.resize(w);
  }

  std::vector<int> window_keyframes() const {
    std::vector<int> w;
    for (int k = static_cast<int>(kf_alive_.size()) - 1; k >= 0 && static_cast<int>(w.size()) < o_.window; --k)
      if (kf_alive_[static_cast<std::size_t>(k)] && !kf_kp_mp_[static_cast<std::size_t>(k)].empty()) w.push_back(k);
    std::reverse(w.begin(), w.end());  // oldest first
    return w;
  }

  void select_points(const std::vector<int>& window, RunResult* r) {
    if (spec_.selector == Selector::kNone || window.size() < 2) return;
    window_->clear();
    for (int f : window) {
      obs_buffer_.clear();
      const auto& ids = kf_kp_mp_[static_cast<std::size_t>(f)];
      for (std::size_t i = 0; i < ids.size(); ++i)
        if (ids[i] >= 0) {
          const KeyPoint& p = kp(f, static_cast<int>(i));
          obs_buffer_.push_back(core::Observation{static_cast<core::PointId>(ids[i]), p.u, p.v});
        }
      const Pose P = est(f);
      core::Keyframe kf;
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
    const core::PointDecision* d = sparsifier_->decisions();
    const std::uint32_t nd = sparsifier_->decision_count();
    if (spec_.selector == Selector::kKeepless) {
      for (std::uint32_t i = 0; i < nd; ++i)
        if (d[i].verdict == core::Verdict::kCull) {
          kill(static_cast<int>(d[i].point), kSelectorCulled);
          ++r->selector_culled;
        }
      return;
    }
    // Baselines at equal count: keep as many evaluated points as keepless
    // keeps on this same window.
    const std::uint32_t keep = sparsifier_->summary().kept;
    std::vector<int> evaluated;
    for (std::uint32_t i = 0; i < nd; ++i)
      if (d[i].verdict != core::Verdict::kSkip) evaluated.push_back(static_cast<int>(d[i].point));
    std::vector<char> kept(evaluated.size(), 0);
    if (spec_.selector == Selector::kRandom) {
      // A fixed random priority per landmark, so a point's fate is stable
      // across windows (a fresh draw each window would cull far more).
      std::vector<std::uint32_t> order(evaluated.size());
      for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
      auto prio = [&](std::uint32_t i) {
        return mix(o_.seed, mps_[static_cast<std::size_t>(evaluated[i])].landmark);
      };
      std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return prio(a) < prio(b); });
      for (std::uint32_t i = 0; i < keep && i < order.size(); ++i) kept[order[i]] = 1;
    } else {
      // ANMS: each point is judged in the newest window keyframe that sees
      // it, by SSC on keypoint responses; keyframes share the count in
      // proportion to their points (largest remainder).
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
      std::vector<std::uint32_t> quota(window.size(), 0);
      std::vector<std::pair<double, std::size_t>> rem;
      std::uint32_t given = 0;
      for (std::size_t sl = 0; sl < window.size(); ++sl) {
        const double exact = evaluated.empty() ? 0.0 : double(keep) * double(per[sl].size()) / double(evaluated.size());
        quota[sl] = static_cast<std::uint32_t>(std::floor(exact));
        given += quota[sl];
        rem.emplace_back(-(exact - std::floor(exact)), sl);
      }
      std::sort(rem.begin(), rem.end());
      for (std::size_t j = 0; given < keep && j < rem.size(); ++j, ++given) ++quota[rem[j].second];
      for (std::size_t sl = 0; sl < window.size(); ++sl) {
        std::vector<SscPoint> pts;
        for (std::uint32_t i : per[sl]) {
          const KeyPoint& p = kp(home[i], home_kp[i]);
          pts.push_back(SscPoint{p.u, p.v, p.response, static_cast<std::uint64_t>(evaluated[i])});
        }
        for (std::uint32_t j : ssc_select(pts, quota[sl], s_.cam.width, s_.cam.height)) kept[per[sl][j]] = 1;
      }
    }
    for (std::size_t i = 0; i < evaluated.size(); ++i)
      if (!kept[i]) {
        kill(evaluated[i], kSelectorCulled);
        ++r->selector_culled;
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
    std::vector<std::pair<int, std::pair<int, int>>> refs;  // (mp, (kf, kp)) per observation
    for (std::size_t j = 0; j < local.size(); ++j) {
      MapPoint& mp = mps_[static_cast<std::size_t>(local[j])];
      in.points.push_back(mp.X.data());
      for (const auto& o : mp.obs) {
        const int pi = add_pose(o.first, true);
        const KeyPoint& p = kp(o.first, o.second);
        in.observations.push_back(BaObservation{pi, static_cast<int>(j), p.u, p.v, p.ur});
        refs.emplace_back(local[j], o);
      }
    }
    const BaResult res = solve_local_ba(s_.cam, in, o_.ba_iterations);
    r->ba_s += res.seconds;
    ++r->ba_calls;
    for (std::size_t i = 0; i < refs.size(); ++i)
      if (res.outlier[i]) remove_obs(refs[i].first, refs[i].second.first, refs[i].second.second);
  }

  // ORB-SLAM2 KeyFrameCulling on the local keyframes (not the newest, not
  // the gauge keyframes).
  void cull_keyframes(const std::vector<int>& window, int newest) {
    for (int f : window) {
      if (f == newest || f < 2) continue;
      int n = 0, redundant = 0;
      for (int m : kf_kp_mp_[static_cast<std::size_t>(f)]) {
        if (m < 0) continue;
        ++n;
        if (mps_[static_cast<std::size_t>(m)].obs.size() >= 4) ++redundant;  // >= 3 others
      }
      if (n > 0 && redundant > 0.9 * n) {
        auto& ids = kf_kp_mp_[static_cast<std::size_t>(f)];
        for (std::size_t i = 0; i < ids.size(); ++i)
          if (ids[i] >= 0) remove_obs(ids[i], f, static_cast<int>(i));
        ids.clear();
        kf_alive_[static_cast<std::size_t>(f)] = false;
      }
    }
  }

  void take_snapshot(RunResult* r) const {
    const int k = o_.snapshot_frame;
    r->snapshot.clear();
    for (const KeyPoint& p : s_.frames[static_cast<std::size_t>(k)].keypoints) {
      const std::uint8_t st = lm_state_[p.landmark];
      int state = 0;
      if (st == kMapped && mps_[static_cast<std::size_t>(lm_mp_[p.landmark])].alive) state = 1;
      else if (st == kSelectorCulled) state = 2;
      r->snapshot.push_back(SnapshotPoint{p.u, p.v, state});
    }
  }

  void finish(RunResult* r) {
    const std::size_t n = s_.frames.size();
    r->kfs_total = static_cast<std::uint32_t>(n);
    r->mps_created = mps_.size();
    std::vector<Pose> gt(n);
    r->estimate.resize(n);
    for (std::size_t k = 0; k < n; ++k) {
      r->estimate[k] = est(static_cast<int>(k));
      gt[k] = s_.frames[k].gt;
      if (kf_alive_[k]) ++r->kfs;
    }
    const Ate ate = absolute_trajectory_error(r->estimate, gt, false);
    if (std::getenv("KEEPLESS_EVAL_DEBUG"))
      for (std::size_t k = 0; k < n; ++k)
        std::fprintf(stderr, "  kf %zu: pos err %.4f rot err %.3f deg\n", k, (r->estimate[k].t - gt[k].t).norm(),
                     rotation_angle(gt[k].q.conjugate() * r->estimate[k].q) * 57.29578);
    r->ate_m = ate.rms_m;
    r->ate_r_deg = ate.rms_r_deg;
    double c = 0, fsum = 0;
    for (const MapPoint& mp : mps_) {
      if (!mp.alive) continue;
      ++r->mps;
      c += double(mp.obs.size());
      int lo = 1 << 30, hi = -1;
      for (const auto& o : mp.obs) {
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
  std::vector<std::uint8_t> lm_state_;
  std::vector<int> lm_mp_;
  std::unordered_map<std::uint64_t, std::vector<std::pair<int, int>>> pending_;
  std::vector<MapPoint> mps_;
  std::vector<int> recent_;
  std::vector<bool> kf_alive_;
  std::vector<std::vector<int>> kf_kp_mp_;
  std::vector<std::array<double, 6>> poses_;
  std::vector<std::uint32_t> mp_stamp_;
  std::uint32_t stamp_ = 0;
  std::unique_ptr<core::Window> window_;
  std::unique_ptr<core::Sparsifier> sparsifier_;
  std::vector<core::Observation> obs_buffer_;
};

}  // namespace

const char* to_string(Selector s) {
  switch (s) {
    case Selector::kNone: return "none";
    case Selector::kKeepless: return "keepless";
    case Selector::kAnms: return "anms";
    case Selector::kRandom: return "random";
  }
  return "?";
}

RunResult run_slam(const Scenario& scenario, const VariantSpec& spec, const SimOptions& options) {
  Engine e(scenario, spec, options);
  return e.run();
}

}  // namespace keepless::eval
