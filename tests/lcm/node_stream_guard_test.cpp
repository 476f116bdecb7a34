// Stray traffic cannot deny service on memq://: normal VO traffic (keyframe,
// then a map event) is decided with the drain on; no message or short burst
// wipes the window, the cull memory or the order; publishers are isolated
// and every answer names the publisher it answers; latency counts from
// arrival; a refused merge item does not hide a valid one.

#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <set>
#include <vector>

#include "keepless/platform/recent_ids.hpp"
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

// Everything a stray message must not change: the window, the cull memory
// (points 0..kPoints), the owner and its order.
struct State {
  WindowSnapshot window;
  std::vector<bool> culled;
  std::uint32_t culls = 0;
  bool owned = false;
  std::int64_t owner = 0, last_sequence = 0, last_utime = 0;
  bool operator==(const State& o) const {
    return window == o.window && culled == o.culled && culls == o.culls && owned == o.owned && owner == o.owner &&
           last_sequence == o.last_sequence && last_utime == o.last_utime;
  }
};
constexpr std::int64_t kPoints = 400;

class GuardOnMemq : public NodeOnMemq {
 protected:
  State state() const {
    State s;
    s.window = snapshot(node_->window());
    for (std::int64_t p = 0; p < kPoints; ++p) s.culled.push_back(node_->cull_memory().contains(static_cast<std::uint64_t>(p)));
    s.culls = node_->cull_memory().size();
    s.owned = node_->order().owned();
    s.owner = node_->order().owner();
    s.last_sequence = node_->order().last_sequence();
    s.last_utime = node_->order().last_utime();
    return s;
  }
  keepless::status_t status() {
    node_->publish_status(false);
    pump();
    return statuses_.back();
  }
  // Keyframe `sequence` of `publisher`: 20 points from `sequence`, id unique per (publisher, sequence).
  static keepless::keyframe_t keyframe(std::int64_t publisher, std::int64_t sequence) {
    keepless::keyframe_t m = kt::make_keyframe(sequence, publisher * 100000 + sequence, kt::id_range(sequence, 20));
    m.publisher_id = publisher;
    return m;
  }
  // The anonymous owner's keyframes 1..n (ids 1..n, overlapping points): the
  // window of K = 4 holds n-3..n and something was culled.
  void live_stream(std::int64_t n) {
    for (std::int64_t s = 1; s <= n; ++s) send(kt::make_keyframe(s, s, kt::id_range(s * 5 % kPoints, 30)));
    ASSERT_EQ(node_->window().keyframe_count(), 4u);
    ASSERT_GT(node_->cull_memory().size(), 0u) << "the stream must cull";
    ASSERT_EQ(node_->counters().messages_rejected, 0u);
  }
  std::size_t count(int status, std::size_t first = 0) const {
    std::size_t n = 0;
    for (std::size_t i = first; i < decisions_.size(); ++i) n += decisions_[i].status == status;
    return n;
  }
  void queue(const std::string& channel, const std::vector<std::uint8_t>& bytes) {
    bus_->publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));  // not handled yet
  }
  void queue(const keepless::keyframe_t& m) { queue(config_.keyframe_channel, kt::encode(m)); }
  void queue(keepless::map_event_t e) {
    kt::finalize(e);
    queue(config_.event_channel, kt::encode(e));
  }
  // The drain on (a latency target that never fires).
  void make_draining_node() {
    NodeConfig c = default_config();
    c.latency_target_ms = 60000;
    c.queue_capacity = 4096;
    make_node(c);
  }
};

// --- 1. the drain ---------------------------------------------------------------

// Defect 1: with a latency target a keyframe followed by a map event (the
// normal VO pattern) was answered SKIPPED, never decided: 0 of 100.
TEST_F(GuardOnMemq, AKeyframeFollowedByAMapEventIsDecided) {
  make_draining_node();
  std::int64_t seq = 0;
  for (int i = 0; i < 100; ++i) {
    queue(kt::make_keyframe(++seq, i, kt::id_range(i * 3, 30)));
    keepless::map_event_t e = kt::make_event(++seq);
    e.deleted_point_id = {i * 3};
    queue(e);
    ASSERT_GT(node_->spin_once(0), 0);
    pump();
  }
  ASSERT_EQ(decisions_.size(), 100u);
  EXPECT_EQ(count(decision_t::STATUS_OPTIMAL), 100u);
  EXPECT_EQ(node_->counters().keyframes_skipped, 0u);
  EXPECT_GT(node_->counters().points_culled, 0u);
  ASSERT_EQ(acks_.size(), 100u);
  for (const map_event_ack_t& a : acks_) EXPECT_EQ(a.status, map_event_ack_t::STATUS_APPLIED);
}

// Defect 1: junk, an invalid keyframe or another publisher's keyframe queued
// behind a keyframe made it SKIPPED. Answers stay in arrival order.
TEST_F(GuardOnMemq, JunkInvalidAndForeignMessagesNeverCauseASkip) {
  make_draining_node();
  std::int64_t seq = 0;
  for (int i = 0; i < 30; ++i) {
    queue(kt::make_keyframe(++seq, i, kt::id_range(i * 3, 30)));
    switch (i % 3) {
      case 0: queue(config_.keyframe_channel, {0x12, 0x34}); break;  // 2 bytes of junk: no answer
      case 1: {
        keepless::keyframe_t bad = kt::make_keyframe(++seq, 1000 + i, kt::id_range(0, 5));
        bad.centre[0] = std::numeric_limits<double>::quiet_NaN();
        queue(bad);
        break;
      }
      default: {
        keepless::keyframe_t other = kt::make_keyframe(1, 2000 + i, kt::id_range(0, 5));
        other.publisher_id = 99;
        queue(other);
      }
    }
    ASSERT_GT(node_->spin_once(0), 0);
    pump();
  }
  EXPECT_EQ(node_->counters().keyframes_skipped, 0u);
  std::size_t decided = 0;
  std::int64_t last_sequence = 0;
  for (const decision_t& d : decisions_) {
    if (d.publisher_id == 0 && d.keyframe_id < 1000) {
      decided += d.status == decision_t::STATUS_OPTIMAL;
      EXPECT_GT(d.sequence, last_sequence) << "answers out of order";
      last_sequence = d.sequence;
    }
  }
  EXPECT_EQ(decided, 30u);
  EXPECT_EQ(decisions_.size(), 50u) << "30 decided, 10 invalid and 10 foreign answered, junk unanswered";
}

// Only a newer accepted keyframe of the same stream supersedes: with a
// rejected one between two valid ones, the first is SKIPPED by the second
// only, and the rejected one is answered after the first.
TEST_F(GuardOnMemq, OnlyANewerAcceptedKeyframeSupersedes) {
  make_draining_node();
  queue(kt::make_keyframe(1, 1, kt::id_range(0, 30)));
  queue(kt::make_keyframe(1, 2, kt::id_range(0, 30)));  // out of order: refused
  queue(kt::make_keyframe(2, 3, kt::id_range(5, 30)));
  ASSERT_GT(node_->spin_once(0), 0);
  pump();
  ASSERT_EQ(decisions_.size(), 3u);
  EXPECT_EQ(decisions_[0].keyframe_id, 1);
  EXPECT_EQ(decisions_[0].status, decision_t::STATUS_OPTIMAL) << "decided before the refusal was answered";
  EXPECT_EQ(decisions_[1].reject_reason, keepless::status_t::REJECT_OUT_OF_ORDER);
  EXPECT_EQ(decisions_[2].status, decision_t::STATUS_OPTIMAL);
  queue(kt::make_keyframe(3, 4, kt::id_range(10, 30)));
  queue(kt::make_keyframe(4, 5, kt::id_range(15, 30)));
  ASSERT_GT(node_->spin_once(0), 0);
  pump();
  ASSERT_EQ(decisions_.size(), 5u);
  EXPECT_EQ(decisions_[3].status, decision_t::STATUS_SKIPPED);
  ASSERT_EQ(decisions_[3].num_window_keyframes, 3) << "the window it entered, not the newer one's";
  EXPECT_EQ(decisions_[3].window_keyframe_id.back(), 4);
  EXPECT_EQ(decisions_[4].status, decision_t::STATUS_OPTIMAL);
}

// The default configuration (latency target on, 5 ms) decides normal VO
// traffic: keyframe, map event, keyframe, ... queued together.
TEST_F(GuardOnMemq, TheDefaultLatencyTargetDecidesEveryKeyframe) {
  NodeConfig c = default_config();
  c.latency_target_ms = NodeConfig{}.latency_target_ms;
  ASSERT_GT(c.latency_target_ms, 0);
  make_node(c);
  std::int64_t seq = 0;
  for (int round = 0; round < 20; ++round) {
    for (int i = 0; i < 5; ++i) {
      const int k = round * 5 + i;
      queue(kt::make_keyframe(++seq, k, kt::id_range(k * 3, 30)));
      keepless::map_event_t e = kt::make_event(++seq);
      e.deleted_point_id = {k * 3 + 1};
      queue(e);
    }
    ASSERT_GT(node_->spin_once(0), 0);
    pump();
  }
  ASSERT_EQ(decisions_.size(), 100u);
  EXPECT_EQ(count(decision_t::STATUS_SKIPPED), 0u);
  EXPECT_EQ(count(decision_t::STATUS_OPTIMAL) + count(decision_t::STATUS_BUDGET_EXHAUSTED), 100u);
  EXPECT_EQ(acks_.size(), 100u);
}

