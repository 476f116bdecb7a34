#pragma once
// An independent, allocation-happy re-statement of what keepless_node does
// with a keyframe stream, on the core library directly: keep the last K
// keyframes (messages in order), rebuild a fresh Window each time, run the
// Sparsifier, and forget culled points. Tests compare the node's decisions
// with this one's.

#include <algorithm>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <set>
#include <vector>

#include "keepless/core/sparsifier.hpp"
#include "keepless/core/window.hpp"
#include "keepless/decision_t.hpp"
#include "keepless/keyframe_t.hpp"
#include "keepless/map_event_t.hpp"

namespace keepless::testing {

struct ReferenceDecision {
  std::int8_t status = 0;
  std::vector<std::int64_t> window_ids;
  std::vector<std::int64_t> culled;
  std::int32_t points = 0, evaluated = 0, kept = 0, culled_count = 0, skipped = 0, pairs = 0;
  std::int64_t max_flow = 0, total_cost = 0;
};

class ReferenceNode {
 public:
  ReferenceNode(const core::Capacities& caps, const core::Params& params, std::uint32_t k)
      : caps_(caps), params_(params), k_(k) {}

  ReferenceDecision step(const keepless::keyframe_t& m) {
    Frame f;
    f.kf.id = static_cast<core::KeyframeId>(m.keyframe_id);
    std::copy(m.centre, m.centre + 3, f.kf.centre);
    std::copy(m.orientation, m.orientation + 4, f.kf.orientation);
    for (int i = 0; i < m.num_observations; ++i) {
      // The node's memory of culls: a culled point never comes back.
      if (ever_culled_.count(static_cast<core::PointId>(m.point_id[i])) > 0) continue;
      core::Observation o;
      o.point = static_cast<core::PointId>(m.point_id[i]);
      o.u = m.u[i];
      o.v = m.v[i];
      if (m.num_depths != 0) o.depth = m.depth[static_cast<std::size_t>(i)];
      if (m.num_tracked != 0) f.tracked[o.point] = static_cast<std::uint8_t>(m.tracked[static_cast<std::size_t>(i)]);
      if (m.num_quality != 0) {
        const auto q = static_cast<std::size_t>(i);
        f.quality[o.point] = {static_cast<std::uint32_t>(m.track_length[q]), m.age[q], m.reprojection_error[q],
                              m.triangulation_angle[q]};
      }
      f.obs.push_back(o);
    }
    if (m.num_intrinsics == 4) {
      f.kf.fx = m.intrinsics[0];
      f.kf.fy = m.intrinsics[1];
      f.kf.cx = m.intrinsics[2];
      f.kf.cy = m.intrinsics[3];
    }
    for (int i = 0; i < m.num_unmapped; ++i) {
      f.unmapped.push_back({m.unmapped_u[static_cast<std::size_t>(i)], m.unmapped_v[static_cast<std::size_t>(i)]});
    }
    f.has_tracked = m.num_tracked != 0;
    f.has_quality = m.num_quality != 0;
    if (frames_.size() == k_) frames_.pop_front();
    frames_.push_back(f);

    core::Window w(caps_);
    for (const Frame& fr : frames_) {
      core::Keyframe kf = fr.kf;
      kf.unmapped = fr.unmapped.data();
      kf.unmapped_count = static_cast<std::uint32_t>(fr.unmapped.size());
      std::vector<std::uint8_t> flags;  // the window copies them
      for (const core::Observation& o : fr.obs) flags.push_back(fr.tracked.count(o.point) ? fr.tracked.at(o.point) : 0);
      kf.tracked = fr.has_tracked && !flags.empty() ? flags.data() : nullptr;
      std::vector<core::PointQuality> quality;
      for (const core::Observation& o : fr.obs) quality.push_back(fr.quality.count(o.point) ? fr.quality.at(o.point) : core::PointQuality{});
      kf.quality = fr.has_quality && !quality.empty() ? quality.data() : nullptr;
      if (w.add_keyframe(kf, fr.obs.data(), static_cast<std::uint32_t>(fr.obs.size())) != core::Status::kOk) {
        ADD_FAILURE() << "reference window rejected keyframe " << fr.kf.id;
      }
    }
    // One sparsifier for the run, as the node's: a fraction budget remembers
    // what earlier decisions kept.
    if (!sparsifier_) sparsifier_ = std::make_unique<core::Sparsifier>(caps_, params_);
    core::Sparsifier& s = *sparsifier_;
    ReferenceDecision d;
    const core::Status st = s.run(w);
    d.status = st == core::Status::kOk ? keepless::decision_t::STATUS_OPTIMAL
                                       : keepless::decision_t::STATUS_BUDGET_EXHAUSTED;
    for (const Frame& fr : frames_) d.window_ids.push_back(static_cast<std::int64_t>(fr.kf.id));
    const core::Summary& sum = s.summary();
    d.points = static_cast<std::int32_t>(sum.points);
    d.evaluated = static_cast<std::int32_t>(sum.evaluated);
    d.kept = static_cast<std::int32_t>(sum.kept);
    d.culled_count = static_cast<std::int32_t>(sum.culled);
    d.skipped = static_cast<std::int32_t>(sum.skipped);
    d.pairs = static_cast<std::int32_t>(sum.pairs);
    d.max_flow = sum.max_flow;
    d.total_cost = sum.total_cost;
    std::set<core::PointId> culled;
    for (std::uint32_t i = 0; i < s.decision_count(); ++i) {
      if (s.decisions()[i].verdict == core::Verdict::kCull) {
        d.culled.push_back(static_cast<std::int64_t>(s.decisions()[i].point));
        culled.insert(s.decisions()[i].point);
        ever_culled_.insert(s.decisions()[i].point);
      }
    }
    for (Frame& fr : frames_) {
      fr.obs.erase(std::remove_if(fr.obs.begin(), fr.obs.end(),
                                  [&](const core::Observation& o) { return culled.count(o.point) > 0; }),
                   fr.obs.end());
    }
    return d;
  }

