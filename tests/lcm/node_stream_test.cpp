// Issue 15 on memq://: no message locks the node out (the stream-order
// policy), map events lose nothing and are answered, a VO that runs ahead of
// the decisions cannot bring culled points back, and queued keyframes are
// answered at once with the newest decided.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <set>
#include <vector>

#include "node_memq_fixture.hpp"

namespace {

namespace kt = keepless::testing;
using kt::NodeOnMemq;
using kt::snapshot;
using kt::WindowSnapshot;
using keepless::decision_t;
using keepless::map_event_ack_t;
using keepless::platform::NodeConfig;
using keepless::platform::RejectReason;

constexpr std::int64_t kMax = std::numeric_limits<std::int64_t>::max();

class StreamOnMemq : public NodeOnMemq {
 protected:
  keepless::status_t status() {
    node_->publish_status(false);
    pump();
    return statuses_.back();
  }
  // Keyframe `sequence` of publisher `publisher`, id unique per (publisher, sequence).
  static keepless::keyframe_t keyframe(std::int64_t publisher, std::int64_t sequence) {
    keepless::keyframe_t m = kt::make_keyframe(sequence, publisher * 100000 + sequence, kt::id_range(sequence, 20));
    m.publisher_id = publisher;
    return m;
  }
  std::size_t accepted_since(std::size_t first) const {
    std::size_t n = 0;
    for (std::size_t i = first; i < decisions_.size(); ++i) n += decisions_[i].status == decision_t::STATUS_OPTIMAL;
    return n;
  }
};

// --- the stream-order policy -------------------------------------------------

// Defect 1: sequence = INT64_MAX was accepted and locked out every later keyframe.
TEST_F(StreamOnMemq, ASequenceJumpIsRefusedWithoutMovingTheOrder) {
  fill();
  const WindowSnapshot before = snapshot(node_->window());
  keepless::keyframe_t jump = kt::make_keyframe(4, 13, kt::id_range(0, 5));
  jump.sequence = kMax;
  send(jump);
  ASSERT_EQ(decisions_.size(), 4u);
  EXPECT_EQ(decisions_.back().reject_reason, keepless::status_t::REJECT_SEQUENCE_JUMP);
  EXPECT_EQ(rejected(RejectReason::kSequenceJump), 1u);
  EXPECT_TRUE(snapshot(node_->window()) == before);
  EXPECT_EQ(node_->order().last_sequence(), 3);
  for (int i = 0; i < 20; ++i) send(kt::make_keyframe(4 + i, 20 + i, kt::id_range(i, 10)));
  EXPECT_EQ(accepted_since(4), 20u) << "every later valid keyframe is decided";
}

TEST_F(StreamOnMemq, AUtimeJumpIsRefusedWithoutMovingTheOrder) {
  fill();
  keepless::keyframe_t m = kt::make_keyframe(4, 13, kt::id_range(0, 5));
  m.utime = kMax;
  send(m);
  EXPECT_EQ(rejected(RejectReason::kUtimeJump), 1u);
  for (int i = 0; i < 20; ++i) send(kt::make_keyframe(4 + i, 20 + i, kt::id_range(i, 10)));
  EXPECT_EQ(accepted_since(4), 20u);
}

TEST_F(StreamOnMemq, JumpBoundsAreConfigurable) {
  NodeConfig c = default_config();
  c.max_sequence_jump = 10;
  c.max_utime_jump_s = 1;
  make_node(c);
  send(kt::make_keyframe(1, 1, {}));
  send(kt::make_keyframe(12, 2, {}));  // 11 above: refused
  keepless::keyframe_t m = kt::make_keyframe(11, 3, {});  // 10 above, but utime 1.1 s on: refused
  m.utime = kt::make_keyframe(1, 1, {}).utime + 1100000;
  send(m);
  send(kt::make_keyframe(11, 4, {}));  // 10 above, 1 s on: accepted
  EXPECT_EQ(rejected(RejectReason::kSequenceJump), 1u);
  EXPECT_EQ(rejected(RejectReason::kUtimeJump), 1u);
  EXPECT_EQ(node_->order().last_sequence(), 11);
}

// Review: a VO that makes keyframes on motion, parked for 11 minutes (more
// than --max-utime-jump-s), had its next valid keyframes refused
// REJECT_UTIME_JUMP. The bound grows by the node's time since the order last
// accepted a message; a utime step the node's clock does not cover is
// still refused.
TEST_F(StreamOnMemq, AUtimeAdvanceAfterAPauseOfTheNodesClockIsAccepted) {
  const auto at = [](std::int64_t s, std::int64_t pause_us) {
    keepless::keyframe_t m = kt::make_keyframe(s, s, kt::id_range(s * 5 % 400, 30));
    m.utime += pause_us;
    return m;
  };
  for (std::int64_t s = 1; s <= 20; ++s) {
    clock_.advance(100000000);
    send(at(s, 0));
  }
  const std::int64_t pause_us = 660ll * 1000000;
  clock_.advance(static_cast<std::uint64_t>(pause_us) * 1000);
  const std::size_t first = decisions_.size();
  for (std::int64_t s = 21; s <= 25; ++s) {
    clock_.advance(100000000);
    send(at(s, pause_us));
  }
  EXPECT_EQ(accepted_since(first), 5u);
  EXPECT_EQ(rejected(RejectReason::kUtimeJump), 0u);
  EXPECT_EQ(node_->order().resyncs(), 0u);
  EXPECT_EQ(node_->order().last_sequence(), 25);
  send(at(26, pause_us + 700ll * 1000000));  // 700 s ahead, 0.1 s of node time at most
  EXPECT_EQ(decisions_.back().reject_reason, keepless::status_t::REJECT_UTIME_JUMP);
}

// The first message has nothing to be checked against; if it is absurd, the
// valid stream after it becomes the order after --restart-confirm messages.
TEST_F(StreamOnMemq, APoisonedFirstMessageIsOutvotedByTheStream) {
  keepless::keyframe_t poison = kt::make_keyframe(1, 999, kt::id_range(0, 5));
  poison.sequence = kMax;
  send(poison);
  for (int i = 1; i <= 10; ++i) send(kt::make_keyframe(i, i, kt::id_range(i, 10)));
  ASSERT_EQ(decisions_.size(), 11u);
  EXPECT_EQ(rejected(RejectReason::kOutOfOrder), 2u) << "refused until the run of 3 is confirmed";
  EXPECT_EQ(accepted_since(1), 8u);
  EXPECT_EQ(node_->order().restarts(), 1u);
  EXPECT_EQ(node_->window().find_keyframe(999), -1) << "the restart cleared the poisoned window";
}

// Defect 1: a VO restarting without a reset was refused until its counter
// passed the old maximum (60 of 60). Served from its third keyframe.
TEST_F(StreamOnMemq, APublisherRestartIsServedWithinAFewMessages) {
  for (int i = 1; i <= 60; ++i) send(kt::make_keyframe(i, 1000 + i, kt::id_range(i, 10)));
  clock_.advance(1000000000);  // the old process died; the new one's clock starts again
  const std::size_t first = decisions_.size();
  for (int i = 1; i <= 60; ++i) send(kt::make_keyframe(i, i, kt::id_range(5000 + i, 10)));
  EXPECT_EQ(accepted_since(first), 58u);
  EXPECT_EQ(rejected(RejectReason::kOutOfOrder), 2u);
  EXPECT_EQ(node_->order().restarts(), 1u);
  // Effect on the window: the old run's keyframes left with the restart.
  for (std::uint32_t k = 0; k < node_->window().keyframe_count(); ++k) {
    EXPECT_LE(node_->window().keyframe(k).id, 60u);
  }
  EXPECT_EQ(status().stream_restarts, 1);
}

// One owner at a time: a new publisher id is refused while the owner is
// live and takes the window over (cleared) once the owner has been silent
// for --owner-timeout-s. (Before, a new id was served from its first
// message and shared the window: changed on purpose, publishers are isolated.)
TEST_F(StreamOnMemq, ANewPublisherIdTakesOverOnlyAfterTheOwnersSilence) {
  for (int i = 1; i <= 10; ++i) send(keyframe(1, 100 + i));
  for (int i = 1; i <= 3; ++i) send(keyframe(2, i));
  EXPECT_EQ(accepted_since(0), 10u);
  EXPECT_EQ(rejected(RejectReason::kNotOwner), 3u);
  EXPECT_EQ(decisions_.back().publisher_id, 2) << "a refusal names the publisher it answers";
  clock_.advance(static_cast<std::uint64_t>(config_.owner_timeout_s * 1e9));
  const std::size_t first = decisions_.size();
  for (int i = 4; i <= 10; ++i) send(keyframe(2, i));
  EXPECT_EQ(accepted_since(first), 7u) << "served from its first keyframe after the silence";
  for (std::uint32_t k = 0; k < node_->window().keyframe_count(); ++k) {
    EXPECT_LT(node_->window().keyframe(k).id, 100000u * 2 + 100) << "the old owner's keyframes left";
  }
  EXPECT_EQ(node_->order().owner(), 2);
  EXPECT_EQ(status().publishers_seen, 2);
}

// Defect 1 (before): of two publishers on one channel the one slightly
// behind was starved. Now the first is the owner and is served in full; the
// second never touches its window (refused, counted, answered).
TEST_F(StreamOnMemq, TwoPublishersOnOneChannelTheOwnerIsServedTheOtherRefused) {
  for (int i = 0; i < 100; ++i) {
    send(keyframe(7, 200 + i));
    send(keyframe(8, 195 + i));
  }
  std::size_t owner = 0, other_refused = 0;
  for (const decision_t& d : decisions_) {
    owner += d.publisher_id == 7 && d.status == decision_t::STATUS_OPTIMAL;
    other_refused += d.publisher_id == 8 && d.reject_reason == keepless::status_t::REJECT_NOT_OWNER;
  }
  EXPECT_EQ(owner, 100u);
  EXPECT_EQ(other_refused, 100u);
  for (std::uint32_t k = 0; k < node_->window().keyframe_count(); ++k) {
    EXPECT_EQ(node_->window().keyframe(k).id / 100000, 7u);
  }
  const keepless::status_t s = status();
  EXPECT_EQ(s.publishers_active, 1);
  EXPECT_EQ(s.stream_conflicts, 100);
  EXPECT_EQ(s.rejected[keepless::status_t::REJECT_NOT_OWNER], 100);
}

// Without ids two streams look like one: the one behind is refused and
// never takes over from the live one (it does not start near sequence 0, so
// it is no restart). (stream_conflicts now counts other publishers' refused
// messages, so this no longer asserts it.)
TEST_F(StreamOnMemq, TwoStreamsOnOneIdNeverDisplaceTheLiveOne) {
  for (int i = 0; i < 100; ++i) {
    send(kt::make_keyframe(200 + i, 10000 + i, kt::id_range(i, 10)));
    send(kt::make_keyframe(195 + i, 20000 + i, kt::id_range(i, 10)));
  }
  std::size_t first_stream = 0;
  for (const decision_t& d : decisions_) first_stream += d.keyframe_id < 20000 && d.status == decision_t::STATUS_OPTIMAL;
  EXPECT_EQ(first_stream, 100u) << "the live stream is never displaced";
  EXPECT_EQ(node_->order().restarts(), 0u);
}

// Defect 2: a reset with sequence 0 wiped the window.
TEST_F(StreamOnMemq, AStaleResetIsRefused) {
  fill();
  const WindowSnapshot before = snapshot(node_->window());
  keepless::map_event_t reset = kt::make_event(0);
  reset.reset = true;
  send(reset);
  EXPECT_TRUE(snapshot(node_->window()) == before);
  EXPECT_EQ(rejected(RejectReason::kOutOfOrder), 1u);
  ASSERT_EQ(acks_.size(), 1u);
  EXPECT_EQ(acks_.back().status, map_event_ack_t::STATUS_REJECTED);
  EXPECT_EQ(acks_.back().reject_reason, keepless::status_t::REJECT_OUT_OF_ORDER);
  EXPECT_FALSE(acks_.back().reset) << "the window was not reset";
}

// Defect 3: status had no counter for messages the node never saw.
TEST_F(StreamOnMemq, SequenceGapsAreCounted) {
  send(kt::make_keyframe(1, 1, {}));
  send(kt::make_keyframe(2, 2, {}));
  send(kt::make_keyframe(5, 3, {}));    // 3, 4 lost
  keepless::map_event_t e = kt::make_event(10);  // 6..9 lost
  send(e);
  send(kt::make_keyframe(3, 4, {}));    // late: refused, not a gap
  EXPECT_EQ(node_->order().sequence_gaps(), 6u);
  EXPECT_EQ(status().sequence_gaps, 6);
}

// Review: a map event before any keyframe (a VO's start-up reset) was
// refused REJECT_NOT_OWNER and counted as a publisher conflict. With no
// owner it is applied to the empty window and sets no order.
TEST_F(StreamOnMemq, AMapEventBeforeAnyKeyframeIsNoConflict) {
  keepless::map_event_t reset = kt::make_event(5);
  reset.reset = true;
  send(reset);
  ASSERT_EQ(acks_.size(), 1u);
  EXPECT_EQ(acks_.back().status, map_event_ack_t::STATUS_APPLIED);
  EXPECT_TRUE(acks_.back().reset);
  keepless::map_event_t other = kt::make_event(9);
  other.publisher_id = 4;
  other.deleted_point_id = kt::id_range(0, 3);
  send(other);
  ASSERT_EQ(acks_.size(), 2u);
  EXPECT_EQ(acks_.back().status, map_event_ack_t::STATUS_APPLIED);
  EXPECT_EQ(node_->counters().messages_rejected, 0u);
  keepless::status_t s = status();
  EXPECT_EQ(s.stream_conflicts, 0);
  EXPECT_EQ(s.publishers_active, 0);
  EXPECT_FALSE(node_->order().owned());
  send(kt::make_keyframe(1, 1, kt::id_range(0, 10)));  // below both events' sequences: they set no order
  EXPECT_EQ(decisions_.back().status, decision_t::STATUS_OPTIMAL);
  EXPECT_EQ(node_->order().owner(), 0);
  EXPECT_EQ(node_->order().last_sequence(), 1);
  s = status();
  EXPECT_EQ(s.publishers_seen, 1);
  EXPECT_EQ(s.stream_conflicts, 0);
}

// --- in-flight safety ----------------------------------------------------------

// Defect 4: a VO one keyframe ahead (it sends keyframe k+1 before it has
// decision k) brought culled ids back into the window.
TEST_F(StreamOnMemq, AVoOneKeyframeAheadCannotBringCulledPointsBack) {
  std::set<std::int64_t> vo_map;  // the VO's live points
  for (std::int64_t p = 0; p < 40; ++p) vo_map.insert(p);
  std::set<std::int64_t> culled;
  std::size_t applied = 0;
  std::int64_t next_point = 40;
  for (int k = 0; k < 12; ++k) {
    // The VO observes its live points (and some new ones)...
    std::vector<std::int64_t> ids(vo_map.begin(), vo_map.end());
    if (ids.size() > 40) ids.erase(ids.begin(), ids.end() - 40);
    for (int j = 0; j < 8; ++j) ids.push_back(next_point++);
    send(kt::make_keyframe(k + 1, k, ids));
    for (std::int64_t id : ids) vo_map.insert(id);
    // ... and applies the decision before the last one (it is one ahead).
    if (decisions_.size() >= 2) {
      for (; applied + 1 < decisions_.size(); ++applied) {
        for (std::int64_t id : decisions_[applied].culled_point_id) vo_map.erase(id);
      }
    }
    for (const decision_t& d : decisions_) culled.insert(d.culled_point_id.begin(), d.culled_point_id.end());
    const keepless::core::Window& w = node_->window();
    for (std::uint32_t s = 0; s < w.keyframe_count(); ++s) {
      for (std::uint32_t j = 0; j < w.observation_count(s); ++j) {
        EXPECT_EQ(culled.count(static_cast<std::int64_t>(w.observations(s)[j].point)), 0u)
            << "culled point " << w.observations(s)[j].point << " back in the window after keyframe " << k;
      }
    }
  }
  ASSERT_FALSE(culled.empty()) << "the stream must cull";
  EXPECT_GT(node_->counters().stale_observations, 0u) << "in-flight keyframes named culled points";
}

TEST_F(StreamOnMemq, AMergeIntoACulledPointIsRefused) {
  for (int i = 0; i < 6; ++i) send(kt::make_keyframe(i + 1, i, kt::id_range(0, 40)));
  std::int64_t victim = -1;
  for (const decision_t& d : decisions_) {
    if (d.num_culled > 0) victim = d.culled_point_id[0];
  }
  ASSERT_GE(victim, 0);
  keepless::map_event_t e = kt::make_event(7);
  e.merged_from_id = {1000};
  e.merged_into_id = {victim};
  send(e);
  ASSERT_EQ(acks_.size(), 1u);
  EXPECT_EQ(acks_.back().refused[map_event_ack_t::ITEM_MERGE_INTO_CULLED], 1);
  EXPECT_EQ(acks_.back().merged_applied, 0);
}

// --- queued keyframes ------------------------------------------------------------

// Defect 3: queued keyframes were decided oldest first, each one late. With
// a latency target, spin_once drains the queue, decides the newest and
// answers the older ones at once: each exactly one answer, nothing culled.
TEST_F(StreamOnMemq, QueuedKeyframesAreSkippedAndTheNewestDecided) {
  NodeConfig c = default_config();
  c.latency_target_ms = 60000;  // drains, but never fires
  make_node(c);
  for (int i = 0; i < 6; ++i) {
    keepless::keyframe_t m = kt::make_keyframe(i + 1, i, kt::id_range(0, 40));
    const std::vector<std::uint8_t> b = kt::encode(m);
    bus_->publish(c.keyframe_channel, b.data(), static_cast<unsigned>(b.size()));  // queued, not handled
  }
  ASSERT_GT(node_->spin_once(0), 0);
  pump();
  ASSERT_EQ(decisions_.size(), 6u);
  for (int i = 0; i < 5; ++i) {
    EXPECT_EQ(decisions_[i].sequence, i + 1);
    EXPECT_EQ(decisions_[i].status, decision_t::STATUS_SKIPPED);
    EXPECT_EQ(decisions_[i].num_culled, 0);
  }
  EXPECT_EQ(decisions_[5].status, decision_t::STATUS_OPTIMAL);
  EXPECT_GT(decisions_[5].num_culled, 0) << "the newest is decided over the whole window";
  EXPECT_EQ(node_->counters().keyframes_skipped, 5u);
  EXPECT_EQ(node_->window().keyframe_count(), 4u);
  EXPECT_EQ(status().keyframes_skipped, 5);
}

// With --scope newest a skipped keyframe's turn passes to the decided one
// (Sparsifier::note_undecided): the newest decides the points of the
// keyframes skipped before it too, not only its own.
TEST_F(StreamOnMemq, SkippedKeyframesPassTheirTurnToTheDecidedOne) {
  NodeConfig c = default_config();
  c.latency_target_ms = 60000;  // drains, but never fires
  c.params.scope = keepless::core::Scope::kNewest;
  make_node(c);
  for (int i = 0; i < 4; ++i) {  // keyframe i sees 10i .. 10i + 19: each shares 10 with the next
    const std::vector<std::uint8_t> b = kt::encode(kt::make_keyframe(i + 1, i, kt::id_range(10 * i, 20)));
    bus_->publish(c.keyframe_channel, b.data(), static_cast<unsigned>(b.size()));  // queued, not handled
  }
  ASSERT_GT(node_->spin_once(0), 0);
  pump();
  ASSERT_EQ(decisions_.size(), 4u);
  const decision_t& d = decisions_[3];
  EXPECT_EQ(d.status, decision_t::STATUS_OPTIMAL);
  EXPECT_EQ(d.evaluated, 30);  // 10 .. 39
  EXPECT_EQ(d.kept + d.culled, d.evaluated) << "the skipped keyframes' points are decided too";
  EXPECT_EQ(d.skipped, d.points - d.evaluated);
}

}  // namespace