// --- 2. no wipe by stray traffic ---------------------------------------------------

// Defect 2(a): one reset from a never-seen publisher id wiped the window and
// the cull memory. The owner's own reset is still honoured, and says so.
TEST_F(GuardOnMemq, AResetFromAnotherPublisherChangesNothing) {
  live_stream(20);
  const State before = state();
  keepless::map_event_t reset = kt::make_event(21);
  reset.reset = true;
  reset.publisher_id = 4242;
  send(reset);
  EXPECT_TRUE(state() == before);
  ASSERT_EQ(acks_.size(), 1u);
  EXPECT_EQ(acks_.back().status, map_event_ack_t::STATUS_REJECTED);
  EXPECT_EQ(acks_.back().reject_reason, keepless::status_t::REJECT_NOT_OWNER);
  EXPECT_FALSE(acks_.back().reset);
  EXPECT_EQ(acks_.back().publisher_id, 4242);
  // The owner's reset, in order: honoured at once.
  keepless::map_event_t own = kt::make_event(21);
  own.reset = true;
  send(own);
  EXPECT_EQ(node_->window().keyframe_count(), 0u);
  EXPECT_EQ(node_->cull_memory().size(), 0u);
  EXPECT_TRUE(acks_.back().reset);
  EXPECT_EQ(acks_.back().status, map_event_ack_t::STATUS_APPLIED);
}

// Defect 2(b): retransmitted 17, 18, 19 after 20 were adopted as a restart:
// window 4 -> 1, keyframe 19 decided twice, a false gap.
TEST_F(GuardOnMemq, RetransmissionsDoNotRestart) {
  live_stream(20);
  const State before = state();
  const std::uint64_t gaps = node_->order().sequence_gaps();
  for (std::int64_t s = 17; s <= 19; ++s) send(kt::make_keyframe(s, s, kt::id_range(s * 5 % kPoints, 30)));
  EXPECT_TRUE(state() == before);
  EXPECT_EQ(node_->order().restarts(), 0u);
  EXPECT_EQ(node_->order().sequence_gaps(), gaps);
  EXPECT_EQ(count(decision_t::STATUS_OPTIMAL), 20u) << "no keyframe decided twice";
  send(kt::make_keyframe(21, 21, kt::id_range(105, 30)));
  EXPECT_EQ(decisions_.back().status, decision_t::STATUS_OPTIMAL);
}

// Review: with --max-sequence-jump at its largest, the gaps between
// sequences INT64_MIN + 1, 0 and INT64_MAX summed past 2^63 and
// status_t.sequence_gaps read -4. Saturated.
TEST_F(GuardOnMemq, SequenceGapsSaturateInsteadOfWrapping) {
  NodeConfig c = default_config();
  c.max_sequence_jump = std::numeric_limits<std::uint64_t>::max();
  make_node(c);
  for (std::int64_t s : {std::numeric_limits<std::int64_t>::min() + 1, std::int64_t{0},
                         std::numeric_limits<std::int64_t>::max()}) {
    keepless::keyframe_t m = kt::make_keyframe(0, 7 + (s > 0) + (s == 0) * 2, kt::id_range(0, 20));
    m.sequence = s;
    send(m);
    ASSERT_EQ(decisions_.back().status, decision_t::STATUS_OPTIMAL) << s;
  }
  EXPECT_EQ(status().sequence_gaps, std::numeric_limits<std::int64_t>::max());
}

// Defect 2(c): 1, 2, then 3 with a NaN centre: the third was rejected, yet
// the window went 4 -> 0 and the order 20 -> 3. A real restart (1, 2, then
// a valid 4; its clock from the start again, after the old order's second
// of silence) is still recognised at its third valid keyframe.
TEST_F(GuardOnMemq, AnInvalidKeyframeNeverCompletesARestart) {
  live_stream(20);
  clock_.advance(1000000000);
  const State before = state();
  send(kt::make_keyframe(1, 501, kt::id_range(300, 10)));
  send(kt::make_keyframe(2, 502, kt::id_range(300, 10)));
  keepless::keyframe_t nan = kt::make_keyframe(3, 503, kt::id_range(300, 10));
  nan.centre[1] = std::numeric_limits<double>::quiet_NaN();
  send(nan);
  EXPECT_TRUE(state() == before);
  EXPECT_EQ(decisions_.back().reject_reason, keepless::status_t::REJECT_NON_FINITE);
  send(kt::make_keyframe(4, 504, kt::id_range(300, 10)));
  EXPECT_EQ(decisions_.back().status, decision_t::STATUS_OPTIMAL);
  EXPECT_EQ(node_->order().restarts(), 1u);
  EXPECT_EQ(node_->order().last_sequence(), 4);
  ASSERT_EQ(node_->window().keyframe_count(), 1u) << "the old run's keyframes left with the restart";
  EXPECT_EQ(node_->cull_memory().size(), 0u);
}

// Defect 2(d): three stale empty map events wiped the window, and the third
// ack said APPLIED, reset = false.
TEST_F(GuardOnMemq, StaleMapEventsNeverWipe) {
  live_stream(20);
  const State before = state();
  for (std::int64_t s = 1; s <= 6; ++s) send(kt::make_event(s));
  EXPECT_TRUE(state() == before);
  ASSERT_EQ(acks_.size(), 6u);
  for (const map_event_ack_t& a : acks_) {
    EXPECT_EQ(a.status, map_event_ack_t::STATUS_REJECTED);
    EXPECT_FALSE(a.reset);
  }
  EXPECT_EQ(node_->order().restarts(), 0u);
}

// Defect 3: one late message of the old process (1030) between the new
// process's 1 and 2 locked the restart out for good (0 of 199).
TEST_F(GuardOnMemq, AStragglerDoesNotLockARestartOut) {
  for (std::int64_t s = 1020; s <= 1029; ++s) send(kt::make_keyframe(s, s, kt::id_range(s % kPoints, 30)));
  send(kt::make_keyframe(1, 1, kt::id_range(0, 20)));            // the new process
  send(kt::make_keyframe(1030, 1030, kt::id_range(230, 30)));     // the old one's straggler
  clock_.advance(1000000000);  // its last message: then the old order falls silent
  const std::size_t first = decisions_.size();
  for (std::int64_t s = 2; s <= 200; ++s) send(kt::make_keyframe(s, s, kt::id_range(s, 20)));
  // Served from its fourth keyframe: the straggler, accepted, clears the run
  // the new process's first keyframe had started (runs count only while the
  // order refuses everything).
  EXPECT_EQ(count(decision_t::STATUS_OPTIMAL, first), 197u) << "served from its fourth keyframe";
  EXPECT_EQ(node_->order().restarts(), 1u);
  EXPECT_EQ(status().stream_restarts, 1);
  EXPECT_EQ(node_->order().last_sequence(), 200);
}

// Defect 4(a): a sender with next sequences and utime +599 s throttled the
// live publisher to 100 of 300. Another id never touches the owner.
TEST_F(GuardOnMemq, AnotherSenderCannotThrottleTheOwner) {
  std::int64_t seq = 0;
  for (int i = 0; i < 300; ++i) {
    ++seq;
    keepless::keyframe_t m = kt::make_keyframe(seq, i, kt::id_range(i % 50, 20));
    m.publisher_id = 7;
    send(m);
    if (i % 3 == 2) {
      keepless::keyframe_t t = kt::make_keyframe(seq + 1, 10000 + i, kt::id_range(0, 5));
      t.utime = m.utime + 599000000;
      t.publisher_id = 9;
      const State before = state();
      send(t);
      ASSERT_TRUE(state() == before) << "after keyframe " << i;
    }
  }
  std::size_t owner = 0;
  for (const decision_t& d : decisions_) owner += d.publisher_id == 7 && d.status == decision_t::STATUS_OPTIMAL;
  EXPECT_EQ(owner, 300u);
  EXPECT_EQ(rejected(RejectReason::kNotOwner), 100u);
}

