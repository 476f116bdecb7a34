// Deferred culling in the node (--defer T) on memq://: a culled point is
// excluded (decision_t.excluded_point_id), stays out of the window while the
// VO tracks it, and is deleted (deleted_point_id) exactly when T keyframes
// in a row have not matched it; bad input (reappearing points, map events,
// resets, a full memory) keeps that consistent; with the mode off nothing
// changes.

#include <algorithm>
#include <cstdint>
#include <vector>

#include "keepless/core/deferred_culls.hpp"
#include "keepless/platform/recent_ids.hpp"
#include "node_memq_fixture.hpp"

namespace keepless::testing {
namespace {

bool has(const std::vector<std::int64_t>& ids, std::int64_t id) {
  return std::find(ids.begin(), ids.end(), id) != ids.end();
}

bool in_window(const keepless::core::Window& w, std::uint64_t point) {
  for (std::uint32_t k = 0; k < w.keyframe_count(); ++k) {
    for (std::uint32_t j = 0; j < w.observation_count(k); ++j) {
      if (w.observations(k)[j].point == point) return true;
    }
  }
  return false;
}

class DeferredNode : public NodeOnMemq {
 protected:
  void make_deferred(std::uint32_t t, std::uint32_t memory = 0) {
    NodeConfig c = default_config();
    c.params.defer_keyframes = t;
    c.defer_memory = memory;
    make_node(c);
  }
  // Keyframes over points 0..39 until a decision excludes something; the
  // first excluded point of it.
  std::int64_t exclude_one() {
    for (int i = 0; i < 8; ++i) {
      send(kt::make_keyframe(++seq_, ++kf_, kt::id_range(0, 40)));
      if (!decisions_.back().excluded_point_id.empty()) return decisions_.back().excluded_point_id.front();
    }
    ADD_FAILURE() << "nothing excluded";
    return -1;
  }
  // A keyframe of fresh points (100 + ...), plus `extra`.
  void send_fresh(const std::vector<std::int64_t>& extra = {}, const std::vector<std::int8_t>& flags = {}) {
    std::vector<std::int64_t> ids = kt::id_range(1000 + 40 * kf_, 40);
    ids.insert(ids.end(), extra.begin(), extra.end());
    keepless::keyframe_t m = kt::make_keyframe(++seq_, ++kf_, ids);
    if (!flags.empty()) {
      m.num_tracked = m.num_observations;
      m.tracked.assign(static_cast<std::size_t>(m.num_observations), 0);
      std::copy(flags.begin(), flags.end(), m.tracked.end() - static_cast<std::ptrdiff_t>(flags.size()));
    }
    send(m);
  }
  std::int64_t seq_ = 0;
  std::int64_t kf_ = 0;
};

TEST_F(DeferredNode, ModeOffListsCullsAsBeforeAndNothingElse) {
  for (int i = 0; i < 8; ++i) send(kt::make_keyframe(i + 1, i, kt::id_range(i * 5, 40)));
  std::size_t culled = 0;
  for (const auto& d : decisions_) {
    EXPECT_EQ(d.num_excluded, 0);
    EXPECT_EQ(d.num_deleted, 0);
    culled += d.culled_point_id.size();
  }
  EXPECT_GT(culled, 0u);
  EXPECT_EQ(node_->counters().points_excluded, 0u);
  EXPECT_EQ(node_->deferred_culls().size(), 0u);
}

TEST_F(DeferredNode, ModeOnDecidesTheSamePointsAsModeOff) {
  // Culled and excluded points both leave the window for good, so over a
  // stream (without map events) each decision excludes exactly what the node
  // without deferral culls.
  const auto stream = [&] {
    for (int i = 0; i < 10; ++i) send(kt::make_keyframe(i + 1, i, kt::id_range(i * 6, 40)));
  };
  stream();
  std::vector<std::vector<std::int64_t>> culled;
  for (const auto& d : decisions_) culled.push_back(d.culled_point_id);
  make_deferred(3);
  stream();
  ASSERT_EQ(decisions_.size(), culled.size());
  std::size_t total = 0;
  for (std::size_t i = 0; i < culled.size(); ++i) {
    EXPECT_EQ(decisions_[i].excluded_point_id, culled[i]) << "keyframe " << i;
    EXPECT_TRUE(decisions_[i].culled_point_id.empty());
    EXPECT_EQ(decisions_[i].culled, static_cast<std::int32_t>(culled[i].size()));
    total += culled[i].size();
  }
  EXPECT_GT(total, 0u);
}

TEST_F(DeferredNode, AnExcludedPointIsTrackedAndDeletedExactlyWhenTheRuleSays) {
  make_deferred(2);
  const std::int64_t p = exclude_one();
  ASSERT_GE(p, 0);
  const auto up = static_cast<std::uint64_t>(p);
  EXPECT_FALSE(in_window(node_->window(), up)) << "excluded: out of the window (out of BA)";
  EXPECT_TRUE(node_->deferred_culls().contains(up));
  // Matched in each of the next 4 keyframes: still excluded, never deleted,
  // never back in the window.
  for (int i = 0; i < 4; ++i) {
    send_fresh({p});
    EXPECT_FALSE(has(decisions_.back().deleted_point_id, p));
    EXPECT_FALSE(has(decisions_.back().excluded_point_id, p));
    EXPECT_FALSE(in_window(node_->window(), up));
    EXPECT_TRUE(node_->deferred_culls().contains(up));
  }
  EXPECT_GE(node_->counters().deferred_observations, 4u);
  // Observed with tracked flag 0: not a match (1 in a row).
  send_fresh({p}, {0});
  EXPECT_FALSE(has(decisions_.back().deleted_point_id, p));
  // Not observed: 2 in a row: deleted by this decision.
  send_fresh();
  EXPECT_TRUE(has(decisions_.back().deleted_point_id, p));
  EXPECT_FALSE(node_->deferred_culls().contains(up));
  EXPECT_TRUE(node_->cull_memory().contains(up));
  // It reappears: dropped as a stale observation, never excluded or deleted again.
  const std::uint64_t stale = node_->counters().stale_observations;
  send_fresh({p});
  EXPECT_EQ(node_->counters().stale_observations, stale + 1);
  EXPECT_FALSE(in_window(node_->window(), up));
  EXPECT_FALSE(has(decisions_.back().deleted_point_id, p));
  // The status reports it.
  node_->publish_status(false);
  pump();
  ASSERT_FALSE(statuses_.empty());
  EXPECT_EQ(statuses_.back().points_excluded, static_cast<std::int64_t>(node_->counters().points_excluded));
  EXPECT_EQ(statuses_.back().points_deleted, static_cast<std::int64_t>(node_->counters().points_deleted));
  EXPECT_EQ(statuses_.back().deferred_points, static_cast<std::int32_t>(node_->deferred_culls().size()));
  EXPECT_GT(statuses_.back().capacity_deferred, 0);
}

TEST_F(DeferredNode, EveryExcludedPointIsDeletedOnceAndIdsAreAscending) {
  make_deferred(1);
  std::vector<std::int64_t> excluded, deleted;
  for (int i = 0; i < 12; ++i) {
    send(kt::make_keyframe(i + 1, i, kt::id_range(i * 6, 40)));
    const auto& d = decisions_.back();
    EXPECT_TRUE(std::is_sorted(d.excluded_point_id.begin(), d.excluded_point_id.end()));
    EXPECT_TRUE(std::is_sorted(d.deleted_point_id.begin(), d.deleted_point_id.end()));
    excluded.insert(excluded.end(), d.excluded_point_id.begin(), d.excluded_point_id.end());
    deleted.insert(deleted.end(), d.deleted_point_id.begin(), d.deleted_point_id.end());
  }
  ASSERT_FALSE(deleted.empty());
  std::sort(excluded.begin(), excluded.end());
  std::sort(deleted.begin(), deleted.end());
  EXPECT_EQ(std::adjacent_find(excluded.begin(), excluded.end()), excluded.end()) << "excluded twice";
  EXPECT_EQ(std::adjacent_find(deleted.begin(), deleted.end()), deleted.end()) << "deleted twice";
  EXPECT_TRUE(std::includes(excluded.begin(), excluded.end(), deleted.begin(), deleted.end()));
  EXPECT_EQ(excluded.size(), deleted.size() + node_->deferred_culls().size());
}

TEST_F(DeferredNode, MapEventsAndResetsForgetExcludedPoints) {
  make_deferred(5);
  const std::int64_t p = exclude_one();
  ASSERT_GE(p, 0);
  const std::vector<std::int64_t> excluded = decisions_.back().excluded_point_id;
  ASSERT_GE(excluded.size(), 2u);
  const std::int64_t q = excluded[1];
  // The VO deletes p itself: forgotten, never listed as deleted.
  keepless::map_event_t e = kt::make_event(++seq_);
  e.deleted_point_id = {p};
  // And merges a live window point into the excluded q: the source leaves the window.
  const std::int64_t live = static_cast<std::int64_t>(node_->window().observations(0)[0].point);
  ASSERT_FALSE(node_->deferred_culls().contains(static_cast<std::uint64_t>(live)));
  e.merged_from_id = {live};
  e.merged_into_id = {q};
  send(e);
  ASSERT_FALSE(acks_.empty());
  EXPECT_EQ(acks_.back().status, keepless::map_event_ack_t::STATUS_APPLIED);
  EXPECT_EQ(acks_.back().merged_applied, 1);
  EXPECT_FALSE(node_->deferred_culls().contains(static_cast<std::uint64_t>(p)));
  EXPECT_TRUE(node_->deferred_culls().contains(static_cast<std::uint64_t>(q)));
  EXPECT_FALSE(in_window(node_->window(), static_cast<std::uint64_t>(live)));
  for (int i = 0; i < 6; ++i) {
    send_fresh();
    EXPECT_FALSE(has(decisions_.back().deleted_point_id, p));
  }
  // A reset forgets the rest.
  keepless::map_event_t r = kt::make_event(++seq_);
  r.reset = true;
  send(r);
  EXPECT_EQ(node_->deferred_culls().size(), 0u);
}

// A merge into an excluded point whose source is not in the window changes
// nothing and is not counted in merged_applied (it was counted).
TEST_F(DeferredNode, AMergeIntoAnExcludedPointCountsOnlyIfItsSourceWasInTheWindow) {
  make_deferred(5);
  const std::int64_t q = exclude_one();
  ASSERT_GE(q, 0);
  const std::int64_t absent = 987654;
  ASSERT_EQ(node_->window().point_views(static_cast<std::uint64_t>(absent)), 0u);
  const std::int64_t live = static_cast<std::int64_t>(node_->window().observations(0)[0].point);
  ASSERT_FALSE(node_->deferred_culls().contains(static_cast<std::uint64_t>(live)));
  const kt::WindowSnapshot before = kt::snapshot(node_->window());
  keepless::map_event_t e = kt::make_event(++seq_);
  e.merged_from_id = {absent};
  e.merged_into_id = {q};
  send(e);
  ASSERT_FALSE(acks_.empty());
  EXPECT_EQ(acks_.back().status, keepless::map_event_ack_t::STATUS_APPLIED);
  EXPECT_EQ(acks_.back().merged_applied, 0);
  EXPECT_TRUE(kt::snapshot(node_->window()) == before);
  keepless::map_event_t both = kt::make_event(++seq_);
  both.merged_from_id = {absent + 1, live};
  both.merged_into_id = {q, q};
  send(both);
  EXPECT_EQ(acks_.back().merged_applied, 1);
  EXPECT_FALSE(in_window(node_->window(), static_cast<std::uint64_t>(live)));
}

TEST_F(DeferredNode, AFullMemoryDeletesAtOnceAndCountsIt) {
  make_deferred(4, /*memory=*/1);
  const std::int64_t p = exclude_one();
  ASSERT_GE(p, 0);
  const auto& d = decisions_.back();
  ASSERT_GE(d.culled, 2);
  EXPECT_EQ(d.num_excluded, 1);
  EXPECT_EQ(d.num_deleted, d.culled - 1) << "what did not fit is deleted at once";
  EXPECT_EQ(node_->deferred_culls().refused(), static_cast<std::uint64_t>(d.culled - 1));
  for (const std::int64_t id : d.deleted_point_id) {
    EXPECT_FALSE(in_window(node_->window(), static_cast<std::uint64_t>(id)));
    EXPECT_TRUE(node_->cull_memory().contains(static_cast<std::uint64_t>(id)));
  }
  node_->publish_status(false);
  pump();
  ASSERT_FALSE(statuses_.empty());
  EXPECT_EQ(statuses_.back().deferred_refused, d.culled - 1);
  EXPECT_EQ(statuses_.back().capacity_deferred, 1);
}

// Review: a merge into an excluded point lost its source's matches, so the
// point was deleted while a keyframe within the newest T had matched it (the
// source) - ORB-SLAM's fusing of a new keyframe's duplicate into an older
// point. T = 3: p excluded at c, a one-view point matched at c + 2 merged
// into p, c + 3 misses it: one keyframe in a row.
TEST_F(DeferredNode, AMergeIntoAnExcludedPointKeepsTheSourcesMatches) {
  make_deferred(3);
  const std::int64_t p = exclude_one();  // tick c
  ASSERT_GE(p, 0);
  const std::int64_t live = 777777;
  send_fresh();        // c + 1: p not matched
  send_fresh({live});  // c + 2: live matched (one view: stays in the window)
  ASSERT_FALSE(has(decisions_.back().deleted_point_id, p));
  ASSERT_TRUE(in_window(node_->window(), static_cast<std::uint64_t>(live)));
  keepless::map_event_t e = kt::make_event(++seq_);
  e.merged_from_id = {live};
  e.merged_into_id = {p};
  send(e);
  ASSERT_EQ(acks_.back().status, keepless::map_event_ack_t::STATUS_APPLIED);
  ASSERT_EQ(acks_.back().merged_applied, 1);
  EXPECT_FALSE(in_window(node_->window(), static_cast<std::uint64_t>(live))) << "now a point out of BA";
  for (int k = 3; k <= 4; ++k) {
    send_fresh();  // c + 3, c + 4
    EXPECT_FALSE(has(decisions_.back().deleted_point_id, p)) << "matched (as live) at c + 2; c + " << k;
  }
  send_fresh();  // c + 5: three in a row since c + 2
  EXPECT_TRUE(has(decisions_.back().deleted_point_id, p));
}

// The same when both are excluded: q, matched at c + 1 and c + 2, merged
// into p (last matched at c): p takes q's last match and q is forgotten.
TEST_F(DeferredNode, AMergeOfAnExcludedPointIntoAnotherKeepsItsMatches) {
  make_deferred(3);
  const std::int64_t p = exclude_one();  // tick c
  ASSERT_GE(p, 0);
  const std::vector<std::int64_t> excluded = decisions_.back().excluded_point_id;
  ASSERT_GE(excluded.size(), 2u);
  const std::int64_t q = excluded[1];
  send_fresh({q});  // c + 1
  send_fresh({q});  // c + 2
  keepless::map_event_t e = kt::make_event(++seq_);
  e.merged_from_id = {q};
  e.merged_into_id = {p};
  send(e);
  ASSERT_EQ(acks_.back().status, keepless::map_event_ack_t::STATUS_APPLIED);
  EXPECT_FALSE(node_->deferred_culls().contains(static_cast<std::uint64_t>(q))) << "the source is forgotten";
  for (int k = 3; k <= 4; ++k) {
    send_fresh();  // c + 3, c + 4
    EXPECT_FALSE(has(decisions_.back().deleted_point_id, p)) << "matched (as q) at c + 2; c + " << k;
  }
  send_fresh();  // c + 5
  EXPECT_TRUE(has(decisions_.back().deleted_point_id, p));
  EXPECT_FALSE(has(decisions_.back().deleted_point_id, q)) << "the VO merged it away: never reported";
}

}  // namespace
}  // namespace keepless::testing
