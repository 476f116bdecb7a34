#include "vo_internals.hpp"

#include <algorithm>
#include <cstdint>
#include <memory>

#include "point_quality.hpp"
#include "point_selection.hpp"
#include "vo_ba.hpp"
#include "vo_geometry.hpp"

namespace keepless::eval::vo::detail {

namespace {

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

}  // namespace

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
                            static_cast<int>(map_.points[static_cast<std::size_t>(p)].obs.size()), k});
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
    culls = baseline_culls(opt_.selector, candidates, cull, opt_.seed, cam_.width, cam_.height, opt_.anms_variant);
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
  // An excluded point the map lost otherwise (a BA outlier, point or
  // keyframe culling, a merge) is forgotten, as the node forgets a point the
  // VO deletes or merges itself.
  for (std::size_t p = 0; p < map_.points.size(); ++p) {
    MapPoint& m = map_.points[p];
    if (!m.excluded || !m.bad) continue;
    m.excluded = false;
    (void)deferred_.forget(static_cast<core::PointId>(p));
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
    result_.points_deleted_deferred += m.bad ? 0 : 1;
    delete_cull(static_cast<int>(id));
  }
  // Nor after: no excluded point the map still holds has gone T unmatched keyframes.
  for (const MapPoint& m : map_.points) {
    if (m.excluded && !m.bad && now - m.matched_tick >= opt_.params.defer_keyframes) ++result_.defer_rule_violations;
  }
}

void Vo::delete_cull(int p) {
  if (opt_.keyframe_culling == KeyframeCulling::kCountCulled) {
    map_.cull_remembered(p);
  } else {
    map_.set_bad(p);
  }
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
    if (refine_pose(cam_, X, obs, &T, &outlier) >= 15) f.Tcw = T;
  }
}

}  // namespace keepless::eval::vo::detail