// Defect 4(b): three far-ahead messages per three keyframes wiped the window
// every cycle (200 restarts). Far-ahead messages are no restart.
TEST_F(GuardOnMemq, FarAheadMessagesNeverWipe) {
  std::int64_t seq = 0;
  for (int i = 0; i < 300; ++i) {
    send(kt::make_keyframe(++seq, i, kt::id_range(i % 50, 20)));
    if (i % 3 == 2 && i > 3) {
      const State before = state();
      for (int j = 0; j < 3; ++j) send(kt::make_keyframe(seq + 2000000 + j, 100000 + i * 3 + j, kt::id_range(0, 5)));
      ASSERT_TRUE(state() == before) << "after keyframe " << i;
    }
  }
  EXPECT_EQ(count(decision_t::STATUS_OPTIMAL), 300u);
  EXPECT_EQ(node_->order().restarts(), 0u);
}

// Defect 5: invalid messages from more ids than --max-publishers evicted the
// owner's order; then a stale reset wiped the window, a jump 20 -> 520
// counted no gap and a replayed keyframe was decided.
TEST_F(GuardOnMemq, ManyPublisherIdsNeverTurnOrderChecksOff) {
  live_stream(20);
  const State before = state();
  for (std::int64_t id = 1; id <= 400; ++id) {
    keepless::keyframe_t bad = kt::make_keyframe(1, 5000 + id, kt::id_range(0, 5));
    bad.orientation[0] = 2;  // invalid
    bad.publisher_id = id;
    send(bad);
    keepless::map_event_t e = kt::make_event(1);
    e.publisher_id = id;
    send(e);
  }
  EXPECT_TRUE(state() == before);
  keepless::map_event_t stale = kt::make_event(3);
  stale.reset = true;
  send(stale);
  EXPECT_TRUE(state() == before) << "a stale reset of the owner is still refused";
  send(kt::make_keyframe(18, 18, kt::id_range(90, 30)));  // replayed
  EXPECT_EQ(decisions_.back().reject_reason, keepless::status_t::REJECT_OUT_OF_ORDER);
  const std::uint64_t gaps = node_->order().sequence_gaps();
  send(kt::make_keyframe(520, 520, kt::id_range(100, 30)));
  EXPECT_EQ(node_->order().sequence_gaps(), gaps + 499);
  const keepless::status_t s = status();
  EXPECT_EQ(s.publishers_seen, 1);
  EXPECT_EQ(s.publishers_active, 1);
}

// --- 3. isolation -----------------------------------------------------------------

// Defect 6: two VOs numbering their own keyframes got 18 of 40 refused as
// duplicates and their points merged; decision_t named no publisher.
TEST_F(GuardOnMemq, PublishersNeverTouchEachOthersKeyframesOrPoints) {
  for (int i = 1; i <= 20; ++i) {
    send(keyframe(1, i));
    keepless::keyframe_t other = kt::make_keyframe(i, i, kt::id_range(0, 10));  // same ids and points
    other.publisher_id = 2;
    send(other);
  }
  std::size_t first = 0;
  for (const decision_t& d : decisions_) {
    if (d.publisher_id == 1) first += d.status == decision_t::STATUS_OPTIMAL;
    if (d.publisher_id == 2) {
      EXPECT_EQ(d.reject_reason, keepless::status_t::REJECT_NOT_OWNER);
    }
  }
  EXPECT_EQ(first, 20u);
  EXPECT_EQ(rejected(RejectReason::kDuplicateKeyframe), 0u);
  // The other publisher's reset and edits cannot remove the owner's keyframes.
  const State before = state();
  keepless::map_event_t e = kt::make_event(21);
  e.publisher_id = 2;
  e.removed_keyframe_id = {static_cast<std::int64_t>(node_->window().keyframe(0).id)};
  e.deleted_point_id = kt::id_range(0, 16);
  send(e);
  e.reset = true;
  send(e);
  EXPECT_TRUE(state() == before);
}

TEST_F(GuardOnMemq, WithOwnerTimeoutZeroTheOwnerIsNeverReplaced) {
  NodeConfig c = default_config();
  c.owner_timeout_s = 0;
  make_node(c);
  send(keyframe(1, 1));
  clock_.advance(3600ull * 1000000000ull);
  send(keyframe(2, 2));
  EXPECT_EQ(decisions_.back().reject_reason, keepless::status_t::REJECT_NOT_OWNER);
  EXPECT_EQ(node_->order().owner(), 1);
}

// --- 4. latency from arrival --------------------------------------------------------

// Defect 7: latency counted from the drain, so a backlog never showed in
// latency_max. Here every handler reads the (ticking) clock once: a keyframe
// with 300 junk messages behind it waits 300 readings longer, and the
// deadline counts from its arrival too.
TEST_F(GuardOnMemq, LatencyAndDeadlineCountFromArrival) {
  const auto run = [&](double target_ms, int junk) {
    NodeConfig c = default_config();
    c.latency_target_ms = target_ms;
    c.queue_capacity = 4096;
    make_node(c);
    clock_.tick = 10000;  // 10 us a reading
    queue(kt::make_keyframe(1, 1, kt::id_range(0, 30)));
    queue(kt::make_keyframe(2, 2, kt::id_range(5, 30)));
    for (int i = 0; i < junk; ++i) queue(config_.keyframe_channel, {0x00, 0x01, 0x02});
    EXPECT_GT(node_->spin_once(0), 0);
    pump();
    EXPECT_EQ(decisions_.size(), 2u);
    return std::pair<std::uint64_t, int>(node_->latency().max(), decisions_.empty() ? -1 : decisions_.back().status);
  };
  const auto quiet = run(60000, 0);
  const auto backlog = run(60000, 300);
  EXPECT_EQ(backlog.second, decision_t::STATUS_OPTIMAL);
  EXPECT_GE(backlog.first, quiet.first + 300 * 10000) << "the backlog shows in latency_max";
  EXPECT_EQ(status().latency_max_ns, static_cast<std::int64_t>(backlog.first));
  // A deadline 1 ms beyond the quiet case's latency: met without the
  // backlog, missed with it (3 ms of waiting).
  const double target_ms = static_cast<double>(quiet.first) / 1e6 + 1.0;
  EXPECT_EQ(run(target_ms, 0).second, decision_t::STATUS_OPTIMAL);
  EXPECT_EQ(run(target_ms, 300).second, decision_t::STATUS_BUDGET_EXHAUSTED);
}

// --- merges (small items) -------------------------------------------------------------

// Merges 5 -> 5 then 5 -> 25: both were refused, so the valid one was lost.
TEST_F(GuardOnMemq, ARefusedMergeDoesNotHideTheValidOne) {
  fill_without_culling();  // 10: 0..29, 11: 10..39, 12: 20..49
  keepless::map_event_t e = kt::make_event(4);
  e.merged_from_id = {5, 5};
  e.merged_into_id = {5, 25};
  send(e);
  ASSERT_EQ(acks_.size(), 1u);
  EXPECT_EQ(acks_.back().merged_applied, 1);
  EXPECT_EQ(acks_.back().refused[map_event_ack_t::ITEM_MERGE_SELF], 1);
  EXPECT_EQ(acks_.back().refused[map_event_ack_t::ITEM_MERGE_REPEATED_SOURCE], 0);
  const keepless::core::Window& w = node_->window();
  for (std::uint32_t j = 0; j < w.observation_count(0); ++j) EXPECT_NE(w.observations(0)[j].point, 5u) << "5 merged";
}

// Repeats of sources among distinct ones, in any order: each source's first
// valid merge applies, every later one is refused as a repeat (found by the
// sorted sources, not by a scan of the merges applied so far).
TEST_F(GuardOnMemq, EachSourcesFirstValidMergeAppliesAndItsRepeatsAreRefused) {
  fill_without_culling();  // 10: 0..29, 11: 10..39, 12: 20..49
  keepless::map_event_t e = kt::make_event(4);
  e.merged_from_id = {7, 3, 7, 4, 3, 7, 4};
  e.merged_into_id = {7, 30, 31, 32, 33, 34, 35};  // 7 -> 7 refused: 7 -> 31 is 7's first valid one
  send(e);
  ASSERT_EQ(acks_.size(), 1u);
  EXPECT_EQ(acks_.back().merged_applied, 3);
  EXPECT_EQ(acks_.back().refused[map_event_ack_t::ITEM_MERGE_SELF], 1);
  EXPECT_EQ(acks_.back().refused[map_event_ack_t::ITEM_MERGE_REPEATED_SOURCE], 3);
  const keepless::core::Window& w = node_->window();
  EXPECT_EQ(w.point_views(7), 0u);
  EXPECT_EQ(w.point_views(3), 0u);
  EXPECT_EQ(w.point_views(4), 0u);
  EXPECT_GT(w.point_views(31), 0u);
}

// merged_applied counted merges that changed nothing (source not in the window).
TEST_F(GuardOnMemq, MergedAppliedCountsOnlyMergesThatChangedSomething) {
  fill_without_culling();
  keepless::map_event_t e = kt::make_event(4);
  e.merged_from_id = {9999, 45};
  e.merged_into_id = {1, 500};
  send(e);
  ASSERT_EQ(acks_.size(), 1u);
  EXPECT_EQ(acks_.back().status, map_event_ack_t::STATUS_APPLIED);
  EXPECT_EQ(acks_.back().merged_applied, 1);
}