  // A map event: reset, or deletions, merges (first observation of a point in
  // a keyframe wins) and keyframe removals.
  void apply(const keepless::map_event_t& e) {
    if (e.reset) {
      frames_.clear();
      ever_culled_.clear();
      return;
    }
    const std::set<std::int64_t> deleted(e.deleted_point_id.begin(), e.deleted_point_id.end());
    std::map<std::int64_t, std::int64_t> merged;
    for (std::size_t i = 0; i < e.merged_from_id.size(); ++i) merged[e.merged_from_id[i]] = e.merged_into_id[i];
    const std::set<std::int64_t> removed(e.removed_keyframe_id.begin(), e.removed_keyframe_id.end());
    std::deque<Frame> next;
    for (Frame& fr : frames_) {
      if (removed.count(static_cast<std::int64_t>(fr.kf.id)) > 0) continue;
      Frame out{fr.kf, {}, fr.unmapped, {}, fr.has_tracked, {}, fr.has_quality};
      std::set<core::PointId> seen;
      for (core::Observation o : fr.obs) {
        const auto id = static_cast<std::int64_t>(o.point);
        if (deleted.count(id) > 0) continue;
        const auto m = merged.find(id);
        const std::uint8_t flag = fr.tracked.count(o.point) ? fr.tracked.at(o.point) : 0;
        if (m != merged.end()) o.point = static_cast<core::PointId>(m->second);
        if (!seen.insert(o.point).second) continue;
        out.tracked[o.point] = flag;
        if (fr.quality.count(static_cast<core::PointId>(id))) out.quality[o.point] = fr.quality.at(static_cast<core::PointId>(id));
        out.obs.push_back(o);
      }
      next.push_back(out);
    }
    frames_ = next;
  }

 private:
  struct Frame {
    core::Keyframe kf;
    std::vector<core::Observation> obs;
    std::vector<core::Keypoint> unmapped;
    std::map<core::PointId, std::uint8_t> tracked;  // keyframe_t's tracked flags by point
    bool has_tracked = false;
    std::map<core::PointId, core::PointQuality> quality;  // keyframe_t's point quality by point
    bool has_quality = false;
  };
  core::Capacities caps_;
  core::Params params_;
  std::uint32_t k_;
  std::deque<Frame> frames_;
  std::set<core::PointId> ever_culled_;
  std::unique_ptr<core::Sparsifier> sparsifier_;
};

// Field-by-field comparison with a node decision.
inline void expect_same(const ReferenceDecision& r, const keepless::decision_t& d, const char* where) {
  EXPECT_EQ(d.status, r.status) << where;
  EXPECT_EQ(d.window_keyframe_id, r.window_ids) << where;
  EXPECT_EQ(d.culled_point_id, r.culled) << where;
  EXPECT_EQ(d.num_culled, static_cast<std::int32_t>(r.culled.size())) << where;
  EXPECT_EQ(d.points, r.points) << where;
  EXPECT_EQ(d.evaluated, r.evaluated) << where;
  EXPECT_EQ(d.kept, r.kept) << where;
  EXPECT_EQ(d.culled, r.culled_count) << where;
  EXPECT_EQ(d.skipped, r.skipped) << where;
  EXPECT_EQ(d.pairs, r.pairs) << where;
  EXPECT_EQ(d.max_flow, r.max_flow) << where;
  EXPECT_EQ(d.total_cost, r.total_cost) << where;
}

}  // namespace keepless::testing