// One owner message the stream does not continue, within the jump bounds,
// became the order and refused every later message of the owner, its reset
// included (a sequence with a bit flipped, a utime stepped ahead, an absurd
// first message heard mid-run, a far-ahead map event). A run of
// --restart-confirm valid keyframes in order among themselves, once the order
// has accepted nothing for 1 s (or a shorter --owner-timeout-s), is a
// resync: it becomes the order and the window is kept.
class ResyncOnMemq : public GuardOnMemq {
 protected:
  // How the owner's keyframes reach the node.
  enum class Delivery {
    kOnce,
    kTwice,          // every datagram delivered twice
    kWithStraggler,  // each followed by a late keyframe, 10 sequences back
  };
  // The owner's keyframe `s`: sequence base_ + s, id s, utime from s.
  keepless::keyframe_t owner_keyframe(std::int64_t s) const {
    keepless::keyframe_t m = kt::make_keyframe(base_ + s, s, kt::id_range(s * 5 % kPoints, 30));
    m.utime = kt::make_keyframe(s, 0, {}).utime;
    return m;
  }
  // The owner's keyframes from..to at 10 Hz of node time.
  void stream_at_10hz(std::int64_t from, std::int64_t to, Delivery delivery = Delivery::kOnce) {
    for (std::int64_t s = from; s <= to; ++s) {
      clock_.advance(100000000);
      send(owner_keyframe(s));
      if (delivery == Delivery::kTwice) send(owner_keyframe(s));
      if (delivery == Delivery::kWithStraggler) {
        keepless::keyframe_t late = owner_keyframe(s - 10);  // valid: its id is not in the window
        late.keyframe_id = 100000 + s;
        send(late);
      }
    }
  }
  // The owner's keyframe `s` with bit 19 of its sequence flipped (within
  // --max-sequence-jump), 0.1 s on: accepted, and it becomes the order.
  void send_flipped(std::int64_t s) {
    keepless::keyframe_t flipped = kt::make_keyframe(base_ + s + (1 << 19), s, kt::id_range(105, 30));
    flipped.utime = kt::make_keyframe(s, 0, {}).utime;
    clock_.advance(100000000);
    send(flipped);
    ASSERT_EQ(decisions_.back().status, decision_t::STATUS_OPTIMAL);
  }
  // The first answer to keyframe id `id` from decision `first` on (a copy's comes after it).
  const decision_t* answer(std::int64_t id, std::size_t first) const {
    for (std::size_t i = first; i < decisions_.size(); ++i) {
      if (decisions_[i].keyframe_id == id) return &decisions_[i];
    }
    return nullptr;
  }
  // After the poison: 4 s of the stream from `from` is served again within
  // the silence (1 s) and the run (3 keyframes), by a resync that keeps the
  // window (`window` keyframes with the resync's); then the owner's reset is honoured.
  void expect_resynchronised(std::int64_t from, std::int32_t window = 4, Delivery delivery = Delivery::kOnce) {
    const std::size_t first = decisions_.size();
    stream_at_10hz(from, from + 39, delivery);
    EXPECT_GE(count(decision_t::STATUS_OPTIMAL, first), 40u - 13u);
    const decision_t* last = answer(from + 39, first);
    ASSERT_NE(last, nullptr);
    EXPECT_EQ(last->status, decision_t::STATUS_OPTIMAL);
    EXPECT_EQ(node_->order().last_sequence(), base_ + from + 39);
    EXPECT_EQ(node_->order().resyncs(), 1u);
    EXPECT_EQ(node_->order().restarts(), 0u);
    EXPECT_EQ(status().stream_restarts, 1);
    std::size_t resync = first;
    while (resync < decisions_.size() && decisions_[resync].status != decision_t::STATUS_OPTIMAL) ++resync;
    ASSERT_LT(resync, decisions_.size());
    EXPECT_EQ(decisions_[resync].num_window_keyframes, window) << "a resync keeps the window";
    keepless::map_event_t reset = kt::make_event(base_ + from + 40);
    reset.utime = kt::make_event(from + 40).utime;
    reset.reset = true;
    send(reset);
    EXPECT_EQ(acks_.back().status, map_event_ack_t::STATUS_APPLIED);
    EXPECT_EQ(node_->window().keyframe_count(), 0u);
  }
  std::int64_t base_ = 0;  // added to every sequence of the owner
};

TEST_F(ResyncOnMemq, ASequenceWithABitFlippedIsOutvoted) {
  stream_at_10hz(1, 20);
  send_flipped(21);
  expect_resynchronised(22);
}

TEST_F(ResyncOnMemq, AUtimeSteppedAheadIsOutvoted) {
  stream_at_10hz(1, 20);
  keepless::keyframe_t stepped = kt::make_keyframe(21, 21, kt::id_range(105, 30));
  stepped.utime += 500ll * 1000000;  // within --max-utime-jump-s
  clock_.advance(100000000);
  send(stepped);
  ASSERT_EQ(decisions_.back().status, decision_t::STATUS_OPTIMAL);
  expect_resynchronised(22);
}

TEST_F(ResyncOnMemq, AnAbsurdFirstMessageHeardMidRunIsOutvoted) {
  keepless::keyframe_t absurd = kt::make_keyframe(4999, 99999, kt::id_range(0, 30));
  absurd.sequence = std::numeric_limits<std::int64_t>::max();
  send(absurd);
  stream_at_10hz(5000, 5002);  // a run of three, but not yet a second since the order accepted anything
  ASSERT_EQ(rejected(RejectReason::kOutOfOrder), 3u);
  expect_resynchronised(5003, 2);  // the absurd keyframe stays: only its sequence was wrong
}

TEST_F(ResyncOnMemq, AFarAheadMapEventIsOutvoted) {
  stream_at_10hz(1, 20);
  keepless::map_event_t far = kt::make_event(21 + 900000);  // within --max-sequence-jump
  far.utime = kt::make_keyframe(21, 0, {}).utime;
  send(far);
  ASSERT_EQ(acks_.back().status, map_event_ack_t::STATUS_APPLIED);
  expect_resynchronised(22);
}

// A stray keyframe with a low sequence (a restart candidate of its own) does
// not stop the stream's resync.
TEST_F(ResyncOnMemq, AStrayLowSequenceDoesNotBlockTheResync) {
  stream_at_10hz(101, 120);
  send_flipped(121);
  stream_at_10hz(122, 122);
  send(kt::make_keyframe(5, 777, kt::id_range(300, 30)));  // valid, refused, sequence <= 16
  expect_resynchronised(123);
}

// Stragglers of the old run refused by the order (sequence above 16) between
// a restarted VO's keyframes never delay its restart.
TEST_F(ResyncOnMemq, RefusedStragglersDoNotDelayARestart) {
  stream_at_10hz(1020, 1029);
  clock_.advance(1000000000);  // the old process died; the new one's clock starts again
  send(kt::make_keyframe(1, 1, kt::id_range(0, 20)));             // the new process
  send(kt::make_keyframe(1025, 5025, kt::id_range(230, 30)));     // the old one's, late: refused
  send(kt::make_keyframe(2, 2, kt::id_range(1, 20)));
  send(kt::make_keyframe(1026, 5026, kt::id_range(231, 30)));     // again
  const std::size_t first = decisions_.size();
  send(kt::make_keyframe(3, 3, kt::id_range(2, 20)));
  EXPECT_EQ(count(decision_t::STATUS_OPTIMAL, first), 1u) << "served from its third keyframe";
  EXPECT_EQ(node_->order().restarts(), 1u);
  EXPECT_EQ(node_->order().resyncs(), 0u);
  EXPECT_EQ(node_->order().last_sequence(), 3);
}

// Late keyframes of a live stream (valid, in order among themselves, refused
// by the order) never take it back: the order keeps accepting.
// (Sequences above 16: a run from 16 or below is a restart, served at once.)
TEST_F(ResyncOnMemq, LateKeyframesOfALiveStreamNeverResync) {
  stream_at_10hz(101, 120);
  const std::size_t first = decisions_.size();
  for (std::int64_t s = 121; s <= 160; ++s) {
    stream_at_10hz(s, s);
    send(kt::make_keyframe(s - 10, 1000 + s, kt::id_range(s * 5 % kPoints, 30)));  // late, not in the window
  }
  EXPECT_EQ(count(decision_t::STATUS_OPTIMAL, first), 40u);
  EXPECT_EQ(rejected(RejectReason::kOutOfOrder), 40u);
  EXPECT_EQ(node_->order().resyncs(), 0u);
  EXPECT_EQ(node_->order().last_sequence(), 160);
}

// Review: a refused keyframe that did not continue the resync run replaced
// it, so with every datagram delivered twice the run never grew past 1 and
// one flipped sequence locked the owner out (0 decisions in 60 s). A
// duplicate now changes no run. (From sequence 1 the copies of 1, 2, 3 were
// also a restart run, and restarted the stream.)
TEST_F(ResyncOnMemq, DuplicatedDatagramsDoNotBlockTheResync) {
  stream_at_10hz(1, 20, Delivery::kTwice);
  EXPECT_EQ(count(decision_t::STATUS_OPTIMAL), 20u);
  EXPECT_EQ(rejected(RejectReason::kOutOfOrder), 20u) << "the copies are refused";
  EXPECT_EQ(node_->order().restarts(), 0u);
  send_flipped(21);
  expect_resynchronised(22, 4, Delivery::kTwice);
}

// The same with a late keyframe (10 sequences back) after each one: each
// straggler started a run of its own in place of the stream's.
TEST_F(ResyncOnMemq, LateStragglersDoNotBlockTheResync) {
  stream_at_10hz(101, 120);
  send_flipped(121);
  expect_resynchronised(122, 4, Delivery::kWithStraggler);
}

// Review: candidate runs outlived the stream accepting again, so two late
// keyframes and a third an hour later were a restart (window and cull memory
// cleared). Every accepted message clears them.
TEST_F(ResyncOnMemq, LateKeyframesOfALiveStreamNeverAddUpToARestart) {
  stream_at_10hz(1, 12);
  for (std::int64_t s : {3, 4}) {
    keepless::keyframe_t late = owner_keyframe(s);
    late.keyframe_id = 100000 + s;  // valid: its id is not in the window
    send(late);
  }
  stream_at_10hz(13, 40);
  clock_.advance(3600ull * 1000000000ull);
  keepless::keyframe_t late = owner_keyframe(5);
  late.keyframe_id = 100005;
  send(late);
  EXPECT_EQ(decisions_.back().status, decision_t::STATUS_REJECTED_INPUT);
  EXPECT_EQ(node_->order().restarts(), 0u);
  EXPECT_EQ(node_->order().resyncs(), 0u);
  EXPECT_EQ(node_->order().last_sequence(), 40);
  EXPECT_EQ(node_->window().keyframe_count(), 4u) << "the window kept";
}

// Review: a VO numbering from a random 64-bit start (here negative) never
// started a resync run, so one flipped sequence locked it out.
TEST_F(ResyncOnMemq, NegativeSequencesAreResynchronised) {
  base_ = -1000000000000;
  stream_at_10hz(1, 20);
  ASSERT_EQ(count(decision_t::STATUS_OPTIMAL), 20u);
  send_flipped(21);
  expect_resynchronised(22);
}

// Review: exact copies of a stream's first keyframes arriving late (a relay
// flushing its queue, a log replayed onto the bus) were a restart run once
// their ids had left the window and the last --window keyframes' memory:
// three of them cleared the window and the cull memory. The order remembers
// its keyframes with sequences 0..16, so the copies change nothing.
TEST_F(ResyncOnMemq, LateCopiesOfTheStreamsStartNeverRestart) {
  stream_at_10hz(1, 40);
  const auto before = kt::snapshot(node_->window());
  const std::uint32_t culls = node_->cull_memory().size();
  ASSERT_GT(culls, 0u);
  for (std::int64_t s = 1; s <= 5; ++s) send(owner_keyframe(s));
  EXPECT_EQ(rejected(RejectReason::kOutOfOrder), 5u);
  EXPECT_EQ(node_->order().restarts(), 0u);
  EXPECT_TRUE(kt::snapshot(node_->window()) == before) << "the window kept";
  EXPECT_EQ(node_->cull_memory().size(), culls) << "the cull memory kept";
  stream_at_10hz(41, 41);
  EXPECT_EQ(decisions_.back().status, decision_t::STATUS_OPTIMAL);
  EXPECT_EQ(node_->order().last_sequence(), 41);
}

// Review: after the VO paused (1 s or more), late copies of keyframes it sent
// before the pause were a resync run: three took the order back 18 sequences
// and 1.8 s, and every older copy after them was decided over a window of
// stale keyframes. A run behind the order in both sequence and utime, and not
// after the order before it, never resyncs.
TEST_F(ResyncOnMemq, LateCopiesAfterAPauseNeverResync) {
  stream_at_10hz(1, 40);
  clock_.advance(2000000000);
  const auto before = kt::snapshot(node_->window());
  for (std::int64_t s = 20; s <= 30; ++s) send(owner_keyframe(s));
  EXPECT_EQ(rejected(RejectReason::kOutOfOrder), 11u);
  EXPECT_EQ(node_->order().resyncs(), 0u);
  EXPECT_EQ(node_->order().last_sequence(), 40);
  EXPECT_TRUE(kt::snapshot(node_->window()) == before) << "the window kept";
  stream_at_10hz(41, 41);
  EXPECT_EQ(decisions_.back().status, decision_t::STATUS_OPTIMAL);
}

// The rule above spares the resync it exists for: one message ahead in both
// sequence and utime (within the bounds) is outvoted by the stream, which
// follows the order before it.
TEST_F(ResyncOnMemq, AKeyframeAheadInSequenceAndUtimeIsOutvoted) {
  stream_at_10hz(1, 20);
  keepless::keyframe_t ahead = kt::make_keyframe(21 + (1 << 19), 21, kt::id_range(105, 30));
  ahead.utime = kt::make_keyframe(21, 0, {}).utime + 500ll * 1000000;
  clock_.advance(100000000);
  send(ahead);
  ASSERT_EQ(decisions_.back().status, decision_t::STATUS_OPTIMAL);
  expect_resynchronised(22);
}

// Review: two such messages locked the owner out until its utime passed
// theirs (20 minutes; twelve, 2 hours): the stream was behind the last and
// not after the one before it, so it was taken for late copies. The
// stream's past arrives as a flush, at once; a live stream heard for the
// resync's silence is outvoting the burst.
TEST_F(ResyncOnMemq, ABurstAheadInSequenceAndUtimeIsOutvoted) {
  stream_at_10hz(1, 20);
  std::int64_t utime = kt::make_keyframe(21, 0, {}).utime;
  for (std::int64_t i = 0; i < 12; ++i) {
    keepless::keyframe_t ahead = kt::make_keyframe(21 + (1 << 19) + i, 900000 + i, kt::id_range(105, 30));
    utime += 599ll * 1000000;  // each within --max-utime-jump-s of the last
    ahead.utime = utime;
    clock_.advance(1000000);
    send(ahead);
    ASSERT_EQ(decisions_.back().status, decision_t::STATUS_OPTIMAL) << i;
  }
  expect_resynchronised(21);
}

// Review: late copies of start keyframes the order never accepted were a
// restart run: three wiped the window and the cull memory, and the stale
// keyframes became the order the live stream was decided over. While the
// order is live a restart needs later utimes (a restarted VO's clock goes
// on; copies are earlier): the node started after its VO ...
TEST_F(ResyncOnMemq, LateCopiesOfAStartTheNodeMissedNeverRestart) {
  stream_at_10hz(20, 40);
  const auto before = kt::snapshot(node_->window());
  const std::uint32_t culls = node_->cull_memory().size();
  ASSERT_GT(culls, 0u);
  for (std::int64_t s = 1; s <= 5; ++s) send(owner_keyframe(s));
  EXPECT_EQ(node_->order().restarts(), 0u);
  EXPECT_TRUE(kt::snapshot(node_->window()) == before) << "the window kept";
  EXPECT_EQ(node_->cull_memory().size(), culls) << "the cull memory kept";
  stream_at_10hz(41, 41);
  EXPECT_EQ(decisions_.back().status, decision_t::STATUS_OPTIMAL);
  for (std::int64_t id : decisions_.back().window_keyframe_id) EXPECT_GE(id, 38) << "a stale keyframe decided over";
}

// ... or lost the datagrams of 2, 3 and 4.
TEST_F(ResyncOnMemq, LateCopiesOfLostStartKeyframesNeverRestart) {
  stream_at_10hz(1, 1);
  stream_at_10hz(5, 40);
  const auto before = kt::snapshot(node_->window());
  for (std::int64_t s = 1; s <= 5; ++s) send(owner_keyframe(s));
  EXPECT_EQ(node_->order().restarts(), 0u);
  EXPECT_TRUE(kt::snapshot(node_->window()) == before) << "the window kept";
}

// A restarted VO whose utimes start again (a replayed log, a clock from
// boot) is served once its old order has been silent for the resync's
// second: 10 Hz keyframes, refused for about a second, then a restart.
TEST_F(ResyncOnMemq, ARestartWithAnEarlierClockIsServedAfterTheOldOrdersSilence) {
  stream_at_10hz(101, 140);
  const std::size_t first = decisions_.size();
  for (std::int64_t s = 1; s <= 30; ++s) {
    clock_.advance(100000000);
    send(kt::make_keyframe(s, 500 + s, kt::id_range(300 + s, 20)));
  }
  EXPECT_EQ(node_->order().restarts(), 1u);
  EXPECT_EQ(node_->order().resyncs(), 0u);
  EXPECT_EQ(node_->order().last_sequence(), 30);
  EXPECT_GE(count(decision_t::STATUS_OPTIMAL, first), 30u - 11u) << "refused for about a second";
  EXPECT_LE(count(decision_t::STATUS_OPTIMAL, first), 30u - 9u) << "not before the old order's silence";
  for (std::int64_t id : decisions_.back().window_keyframe_id) EXPECT_GT(id, 500) << "an old keyframe kept";
}

// Review: the resync waited for --owner-timeout-s, so with 30 s one flipped
// sequence locked the owner out for 30 s. It waits 1 s at most.
TEST_F(ResyncOnMemq, ALongOwnerTimeoutDoesNotDelayTheResync) {
  NodeConfig c = default_config();
  c.owner_timeout_s = 30;
  make_node(c);
  stream_at_10hz(1, 20);
  send_flipped(21);
  expect_resynchronised(22);
  EXPECT_EQ(node_->order().owner(), 0) << "no takeover";
}

// Review: a flipped sequence while sequences were still <= 16 made the
// stream's next keyframes look like a restart, clearing the window and the
// cull memory. They continue the order from before the flipped one: a
// resync, the window and the culls kept.
TEST_F(ResyncOnMemq, AnEarlyFlippedSequenceIsResynchronisedNotARestart) {
  stream_at_10hz(1, 5);
  std::vector<std::uint64_t> culled;
  for (std::uint64_t p = 0; p < kPoints; ++p) {
    if (node_->cull_memory().contains(p)) culled.push_back(p);
  }
  ASSERT_FALSE(culled.empty()) << "the stream must cull";
  send_flipped(6);
  const std::size_t first = decisions_.size();
  stream_at_10hz(7, 36);
  EXPECT_GE(count(decision_t::STATUS_OPTIMAL, first), 30u - 13u);
  EXPECT_EQ(decisions_.back().status, decision_t::STATUS_OPTIMAL);
  EXPECT_EQ(node_->order().last_sequence(), 36);
  EXPECT_EQ(node_->order().resyncs(), 1u);
  EXPECT_EQ(node_->order().restarts(), 0u);
  std::size_t resync = first;
  while (resync < decisions_.size() && decisions_[resync].status != decision_t::STATUS_OPTIMAL) ++resync;
  ASSERT_LT(resync, decisions_.size());
  EXPECT_EQ(decisions_[resync].num_window_keyframes, 4) << "a resync keeps the window";
  for (std::uint64_t p : culled) EXPECT_TRUE(node_->cull_memory().contains(p)) << "point " << p;
}

// A real restart early in a stream is still one: its first keyframe does
// not follow the order before the last accepted message.
TEST_F(ResyncOnMemq, AnEarlyRestartIsStillARestart) {
  stream_at_10hz(1, 5);
  clock_.advance(1000000000);
  const std::size_t first = decisions_.size();
  for (std::int64_t s = 1; s <= 3; ++s) send(kt::make_keyframe(s, 500 + s, kt::id_range(300 + s, 20)));
  EXPECT_EQ(count(decision_t::STATUS_OPTIMAL, first), 1u) << "served from its third keyframe";
  EXPECT_EQ(node_->order().restarts(), 1u);
  EXPECT_EQ(node_->window().keyframe_count(), 1u) << "the old run's keyframes left with the restart";
  EXPECT_EQ(node_->cull_memory().size(), 0u);
}

// A VO that crash-restarts within its first --window keyframes and numbers
// its sequences and keyframe ids from 1 again: its keyframes are not
// retransmissions (later utimes, other points), so it is a restart.
class EarlyRestartOnMemq : public ResyncOnMemq {
 protected:
  void SetUp() override {
    NodeConfig c = default_config();
    c.window = 8;
    make_node(c);
  }
  // The old process's keyframe `s` (sequence and id s).
  static keepless::keyframe_t old_keyframe(std::int64_t s) { return kt::make_keyframe(s, s, kt::id_range(s * 5, 30)); }
  // The new process's keyframe `s`: sequence and id s again, 5 s later, other points.
  static keepless::keyframe_t new_keyframe(std::int64_t s) {
    keepless::keyframe_t m = kt::make_keyframe(s, s, kt::id_range(200 + s * 5, 30));
    m.utime += 5000000;
    return m;
  }
  // Every point in the window is the new process's.
  bool window_only_new() const {
    const keepless::core::Window& w = node_->window();
    for (std::uint32_t k = 0; k < w.keyframe_count(); ++k) {
      for (std::uint32_t j = 0; j < w.observation_count(k); ++j) {
        if (w.observations(k)[j].point < 200) return false;
      }
    }
    return true;
  }
};

// Before: the copies of 1..5 were refused as retransmissions (their ids in
// the window) and 6..12 accepted in order: no restart, old keyframe 5 still
// in the window, new 6..12 decided on windows mixing both processes.
TEST_F(EarlyRestartOnMemq, ARestartReusingSequencesAndIdsIsARestart) {
  for (std::int64_t s = 1; s <= 5; ++s) send(old_keyframe(s));
  ASSERT_EQ(node_->window().keyframe_count(), 5u);
  const std::size_t first = decisions_.size();
  for (std::int64_t s = 1; s <= 12; ++s) send(new_keyframe(s));
  EXPECT_EQ(node_->order().restarts(), 1u);
  EXPECT_EQ(node_->order().resyncs(), 0u);
  EXPECT_EQ(node_->order().last_sequence(), 12);
  EXPECT_EQ(count(decision_t::STATUS_OPTIMAL, first), 10u) << "served from its third keyframe";
  EXPECT_TRUE(window_only_new()) << "an old keyframe is still in the window";
  std::vector<std::uint64_t> ids;
  for (std::uint32_t k = 0; k < node_->window().keyframe_count(); ++k) ids.push_back(node_->window().keyframe(k).id);
  EXPECT_EQ(ids, (std::vector<std::uint64_t>{5, 6, 7, 8, 9, 10, 11, 12}));
  // Each decision of the new process equals a fresh node's fed its keyframes 3..12.
  const std::vector<decision_t> got(decisions_.begin() + static_cast<std::ptrdiff_t>(first), decisions_.end());
  make_node(config_);
  for (std::int64_t s = 3; s <= 12; ++s) send(new_keyframe(s));
  ASSERT_EQ(decisions_.size(), 10u);
  ASSERT_EQ(got.size(), 12u);
  for (std::size_t i = 0; i < 10; ++i) {
    const decision_t& a = got[i + 2];
    const decision_t& b = decisions_[i];
    EXPECT_EQ(a.keyframe_id, b.keyframe_id);
    EXPECT_EQ(a.status, b.status) << "keyframe " << b.keyframe_id;
    EXPECT_EQ(a.window_keyframe_id, b.window_keyframe_id) << "keyframe " << b.keyframe_id;
    EXPECT_EQ(a.culled_point_id, b.culled_point_id) << "keyframe " << b.keyframe_id;
  }
}

// The same after three old keyframes: the new process's third has the
// sequence of the last accepted keyframe, and differs from it.
TEST_F(EarlyRestartOnMemq, ARestartReusingTheLastSequenceIsARestart) {
  for (std::int64_t s = 1; s <= 3; ++s) send(old_keyframe(s));
  const std::size_t first = decisions_.size();
  for (std::int64_t s = 1; s <= 6; ++s) send(new_keyframe(s));
  EXPECT_EQ(node_->order().restarts(), 1u);
  EXPECT_EQ(count(decision_t::STATUS_OPTIMAL, first), 4u) << "served from its third keyframe";
  EXPECT_EQ(node_->window().keyframe_count(), 4u);
  EXPECT_TRUE(window_only_new());
}

// Retransmissions early in a stream (same bytes, ids in the window) still
// change nothing, however often repeated. The node remembers its window's
// keyframes (K = 8), in its fixed memory.
TEST_F(EarlyRestartOnMemq, EarlyRetransmissionsDoNotRestart) {
  EXPECT_EQ(node_->order().recent_capacity(), 8u);
  EXPECT_GE(node_->order().memory_bytes(), 8 * 16u);
  for (std::int64_t s = 1; s <= 5; ++s) send(old_keyframe(s));
  const State before = state();
  for (int copy = 0; copy < 3; ++copy) {
    for (std::int64_t s = 1; s <= 5; ++s) send(old_keyframe(s));
  }
  EXPECT_TRUE(state() == before);
  EXPECT_EQ(node_->order().restarts(), 0u);
  EXPECT_EQ(count(decision_t::STATUS_OPTIMAL), 5u) << "no keyframe decided twice";
  send(old_keyframe(6));
  EXPECT_EQ(decisions_.back().status, decision_t::STATUS_OPTIMAL);
}

// Differing copies are no cheaper than other keyframes: fewer than
// --restart-confirm of them in a row change nothing, and the owner's next
// keyframe clears them.
TEST_F(EarlyRestartOnMemq, FewerDifferingCopiesThanARunChangeNothing) {
  for (std::int64_t s = 1; s <= 5; ++s) send(old_keyframe(s));
  for (std::int64_t round = 0; round < 3; ++round) {
    const State before = state();
    send(new_keyframe(1));
    send(new_keyframe(2));
    EXPECT_TRUE(state() == before);
    send(old_keyframe(6 + round));
    EXPECT_EQ(decisions_.back().status, decision_t::STATUS_OPTIMAL);
    send(new_keyframe(3));
    EXPECT_EQ(decisions_.back().reject_reason, keepless::status_t::REJECT_OUT_OF_ORDER);
  }
  EXPECT_EQ(node_->order().restarts(), 0u);
  EXPECT_EQ(node_->window().keyframe_count(), 8u);
}

// Late exact copies of the dead process's keyframes, after the restart: the
// new process's keyframes pushed them out of the record and reuse their ids,
// yet they are earlier than the last accepted keyframe, so they count toward
// no run (they restarted the stream again and brought keyframe 5 back).
TEST_F(EarlyRestartOnMemq, LateCopiesOfTheDeadProcessDoNotRestartAgain) {
  for (std::int64_t s = 1; s <= 5; ++s) send(old_keyframe(s));
  for (std::int64_t s = 1; s <= 10; ++s) send(new_keyframe(s));
  ASSERT_EQ(node_->order().restarts(), 1u);
  ASSERT_TRUE(window_only_new());
  const std::size_t culls = node_->cull_memory().size();
  for (std::int64_t s = 3; s <= 5; ++s) send(old_keyframe(s));
  EXPECT_EQ(node_->order().restarts(), 1u);
  EXPECT_EQ(node_->order().last_sequence(), 10);
  EXPECT_EQ(node_->window().keyframe_count(), 8u);
  EXPECT_EQ(node_->cull_memory().size(), culls);
  send(new_keyframe(11));
  EXPECT_TRUE(window_only_new()) << "the dead process's keyframe 5 is back in the window";
}

// Review: the same once the new process's own ids had pushed the dead one's
// out of the window: its accepted keyframes had replaced the start's hashes,
// so copies of the dead process's 3, 4, 5 restarted the live stream again.
TEST_F(EarlyRestartOnMemq, LateCopiesOfTheDeadProcessAfterTheWindowChangeNothing) {
  for (std::int64_t s = 1; s <= 5; ++s) send(old_keyframe(s));
  for (std::int64_t s = 1; s <= 30; ++s) {
    keepless::keyframe_t m = new_keyframe(s);
    m.keyframe_id = 1000 + s;  // the new process's own ids
    send(m);
  }
  ASSERT_EQ(node_->order().restarts(), 1u);
  const auto before = kt::snapshot(node_->window());
  const std::uint32_t culls = node_->cull_memory().size();
  for (std::int64_t s = 3; s <= 5; ++s) send(old_keyframe(s));
  EXPECT_EQ(node_->order().restarts(), 1u);
  EXPECT_EQ(node_->order().last_sequence(), 30);
  EXPECT_TRUE(kt::snapshot(node_->window()) == before) << "the window kept";
  EXPECT_EQ(node_->cull_memory().size(), culls) << "the cull memory kept";
  keepless::keyframe_t m = new_keyframe(31);
  m.keyframe_id = 1031;
  send(m);
  EXPECT_TRUE(window_only_new());
}

// Copies of keyframes after a plain and after a reset map event change nothing.
TEST_F(EarlyRestartOnMemq, CopiesAfterMapEventsChangeNothing) {
  for (std::int64_t s = 1; s <= 3; ++s) send(old_keyframe(s));
  keepless::map_event_t e = kt::make_event(4);
  e.deleted_point_id = {5};
  send(e);
  State before = state();
  for (int c = 0; c < 2; ++c) for (std::int64_t s = 1; s <= 3; ++s) send(old_keyframe(s));
  EXPECT_TRUE(state() == before);
  keepless::map_event_t reset = kt::make_event(5);
  reset.reset = true;
  send(reset);
  send(reset);
  ASSERT_EQ(node_->window().keyframe_count(), 0u);
  before = state();
  for (int c = 0; c < 2; ++c) for (std::int64_t s = 1; s <= 3; ++s) send(old_keyframe(s));
  EXPECT_TRUE(state() == before);
  EXPECT_EQ(node_->order().restarts(), 0u);
}

// Two anonymous VO processes numbering keyframe ids alike: the one behind
// (its keyframes timed before the owner's last) is refused, early in the
// stream too; it wiped the window once its ids counted toward a restart.
TEST_F(EarlyRestartOnMemq, TheProcessBehindIsRefused) {
  for (std::int64_t s = 1; s <= 5; ++s) send(old_keyframe(s));
  for (std::int64_t s = 1; s <= 3; ++s) {
    keepless::keyframe_t m = new_keyframe(s);
    m.utime -= 5000000 - 1000;  // the owner's clock, a little behind it
    send(m);
  }
  EXPECT_EQ(node_->order().restarts(), 0u);
  EXPECT_EQ(node_->window().keyframe_count(), 5u);
}

// A VO restarted behind a persisted sequence counter (or a bridge that
// numbers its messages): the new process numbers its keyframe ids from 0
// again but continues the old sequences. Its keyframes are in order and
// their ids unique among the window's, so to the node it is the old stream:
// served at once, no restart, the old process's keyframes left in the window
// until they slide out (the first --window - 1 decisions) and its culls in
// the cull memory. Its reset first (in order) gives it a clean window.
class ContinuedSequenceOnMemq : public EarlyRestartOnMemq {
 protected:
  static constexpr std::int64_t kOld = 12;       // the old process's keyframes, more than the window (8)
  static constexpr std::int64_t kOwnPoints = 200;  // the new process's point ids, none the old one's
  // The old process: sequences 1..n, keyframe ids 0..n-1, at 10 Hz.
  void dead_process(std::int64_t n = kOld) {
    for (std::int64_t s = 1; s <= n; ++s) {
      clock_.advance(100000000);
      send(kt::make_keyframe(s, s - 1, kt::id_range(s * 5, 30)));
    }
    last_old_ = n;
    ASSERT_EQ(count(decision_t::STATUS_OPTIMAL), static_cast<std::size_t>(n));
    ASSERT_GT(node_->cull_memory().size(), 0u) << "the old process must cull";
  }
  // The new process's keyframe j: id j, sequence `first` + j, 2 s after the
  // old process's last, points from `points` + 5j (kOwnPoints: ids of its
  // own; 5: the old process's ids again, a VO numbering its points from 0).
  keepless::keyframe_t restarted(std::int64_t first, std::int64_t j, std::int64_t points) const {
    keepless::keyframe_t m = kt::make_keyframe(first + j, j, kt::id_range(points + j * 5, 30));
    m.utime = kt::make_keyframe(last_old_, 0, {}).utime + 2000000 + j * 100000;
    return m;
  }
  // The new process's keyframes 0..n-1 at 10 Hz, after 2 s of silence.
  void new_process(std::int64_t first, std::int64_t points = kOwnPoints, std::int64_t n = 20) {
    clock_.advance(2000000000);
    for (std::int64_t j = 0; j < n; ++j) {
      clock_.advance(100000000);
      send(restarted(first, j, points));
    }
  }
  // The old process's keyframes in decision `d`'s window (oldest first):
  // those ahead of `first_id`, the new process's first accepted one.
  static std::size_t old_in(const decision_t& d, std::int64_t first_id) {
    for (std::size_t i = 0; i < d.window_keyframe_id.size(); ++i) {
      if (d.window_keyframe_id[i] == first_id) return i;
    }
    return 0;  // it left the window, after every older keyframe
  }
  // Whether a point is observed both by one of the window's `old` oldest
  // keyframes (the old process's) and by one of the rest.
  bool old_and_new_meet(std::size_t old) const {
    const keepless::core::Window& w = node_->window();
    std::set<keepless::core::PointId> old_points;
    for (std::uint32_t k = 0; k < w.keyframe_count(); ++k) {
      for (std::uint32_t j = 0; j < w.observation_count(k); ++j) {
        const keepless::core::PointId p = w.observations(k)[j].point;
        if (k < old) {
          old_points.insert(p);
        } else if (old_points.count(p) != 0) {
          return true;
        }
      }
    }
    return false;
  }
  // Decisions from `first` on whose window holds an old keyframe.
  std::size_t mixed(std::size_t first, std::int64_t first_id) const {
    std::size_t n = 0;
    for (std::size_t i = first; i < decisions_.size(); ++i) n += old_in(decisions_[i], first_id) > 0;
    return n;
  }
  // The decisions since `first`, and a fresh node's for the same keyframes of the new process.
  std::vector<decision_t> since(std::size_t first) const {
    return {decisions_.begin() + static_cast<std::ptrdiff_t>(first), decisions_.end()};
  }
  std::vector<decision_t> fresh_node(std::int64_t first, std::int64_t points) {
    make_node(config_);
    new_process(first, points);
    return decisions_;
  }
  std::int64_t last_old_ = 0;
};

// Old 1..12 (ids 0..11), new 13..32 (ids 0..19): all 20 decided, none
// refused, no restart; the first 7 (ids 0..6) over windows that still hold
// old keyframes (7 - j of them). The point ids do not meet, so the culls are
// a fresh node's; the old culls stay remembered.
TEST_F(ContinuedSequenceOnMemq, ARestartContinuingTheSequencesIsServedOverTheOldWindow) {
  dead_process();
  std::uint64_t old_cull = 0;
  while (old_cull < 200 && !node_->cull_memory().contains(old_cull)) ++old_cull;
  ASSERT_LT(old_cull, 200u);
  const std::size_t first = decisions_.size();
  new_process(kOld + 1);
  ASSERT_EQ(decisions_.size(), first + 20);
  EXPECT_EQ(count(decision_t::STATUS_OPTIMAL, first), 20u) << "served at once";
  EXPECT_EQ(node_->counters().messages_rejected, 0u);
  EXPECT_EQ(node_->order().restarts(), 0u);
  EXPECT_EQ(node_->order().resyncs(), 0u);
  EXPECT_EQ(node_->order().last_sequence(), kOld + 20);
  for (std::size_t j = 0; j < 20; ++j) {
    EXPECT_EQ(old_in(decisions_[first + j], 0), j < 7 ? 7 - j : 0) << "keyframe " << j;
  }
  EXPECT_EQ(mixed(first, 0), 7u) << "--window - 1 decisions over old keyframes";
  EXPECT_TRUE(window_only_new());
  EXPECT_TRUE(node_->cull_memory().contains(old_cull)) << "no restart: the old culls are kept";
  const std::vector<decision_t> got = since(first);
  const std::vector<decision_t> fresh = fresh_node(kOld + 1, kOwnPoints);
  ASSERT_EQ(fresh.size(), 20u);
  for (std::size_t j = 0; j < 20; ++j) EXPECT_EQ(got[j].culled_point_id, fresh[j].culled_point_id) << "keyframe " << j;
}

// The same new process numbering its points from 0 again, as the old one
// did: its observations meet the old keyframes' points in the window (2
// windows), and those of ids the old process culled are dropped as stale
// (410 against a fresh node's 290: the cull memory was not cleared), so 9
// of its 20 decisions cull less than a fresh node's. Still served.
TEST_F(ContinuedSequenceOnMemq, ARestartReusingPointIdsMeetsTheOldPointsAndCulls) {
  dead_process();
  const std::uint64_t stale = node_->counters().stale_observations;
  const std::size_t first = decisions_.size();
  std::size_t meetings = 0;  // windows where an old and a new keyframe observe one point
  clock_.advance(2000000000);
  for (std::int64_t j = 0; j < 20; ++j) {
    clock_.advance(100000000);
    send(restarted(kOld + 1, j, 5));
    meetings += old_and_new_meet(old_in(decisions_.back(), 0));
  }
  EXPECT_EQ(meetings, 2u) << "the two processes' points meet in the window";
  EXPECT_EQ(count(decision_t::STATUS_OPTIMAL, first), 20u) << "served at once";
  EXPECT_EQ(node_->order().restarts(), 0u);
  EXPECT_EQ(mixed(first, 0), 7u);
  EXPECT_GT(node_->counters().stale_observations, stale) << "the old culls drop the new process's points";
  const std::uint64_t new_stale = node_->counters().stale_observations - stale;
  const std::vector<decision_t> got = since(first);
  const std::vector<decision_t> fresh = fresh_node(kOld + 1, 5);
  ASSERT_EQ(fresh.size(), 20u);
  std::size_t differ = 0, fewer = 0;
  for (std::size_t j = 0; j < 20; ++j) {
    differ += got[j].culled_point_id != fresh[j].culled_point_id;
    fewer += got[j].culled_point_id.size() < fresh[j].culled_point_id.size();
  }
  EXPECT_EQ(differ, 9u) << "its decisions over the old window and culls";
  EXPECT_EQ(fewer, differ) << "each culls less than a fresh node's";
  EXPECT_GT(new_stale, node_->counters().stale_observations) << "more than its own in-flight culls dropped";
}

// Sequences jumping ahead within --max-sequence-jump: the same, the jump a
// gap. Beyond it: refused until a resync run (the old process silent for
// 1 s), whose third keyframe is decided over the kept window.
TEST_F(ContinuedSequenceOnMemq, ARestartJumpingAheadIsServedOverTheOldWindow) {
  dead_process();
  const std::size_t first = decisions_.size();
  new_process(5000);
  EXPECT_EQ(count(decision_t::STATUS_OPTIMAL, first), 20u) << "served at once";
  EXPECT_EQ(node_->order().restarts(), 0u);
  EXPECT_EQ(node_->order().resyncs(), 0u);
  EXPECT_EQ(node_->order().sequence_gaps(), 5000u - kOld - 1);
  EXPECT_EQ(mixed(first, 0), 7u);
}

TEST_F(ContinuedSequenceOnMemq, ARestartJumpingBeyondTheBoundIsResynchronised) {
  dead_process();
  const std::size_t first = decisions_.size();
  new_process(kOld + 2000000);
  ASSERT_EQ(decisions_.size(), first + 20);
  for (std::size_t j = 0; j < 2; ++j) {
    EXPECT_EQ(decisions_[first + j].reject_reason, keepless::status_t::REJECT_SEQUENCE_JUMP);
  }
  EXPECT_EQ(count(decision_t::STATUS_OPTIMAL, first), 18u) << "served from its third keyframe";
  EXPECT_EQ(node_->order().resyncs(), 1u);
  EXPECT_EQ(node_->order().restarts(), 0u);
  EXPECT_EQ(old_in(decisions_[first + 2], 2), 7u) << "a resync keeps the window";
  EXPECT_EQ(mixed(first + 2, 2), 7u);
}

// An old process of fewer keyframes than the window: the new process's ids
// still held are refused (duplicate keyframe ids, in order: no run) until
// fresh ids arrive, then 7 decisions over old keyframes.
TEST_F(ContinuedSequenceOnMemq, ARestartWithinTheWindowIsRefusedUntilFreshIds) {
  dead_process(5);
  const std::size_t first = decisions_.size();
  new_process(6);
  ASSERT_EQ(decisions_.size(), first + 20);
  for (std::size_t j = 0; j < 5; ++j) {
    EXPECT_EQ(decisions_[first + j].reject_reason, keepless::status_t::REJECT_DUPLICATE_KEYFRAME);
  }
  EXPECT_EQ(count(decision_t::STATUS_OPTIMAL, first), 15u);
  EXPECT_EQ(node_->order().restarts(), 0u);
  EXPECT_EQ(node_->order().resyncs(), 0u);
  EXPECT_EQ(mixed(first, 5), 7u);
  EXPECT_TRUE(window_only_new());
}

// The remedy: the new process's reset first, in order. The window and the
// cull memory are cleared at once and every keyframe is decided as by a
// fresh node, its point ids reused or not.
TEST_F(ContinuedSequenceOnMemq, AResetFirstGivesTheRestartAFreshWindow) {
  dead_process();
  keepless::map_event_t reset = kt::make_event(kOld + 1);
  reset.utime = restarted(0, 0, 0).utime;
  reset.reset = true;
  send(reset);
  ASSERT_TRUE(acks_.back().reset);
  EXPECT_EQ(node_->window().keyframe_count(), 0u);
  EXPECT_EQ(node_->cull_memory().size(), 0u);
  const std::uint64_t stale = node_->counters().stale_observations;
  const std::size_t first = decisions_.size();
  new_process(kOld + 2, 5);
  EXPECT_EQ(count(decision_t::STATUS_OPTIMAL, first), 20u);
  EXPECT_EQ(mixed(first, 0), 0u);
  const std::uint64_t own_stale = node_->counters().stale_observations - stale;
  const std::vector<decision_t> got = since(first);
  const std::vector<decision_t> fresh = fresh_node(kOld + 2, 5);
  ASSERT_EQ(fresh.size(), got.size());
  for (std::size_t j = 0; j < got.size(); ++j) {
    EXPECT_EQ(got[j].window_keyframe_id, fresh[j].window_keyframe_id) << "keyframe " << j;
    EXPECT_EQ(got[j].culled_point_id, fresh[j].culled_point_id) << "keyframe " << j;
  }
  EXPECT_EQ(node_->counters().stale_observations, own_stale) << "only its own in-flight culls";
}

}  // namespace
