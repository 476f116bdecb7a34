// keepless_node's loop on memq://: every class of bad message is refused
// before it touches the window, counted under its reason, and nothing valid
// around it is lost; valid streams slide the window and get one decision each,
// equal to the core library's.

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <cmath>
#include <deque>
#include <iterator>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "keepless/decision_t.hpp"
#include "keepless/decision_timing_t.hpp"
#include "keepless/platform/node.hpp"
#include "keepless/status_t.hpp"
#include "forward_stream.hpp"
#include "node_memq_fixture.hpp"
#include "reference_node.hpp"

namespace kt = keepless::testing;
using keepless::platform::Node;
using keepless::platform::NodeConfig;
using keepless::platform::RejectReason;

namespace {

using kt::NodeOnMemq;
using kt::snapshot;
using kt::WindowSnapshot;

// --- one test per rejection reason ---------------------------------------

TEST_F(NodeOnMemq, RejectsOversizeCountBeforeDecoding) {
  fill();
  const WindowSnapshot before = snapshot(node_->window());
  send(kt::make_keyframe(4, 13, kt::id_range(0, 65)));  // limit 64
  EXPECT_EQ(decisions_.size(), 3u) << "a message refused unread gets no decision";
  expect_rejected_only(RejectReason::kOversizeCount, before);
}

TEST_F(NodeOnMemq, RejectsOversizeMapEvent) {
  fill();
  const WindowSnapshot before = snapshot(node_->window());
  keepless::map_event_t e = kt::make_event(4);
  e.deleted_point_id = kt::id_range(0, 17);  // limit 16
  send(e);
  expect_rejected_only(RejectReason::kOversizeCount, before);
}

TEST_F(NodeOnMemq, RejectsNanPose) {
  fill();
  const WindowSnapshot before = snapshot(node_->window());
  keepless::keyframe_t m = kt::make_keyframe(4, 13, kt::id_range(0, 10));
  m.centre[2] = std::numeric_limits<double>::quiet_NaN();
  send(m);
  ASSERT_EQ(decisions_.size(), 4u);
  EXPECT_EQ(decisions_.back().status, keepless::decision_t::STATUS_REJECTED_INPUT);
  EXPECT_EQ(decisions_.back().reject_reason, keepless::status_t::REJECT_NON_FINITE);
  EXPECT_EQ(decisions_.back().num_culled, 0);
  expect_rejected_only(RejectReason::kNonFinite, before);
}

TEST_F(NodeOnMemq, RejectsInfiniteKeypoint) {
  fill();
  const WindowSnapshot before = snapshot(node_->window());
  keepless::keyframe_t m = kt::make_keyframe(4, 13, kt::id_range(0, 10));
  m.v[7] = std::numeric_limits<float>::infinity();
  send(m);
  expect_rejected_only(RejectReason::kNonFinite, before);
}

// Defect 2 (issue 15): one stale keyframe id dropped the whole event, its
// deletions and merges included, and nobody was told.
TEST_F(NodeOnMemq, AnUnknownKeyframeIdLosesNoValidItemAndIsAcknowledged) {
  fill_without_culling();  // 10: 0..29, 11: 10..39, 12: 20..49
  keepless::map_event_t e = kt::make_event(4);
  e.deleted_point_id = kt::id_range(0, 10);  // ten deletions
  e.merged_from_id = {45};
  e.merged_into_id = {500};
  e.removed_keyframe_id = {999, 11};  // 999 is stale, 11 is in the window
  send(e);
  EXPECT_EQ(node_->counters().messages_rejected, 0u);
  const keepless::core::Window& w = node_->window();
  ASSERT_EQ(w.keyframe_count(), 2u) << "keyframe 11 removed";
  EXPECT_EQ(w.observation_count(0), 20u) << "all ten deletions applied";
  bool renamed = false;
  for (std::uint32_t j = 0; j < w.observation_count(1); ++j) renamed |= w.observations(1)[j].point == 500u;
  EXPECT_TRUE(renamed) << "the merge applied";
  ASSERT_EQ(acks_.size(), 1u);
  const keepless::map_event_ack_t& a = acks_.back();
  EXPECT_EQ(a.sequence, 4);
  EXPECT_EQ(a.status, keepless::map_event_ack_t::STATUS_PARTIAL);
  EXPECT_EQ(a.deleted_applied, 10);
  EXPECT_EQ(a.merged_applied, 1);
  EXPECT_EQ(a.removed_applied, 1);
  ASSERT_EQ(a.num_refused, 1);
  EXPECT_EQ(a.refused_id[0], 999);
  EXPECT_EQ(a.refused_reason[0], keepless::map_event_ack_t::ITEM_REMOVE_UNKNOWN_KEYFRAME);
  EXPECT_EQ(a.refused[keepless::map_event_ack_t::ITEM_REMOVE_UNKNOWN_KEYFRAME], 1);
  EXPECT_EQ(node_->counters().event_items_refused, 1u);
}

// Each bad merge or removal is refused alone, with its reason; every valid
// item of the same event is applied. A source whose first item was refused
// (3 -> 2, a chain) is merged by its next valid item (3 -> 8): a refused
// item does not take the source's turn.
TEST_F(NodeOnMemq, BadMergeItemsAreRefusedOneByOne) {
  fill_without_culling();  // 10: 0..29, 11: 10..39, 12: 20..49
  keepless::map_event_t e = kt::make_event(4);
  e.deleted_point_id = {5};
  e.merged_from_id = {1, 2, 3, 3, 4, 6, 6};
  e.merged_into_id = {1, 7, 2, 8, 5, 9, 10};  // self, ok, chain (2 is a source), ok, into deleted, ok, repeat
  e.removed_keyframe_id = {12, 12};
  send(e);
  ASSERT_EQ(acks_.size(), 1u);
  const keepless::map_event_ack_t& a = acks_.back();
  using A = keepless::map_event_ack_t;
  EXPECT_EQ(a.status, A::STATUS_PARTIAL);
  EXPECT_EQ(a.merged_applied, 3);  // 2 -> 7, 3 -> 8 and 6 -> 9
  EXPECT_EQ(a.refused[A::ITEM_MERGE_SELF], 1);
  EXPECT_EQ(a.refused[A::ITEM_MERGE_CHAIN], 1);
  EXPECT_EQ(a.refused[A::ITEM_MERGE_REPEATED_SOURCE], 1);
  EXPECT_EQ(a.refused[A::ITEM_MERGE_INTO_DELETED], 1);
  EXPECT_EQ(a.refused[A::ITEM_REMOVE_REPEATED], 1);
  EXPECT_EQ(a.removed_applied, 1);
  EXPECT_EQ(node_->window().find_keyframe(12), -1);
  EXPECT_EQ(node_->counters().messages_rejected, 0u);
}

TEST_F(NodeOnMemq, RejectsDuplicateObservation) {
  fill();
  const WindowSnapshot before = snapshot(node_->window());
  send(kt::make_keyframe(4, 13, {1, 2, 3, 2}));
  ASSERT_EQ(decisions_.size(), 4u);
  EXPECT_EQ(decisions_.back().reject_reason, keepless::status_t::REJECT_DUPLICATE_OBSERVATION);
  expect_rejected_only(RejectReason::kDuplicateObservation, before);
}

TEST_F(NodeOnMemq, RejectsDuplicateKeyframe) {
  fill();
  const WindowSnapshot before = snapshot(node_->window());
  send(kt::make_keyframe(4, 11, kt::id_range(0, 5)));
  expect_rejected_only(RejectReason::kDuplicateKeyframe, before);
}

TEST_F(NodeOnMemq, RejectsOutOfOrderSequence) {
  fill();
  const WindowSnapshot before = snapshot(node_->window());
  send(kt::make_keyframe(3, 13, kt::id_range(0, 5)));  // 3 was already accepted
  expect_rejected_only(RejectReason::kOutOfOrder, before);
}

TEST_F(NodeOnMemq, RejectsOutOfOrderMapEvent) {
  fill();
  const WindowSnapshot before = snapshot(node_->window());
  keepless::map_event_t e = kt::make_event(2);
  e.deleted_point_id = {0};
  send(e);
  expect_rejected_only(RejectReason::kOutOfOrder, before);
}

TEST_F(NodeOnMemq, RejectsUtimeGoingBackwards) {
  fill();
  const WindowSnapshot before = snapshot(node_->window());
  keepless::keyframe_t m = kt::make_keyframe(4, 13, kt::id_range(0, 5));
  m.utime = 1;
  send(m);
  expect_rejected_only(RejectReason::kUtimeBackwards, before);
}

TEST_F(NodeOnMemq, RejectsWrongFingerprint) {
  fill();
  const WindowSnapshot before = snapshot(node_->window());
  std::vector<std::uint8_t> bytes = kt::encode(kt::make_keyframe(4, 13, kt::id_range(0, 5)));
  bytes[3] ^= 0x40;
  send_bytes(config_.keyframe_channel, bytes);
  expect_rejected_only(RejectReason::kFingerprint, before);
}

TEST_F(NodeOnMemq, RejectsAnotherTypeOnTheKeyframeChannel) {
  fill();
  const WindowSnapshot before = snapshot(node_->window());
  keepless::decision_t d{};
  send_bytes(config_.keyframe_channel, kt::encode(d));
  expect_rejected_only(RejectReason::kFingerprint, before);
}

TEST_F(NodeOnMemq, RejectsTruncatedBytes) {
  fill();
  const WindowSnapshot before = snapshot(node_->window());
  std::vector<std::uint8_t> bytes = kt::encode(kt::make_keyframe(4, 13, kt::id_range(0, 5)));
  bytes.resize(bytes.size() - 5);
  send_bytes(config_.keyframe_channel, bytes);
  expect_rejected_only(RejectReason::kTruncated, before);
}

TEST_F(NodeOnMemq, RejectsTrailingBytesAndStubs) {
  fill();
  const WindowSnapshot before = snapshot(node_->window());
  std::vector<std::uint8_t> bytes = kt::encode(kt::make_keyframe(4, 13, kt::id_range(0, 5)));
  bytes.push_back(0);
  send_bytes(config_.keyframe_channel, bytes);
  send_bytes(config_.keyframe_channel, std::vector<std::uint8_t>(bytes.begin(), bytes.begin() + 5));
  keepless::map_event_t e = kt::make_event(4);
  e.deleted_point_id = {1, 2};
  kt::finalize(e);
  std::vector<std::uint8_t> eb = kt::encode(e);
  eb.pop_back();
  send_bytes(config_.event_channel, eb);
  EXPECT_EQ(rejected(RejectReason::kTruncated), 3u);
  EXPECT_EQ(node_->counters().messages_rejected, 3u);
  EXPECT_TRUE(snapshot(node_->window()) == before);
}

TEST_F(NodeOnMemq, RejectsNegativeCountAndBadFields) {
  fill();
  const WindowSnapshot before = snapshot(node_->window());
  std::vector<std::uint8_t> bytes = kt::encode(kt::make_keyframe(4, 13, {}));
  bytes[keepless::platform::wire::kKeyframeCountOffset] = 0xff;  // count = negative
  send_bytes(config_.keyframe_channel, bytes);
  keepless::keyframe_t m = kt::make_keyframe(4, 13, kt::id_range(0, 5));
  m.image_width = 0;
  send(m);
  m = kt::make_keyframe(4, 13, kt::id_range(0, 5));
  m.orientation[0] = 2;  // not a unit quaternion
  send(m);
  EXPECT_EQ(rejected(RejectReason::kInvalidField), 3u);
  EXPECT_EQ(node_->counters().messages_rejected, 3u);
  EXPECT_TRUE(snapshot(node_->window()) == before);
}

TEST_F(NodeOnMemq, StatusCountsRejectsByReason) {
  fill();
  send(kt::make_keyframe(3, 13, kt::id_range(0, 5)));  // out of order
  std::vector<std::uint8_t> bytes = kt::encode(kt::make_keyframe(4, 13, kt::id_range(0, 5)));
  bytes.resize(20);
  send_bytes(config_.keyframe_channel, bytes);  // truncated
  node_->publish_status(true);
  pump();
  ASSERT_EQ(statuses_.size(), 1u);
  const keepless::status_t& s = statuses_.back();
  EXPECT_TRUE(s.is_final);
  EXPECT_EQ(s.keyframes_received, 5);
  EXPECT_EQ(s.messages_rejected, 2);
  EXPECT_EQ(s.rejected[keepless::status_t::REJECT_OUT_OF_ORDER], 1);
  EXPECT_EQ(s.rejected[keepless::status_t::REJECT_TRUNCATED], 1);
  EXPECT_EQ(s.decisions_published, 4);  // 3 + the answered out-of-order one
  EXPECT_EQ(s.window_keyframes, 3);
  EXPECT_EQ(s.last_sequence, 3);
  EXPECT_EQ(s.capacity_keyframes, 4);
  EXPECT_GT(s.memory_bytes, 0);
  EXPECT_GT(s.latency_max_ns, 0);
}

// --- valid streams --------------------------------------------------------

TEST_F(NodeOnMemq, SlidesAndMatchesTheLibrary) {
  kt::ReferenceNode ref(keepless::platform::window_capacities(config_), config_.params, config_.window);
  std::vector<kt::ReferenceDecision> expected;
  for (int i = 0; i < 10; ++i) {
    const keepless::keyframe_t m = kt::make_keyframe(i + 1, 100 + i, kt::id_range(i * 8, 40));
    expected.push_back(ref.step(m));
    send(m);
  }
  ASSERT_EQ(decisions_.size(), 10u);
  int culled = 0;
  for (int i = 0; i < 10; ++i) {
    EXPECT_EQ(decisions_[i].sequence, i + 1);
    EXPECT_EQ(decisions_[i].keyframe_id, 100 + i);
    kt::expect_same(expected[i], decisions_[i], ("keyframe " + std::to_string(i)).c_str());
    culled += decisions_[i].num_culled;
  }
  EXPECT_GT(culled, 0) << "the stream should exercise culling";
  EXPECT_EQ(node_->window().keyframe_count(), 4u);
  EXPECT_EQ(node_->window().keyframe(0).id, 106u);
}

TEST_F(NodeOnMemq, CulledPointsLeaveTheWindow) {
  for (int i = 0; i < 6; ++i) send(kt::make_keyframe(i + 1, i, kt::id_range(0, 40)));
  std::vector<std::int64_t> all_culled;
  for (const auto& d : decisions_) {
    all_culled.insert(all_culled.end(), d.culled_point_id.begin(), d.culled_point_id.end());
  }
  ASSERT_FALSE(all_culled.empty());
  const keepless::core::Window& w = node_->window();
  for (std::uint32_t k = 0; k < w.keyframe_count(); ++k) {
    for (std::uint32_t j = 0; j < w.observation_count(k); ++j) {
      const auto p = static_cast<std::int64_t>(w.observations(k)[j].point);
      EXPECT_EQ(std::count(all_culled.begin(), all_culled.end(), p), 0) << "culled point " << p << " still observed";
    }
  }
  EXPECT_EQ(static_cast<std::int64_t>(node_->counters().points_culled), static_cast<std::int64_t>(all_culled.size()));
}

TEST_F(NodeOnMemq, MapEventDeletesMergesAndRemoves) {
  fill_without_culling();  // 10: 0..29, 11: 10..39, 12: 20..49
  keepless::map_event_t e = kt::make_event(4);
  e.deleted_point_id = {0, 1, 12345};  // 12345 is not in the window: ignored
  e.merged_from_id = {21, 45};
  e.merged_into_id = {20, 500};  // 21 -> 20 collides in keyframes that saw both
  e.removed_keyframe_id = {11};
  send(e);
  ASSERT_EQ(node_->counters().messages_rejected, 0u);
  const keepless::core::Window& w = node_->window();
  ASSERT_EQ(w.keyframe_count(), 2u);
  EXPECT_EQ(w.keyframe(0).id, 10u);
  EXPECT_EQ(w.keyframe(1).id, 12u);
  EXPECT_EQ(w.observation_count(0), 27u);  // 30 - {0, 1} - merged duplicate 21
  EXPECT_EQ(w.observation_count(1), 29u);  // 30 - merged duplicate 21; 45 renamed
  for (std::uint32_t k = 0; k < 2; ++k) {
    for (std::uint32_t j = 0; j < w.observation_count(k); ++j) {
      const auto p = w.observations(k)[j].point;
      EXPECT_NE(p, 0u);
      EXPECT_NE(p, 21u);
      EXPECT_NE(p, 45u);
    }
  }
  EXPECT_EQ(w.observations(1)[24].point, 500u);  // 45 was 26th in keyframe 12, 21 (2nd) merged away

  keepless::map_event_t reset = kt::make_event(5);  // order-checked like any message
  reset.reset = true;
  send(reset);
  EXPECT_EQ(node_->window().keyframe_count(), 0u);
  ASSERT_EQ(acks_.size(), 2u);
  EXPECT_EQ(acks_.back().status, keepless::map_event_ack_t::STATUS_APPLIED);
  EXPECT_TRUE(acks_.back().reset);
  send(kt::make_keyframe(6, 10, kt::id_range(0, 5)));
  EXPECT_EQ(node_->window().keyframe_count(), 1u);
  EXPECT_EQ(node_->counters().messages_rejected, 0u);
}

TEST_F(NodeOnMemq, EmptyListsAfterFullOnesDecodeEmpty) {
  fill();
  keepless::map_event_t e = kt::make_event(4);
  e.deleted_point_id = {0};
  send(e);
  send(kt::make_keyframe(5, 13, {}));  // no observations after ones with many
  keepless::map_event_t empty = kt::make_event(6);
  send(empty);
  EXPECT_EQ(node_->counters().messages_rejected, 0u);
  EXPECT_EQ(node_->window().keyframe_count(), 4u);
  EXPECT_EQ(node_->window().observation_count(3), 0u);
}

TEST_F(NodeOnMemq, BudgetExhaustedCullsNothing) {
  NodeConfig c = default_config();
  c.budget_work_units = 1;
  make_node(c);
  for (int i = 0; i < 4; ++i) send(kt::make_keyframe(i + 1, i, kt::id_range(0, 40)));
  ASSERT_EQ(decisions_.size(), 4u);
  EXPECT_EQ(decisions_.back().status, keepless::decision_t::STATUS_BUDGET_EXHAUSTED);
  EXPECT_EQ(decisions_.back().num_culled, 0);
  EXPECT_GE(node_->counters().budget_exhaustions, 1u);
  EXPECT_EQ(node_->window().total_observations(), 160u);
}

// Each monocular use with its default flags, as the end-to-end test runs
// it: a decision the latency target stops (the host stalled) culls nothing,
// and whichever keyframe's decision it is, the use's rules hold after it
// (forward_stream.hpp): the next decision catches up on what was missed, and
// every excluded point is deleted when its own rule says.
TEST_F(NodeOnMemq, EachMonocularUseKeepsItsRulesWhicheverDecisionIsLate) {
  constexpr int kFrames = 30;
  for (const auto& [use, fraction] : kt::forward_stream::kMonocularUses) {
    for (int late = 0; late < kFrames; ++late) {
      SCOPED_TRACE(std::string(use) + " at " + fraction + ", late at keyframe " + std::to_string(late));
      NodeConfig c;
      std::string error;
      // --max-observations: a small fixed memory (60 a keyframe here); decisions do not depend on it.
      const char* argv[] = {"keepless_node", "--url", "memq://", "--use", use, "--keep-fraction", fraction,
                            "--max-observations", "64", "--quiet"};
      ASSERT_EQ(keepless::platform::parse_node_arguments(static_cast<int>(std::size(argv)), argv, c, error),
                keepless::platform::ParseResult::kOk)
          << error;
      ASSERT_GT(c.latency_target_ms, 0) << "the default configuration has a latency target";
      make_node(c);
      for (int i = 0; i < kFrames; ++i) {
        clock_.tick = i == late ? 100000000ull : 1000ull;  // 100 ms a clock reading: past the deadline at once
        send(kt::forward_stream::keyframe(i));
        ASSERT_EQ(decisions_.size(), static_cast<std::size_t>(i) + 1);
      }
      EXPECT_EQ(decisions_[static_cast<std::size_t>(late)].status, keepless::decision_t::STATUS_BUDGET_EXHAUSTED);
      EXPECT_GT(kt::forward_stream::expect_use_rules(use, decisions_), 100u);
    }
  }
}

TEST_F(NodeOnMemq, WindowCapacityIsAnsweredNotFatal) {
  NodeConfig c = default_config();
  c.max_pair_arcs = 50;  // far below what four overlapping keyframes need
  c.params.pair_capacity = 100;  // nothing culled, so every keyframe keeps all 40 points
  make_node(c);
  for (int i = 0; i < 4; ++i) send(kt::make_keyframe(i + 1, i, kt::id_range(0, 40)));
  ASSERT_EQ(decisions_.size(), 4u);
  EXPECT_EQ(decisions_.back().status, keepless::decision_t::STATUS_CAPACITY_EXCEEDED);
  EXPECT_EQ(decisions_.back().num_culled, 0);
  EXPECT_GE(node_->counters().capacity_exceeded, 1u);
}

// A window beyond the window's points: older keyframes make room, the
// keyframe is answered STATUS_CAPACITY_EXCEEDED with what the window needed,
// and the next keyframes are decided. Then the same for the network's pair
// arcs, which the slide brings back within capacity.
TEST_F(NodeOnMemq, AWindowBeyondCapacityIsAnsweredWithItsFiguresAndServingGoesOn) {
  using S = keepless::status_t;
  NodeConfig c = default_config();
  c.max_points = 100;
  c.max_window_observations = 150;
  c.max_pair_arcs = 60;
  c.params.pair_capacity = 100;  // nothing culled: the windows stay as sent
  make_node(c);
  const auto last_status = [&] {
    node_->publish_status(false);
    pump();
    return statuses_.back();
  };
  send(kt::make_keyframe(1, 10, kt::id_range(0, 60)));
  send(kt::make_keyframe(2, 11, kt::id_range(60, 60)));  // 120 distinct points > 100
  ASSERT_EQ(decisions_.size(), 2u);
  EXPECT_EQ(decisions_[0].status, keepless::decision_t::STATUS_OPTIMAL);
  EXPECT_EQ(decisions_[1].status, keepless::decision_t::STATUS_CAPACITY_EXCEEDED);
  EXPECT_EQ(decisions_[1].num_culled, 0);
  EXPECT_EQ(node_->counters().capacity_exceeded, 1u);
  EXPECT_EQ(node_->counters().messages_rejected, 0u);
  // The new keyframe is held; the oldest made room.
  ASSERT_EQ(node_->window().keyframe_count(), 1u);
  EXPECT_EQ(node_->window().keyframe(0).id, 11u);
  S st = last_status();
  EXPECT_EQ(st.capacity_exceeded, 1);
  EXPECT_EQ(st.last_capacity, S::CAPACITY_POINTS);
  EXPECT_EQ(st.last_capacity_sequence, 2);
  EXPECT_EQ(st.last_capacity_needed, 120);
  EXPECT_EQ(st.last_capacity_held, 100);
  EXPECT_EQ(st.capacity_pair_arcs, 60);

  // Later valid keyframes are decided: 11 and 12 share 30 points (30 pair arcs).
  send(kt::make_keyframe(3, 12, kt::id_range(90, 30)));
  ASSERT_EQ(decisions_.size(), 3u);
  EXPECT_EQ(decisions_[2].status, keepless::decision_t::STATUS_OPTIMAL);
  EXPECT_EQ(decisions_[2].evaluated, 30);

  // Points 90..119 in three keyframes: 90 pair arcs > 60.
  send(kt::make_keyframe(4, 13, kt::id_range(90, 30)));
  ASSERT_EQ(decisions_.size(), 4u);
  EXPECT_EQ(decisions_[3].status, keepless::decision_t::STATUS_CAPACITY_EXCEEDED);
  EXPECT_EQ(decisions_[3].num_culled, 0);
  EXPECT_EQ(node_->window().keyframe_count(), 3u);  // held, only not decided
  EXPECT_EQ(node_->window().pair_arcs(), 90u);
  st = last_status();
  EXPECT_EQ(st.capacity_exceeded, 2);
  EXPECT_EQ(st.last_capacity, S::CAPACITY_PAIR_ARCS);
  EXPECT_EQ(st.last_capacity_sequence, 4);
  EXPECT_EQ(st.last_capacity_needed, 90);
  EXPECT_EQ(st.last_capacity_held, 60);

  // The window (K = 4) slides past the crowded keyframes: 11, 12, 13 + 20
  // still needs 90; 12, 13, 20, 21 needs 30 and is decided, and so on.
  for (int i = 0; i < 4; ++i) send(kt::make_keyframe(5 + i, 20 + i, kt::id_range(200 + 10 * i, 10)));
  ASSERT_EQ(decisions_.size(), 8u);
  EXPECT_EQ(decisions_[4].status, keepless::decision_t::STATUS_CAPACITY_EXCEEDED);
  for (std::size_t d = 5; d < 8; ++d) EXPECT_EQ(decisions_[d].status, keepless::decision_t::STATUS_OPTIMAL) << d;
  EXPECT_EQ(node_->counters().capacity_exceeded, 3u);
  EXPECT_EQ(node_->counters().messages_rejected, 0u);
}

TEST_F(NodeOnMemq, StopsAfterMaxKeyframes) {
  NodeConfig c = default_config();
  c.max_keyframes = 2;
  make_node(c);
  send(kt::make_keyframe(1, 1, kt::id_range(0, 5)));
  EXPECT_FALSE(node_->finished());
  send(kt::make_keyframe(2, 2, kt::id_range(0, 5)));
  EXPECT_TRUE(node_->finished());
}

// Each decision_timing_t's solver work units, appended to `work`.
void record_solver_work(lcm::LCM& bus, const std::string& channel, std::vector<std::int64_t>* work) {
  void (*on_timing)(const lcm::ReceiveBuffer*, const std::string&, const keepless::decision_timing_t*,
                    std::vector<std::int64_t>*) =
      [](const lcm::ReceiveBuffer*, const std::string&, const keepless::decision_timing_t* t,
         std::vector<std::int64_t>* w) { w->push_back(t->solver_work_units); };
  bus.subscribeFunction(channel, on_timing, work);
}

// A decision whose work budget cannot cover the solve (the certificate of
// the closed-form start is one pass over the network's arc slots, which
// never shrink while the network lives) is flagged and culls nothing; the
// decisions before it are the library's. M = 100 culls nothing, so the
// reference's window (which never sees budgets) stays the node's. (How
// update() catches up after a stop: core_incremental_test.)
TEST_F(NodeOnMemq, AStopForBudgetIsFlaggedAndCullsNothing) {
  NodeConfig c = default_config();
  c.params.pair_capacity = 100;
  const std::vector<keepless::keyframe_t> stream = {
      kt::make_keyframe(1, 100, kt::id_range(0, 40)), kt::make_keyframe(2, 101, kt::id_range(8, 40)),
      kt::make_keyframe(3, 102, kt::id_range(16, 40)),
      // Empty: the 4th fills the window (K = 4) without changing the network,
      // the 5th slides the first keyframe out.
      kt::make_keyframe(4, 103, {}), kt::make_keyframe(5, 104, {})};

  // The solver work of each window, unbudgeted (work units are deterministic).
  make_node(c);
  std::vector<std::int64_t> work;
  record_solver_work(*bus_, c.timing_channel, &work);
  for (const keepless::keyframe_t& m : stream) send(m);
  ASSERT_EQ(work.size(), stream.size());
  ASSERT_LT(work[1], work[2] * 4 / 5);

  // 80 % of the third window's: from the third decision on, every one stops.
  c.budget_work_units = static_cast<std::uint64_t>(work[2]) * 4 / 5;
  make_node(c);
  kt::ReferenceNode ref(keepless::platform::window_capacities(c), c.params, c.window);
  std::vector<kt::ReferenceDecision> expected;
  for (const keepless::keyframe_t& m : stream) {
    expected.push_back(ref.step(m));
    ASSERT_TRUE(expected.back().culled.empty()) << "M = 100 should cull nothing";
    send(m);
  }
  ASSERT_EQ(decisions_.size(), stream.size());
  for (std::size_t i = 0; i < stream.size(); ++i) {
    const std::string where = "keyframe " + std::to_string(i);
    if (i < 2) {
      kt::expect_same(expected[i], decisions_[i], where.c_str());
      continue;
    }
    EXPECT_EQ(decisions_[i].status, keepless::decision_t::STATUS_BUDGET_EXHAUSTED) << where;
    EXPECT_EQ(decisions_[i].num_culled, 0) << where;
    EXPECT_EQ(decisions_[i].kept, expected[i].evaluated) << "a stopped decision keeps every evaluated point";
  }
  EXPECT_EQ(node_->counters().budget_exhaustions, 3u);
}

// Review: a decision the deadline stopped before any solve reported the
// previous decision's solver work in its decision_timing_t.
TEST_F(NodeOnMemq, ADeadlineStopReportsNoSolverWork) {
  NodeConfig c = default_config();
  c.latency_target_ms = NodeConfig{}.latency_target_ms;  // the default target
  make_node(c);
  std::vector<std::int64_t> work;
  record_solver_work(*bus_, c.timing_channel, &work);
  for (int i = 1; i <= 3; ++i) send(kt::make_keyframe(i, i, kt::id_range(i * 5, 30)));
  clock_.tick = 100000000ull;  // 100 ms a reading: past the deadline before the update
  send(kt::make_keyframe(4, 4, kt::id_range(20, 30)));
  ASSERT_EQ(decisions_.size(), 4u);
  ASSERT_EQ(work.size(), 4u);
  EXPECT_EQ(decisions_[3].status, keepless::decision_t::STATUS_BUDGET_EXHAUSTED);
  EXPECT_GT(work[2], 0);
  EXPECT_EQ(work[3], 0) << "no solve ran: keyframe 3's work was reported";
}

// The optional keyframe_t arrays reach the cost models, and the policies
// flags the library: the node decides what the library does on the same
// keyframes (depths, intrinsics, unmapped keypoints), for each cost model.
TEST_F(NodeOnMemq, PoliciesAndOptionalFieldsMatchTheLibrary) {
  for (keepless::core::CostModel model :
       {keepless::core::CostModel::kAuthors, keepless::core::CostModel::kInformation}) {
    NodeConfig c = default_config();
    c.max_unmapped = 20;
    c.params.cost_model = model;
    c.params.scope = keepless::core::Scope::kNewest;
    c.params.coverage_floor = 6;
    c.params.pair_capacity = 2;
    make_node(c);
    kt::ReferenceNode ref(keepless::platform::window_capacities(config_), config_.params, config_.window);
    std::vector<kt::ReferenceDecision> expected;
    for (int i = 0; i < 8; ++i) {
      keepless::keyframe_t m = kt::make_keyframe(i + 1, 100 + i, kt::id_range(i * 8, 40));
      m.num_depths = m.num_observations;
      for (int j = 0; j < m.num_observations; ++j) m.depth.push_back(1.0f + static_cast<float>((j * 7 + i) % 13));
      m.num_intrinsics = 4;
      m.intrinsics = {500.0, 500.0, 320.0, 240.0};
      m.num_unmapped = 3 * (i % 4);
      for (int j = 0; j < m.num_unmapped; ++j) {
        m.unmapped_u.push_back(static_cast<float>(40 * j + 25));
        m.unmapped_v.push_back(static_cast<float>(30 * j + 15));
      }
      expected.push_back(ref.step(m));
      send(m);
    }
    ASSERT_EQ(decisions_.size(), 8u);
    EXPECT_EQ(node_->counters().messages_rejected, 0u);
    for (int i = 0; i < 8; ++i) {
      kt::expect_same(expected[i], decisions_[i], ("keyframe " + std::to_string(i)).c_str());
    }
    // More unmapped keypoints than --max-unmapped: refused before decoding.
    keepless::keyframe_t big = kt::make_keyframe(50, 300, kt::id_range(0, 5));
    big.num_unmapped = 21;
    big.unmapped_u.assign(21, 1.0f);
    big.unmapped_v.assign(21, 1.0f);
    send(big);
    EXPECT_EQ(rejected(RejectReason::kOversizeCount), 1u);
  }
}

// Tracking-safe culling: the tracked flags of keyframe_t reach the window,
// the newest keyframe's flagged points are never culled, and with --maturity
// the decisions equal the library's on the same windows.
TEST_F(NodeOnMemq, TrackedFlagsAndMaturityMatchTheLibrary) {
  NodeConfig c = default_config();
  c.params.pair_capacity = 2;
  c.params.maturity_keyframes = 1;
  make_node(c);
  kt::ReferenceNode ref(keepless::platform::window_capacities(config_), config_.params, config_.window);
  std::vector<kt::ReferenceDecision> expected;
  std::vector<keepless::keyframe_t> sent;
  for (int i = 0; i < 8; ++i) {
    keepless::keyframe_t m = kt::make_keyframe(i + 1, 100 + i, kt::id_range(i * 8, 40));
    if (i % 4 != 2) {  // every fourth keyframe sends none
      m.num_tracked = m.num_observations;
      for (int j = 0; j < m.num_observations; ++j) m.tracked.push_back(static_cast<std::int8_t>((j + i) % 3 == 0));
    }
    expected.push_back(ref.step(m));
    sent.push_back(m);
    send(m);
  }
  ASSERT_EQ(decisions_.size(), 8u);
  EXPECT_EQ(node_->counters().messages_rejected, 0u);
  int culled = 0;
  for (int i = 0; i < 8; ++i) {
    kt::expect_same(expected[i], decisions_[i], ("keyframe " + std::to_string(i)).c_str());
    culled += decisions_[i].num_culled;
    const keepless::keyframe_t& m = sent[static_cast<std::size_t>(i)];
    for (int j = 0; j < m.num_tracked; ++j) {
      if (m.tracked[static_cast<std::size_t>(j)] == 0) continue;
      EXPECT_EQ(std::count(decisions_[i].culled_point_id.begin(), decisions_[i].culled_point_id.end(),
                           m.point_id[static_cast<std::size_t>(j)]),
                0)
          << "tracked point " << m.point_id[static_cast<std::size_t>(j)] << " culled at keyframe " << i;
    }
  }
  EXPECT_GT(culled, 0) << "the stream should exercise culling";
  // The newest keyframe in the window holds its flags.
  const keepless::core::Window& w = node_->window();
  ASSERT_NE(w.keyframe(w.keyframe_count() - 1).tracked, nullptr);
}

// --tracked-first: with a keep budget smaller than the flagged points, the
// newest keyframe's flagged points are candidates kept first, so some are
// culled (never, when skipped); the decisions equal the library's.
TEST_F(NodeOnMemq, TrackedFirstWithinAKeepBudgetMatchesTheLibrary) {
  NodeConfig c = default_config();
  c.params.budget = keepless::core::KeepBudget{keepless::core::BudgetKind::kPoints, 5, 0.0};
  c.params.tracked_first = true;
  make_node(c);
  kt::ReferenceNode ref(keepless::platform::window_capacities(config_), config_.params, config_.window);
  int flagged_culled = 0;
  for (int i = 0; i < 8; ++i) {
    keepless::keyframe_t m = kt::make_keyframe(i + 1, 100 + i, kt::id_range(i * 8, 40));
    m.num_tracked = m.num_observations;
    for (int j = 0; j < m.num_observations; ++j) m.tracked.push_back(static_cast<std::int8_t>((j + i) % 3 == 0));
    const kt::ReferenceDecision expected = ref.step(m);
    send(m);
    ASSERT_EQ(decisions_.size(), static_cast<std::size_t>(i + 1));
    kt::expect_same(expected, decisions_.back(), ("keyframe " + std::to_string(i)).c_str());
    for (int j = 0; j < m.num_tracked; ++j) {
      if (m.tracked[static_cast<std::size_t>(j)] == 0) continue;
      flagged_culled += static_cast<int>(std::count(decisions_.back().culled_point_id.begin(),
                                                    decisions_.back().culled_point_id.end(),
                                                    m.point_id[static_cast<std::size_t>(j)]));
    }
  }
  EXPECT_EQ(node_->counters().messages_rejected, 0u);
  EXPECT_GT(flagged_culled, 0) << "beyond the budget flagged points are culled: they count toward it";
}

// --cost track: keyframe_t's point quality reaches the window (through
// slides and the culled points' removal) and the decisions equal the
// library's on the same windows; keyframes without it are counted.
TEST_F(NodeOnMemq, PointQualityMatchesTheLibrary) {
  NodeConfig c = default_config();
  c.params.pair_capacity = 2;
  c.params.cost_model = keepless::core::CostModel::kTrack;
  make_node(c);
  kt::ReferenceNode ref(keepless::platform::window_capacities(config_), config_.params, config_.window);
  std::vector<kt::ReferenceDecision> expected;
  for (int i = 0; i < 8; ++i) {
    keepless::keyframe_t m = kt::make_keyframe(i + 1, 100 + i, kt::id_range(i * 8, 40));
    if (i % 4 != 2) {  // every fourth keyframe sends none
      m.num_quality = m.num_observations;
      for (int j = 0; j < m.num_observations; ++j) {
        m.track_length.push_back((j * 7 + i) % 23);
        m.age.push_back((j + i) % 5 - 1);
        m.reprojection_error.push_back(0.3f * static_cast<float>((j * 3 + i) % 13) - 0.2f);
        m.triangulation_angle.push_back(0.7f * static_cast<float>((j * 5 + i) % 17));
      }
    }
    expected.push_back(ref.step(m));
    send(m);
  }
  ASSERT_EQ(decisions_.size(), 8u);
  EXPECT_EQ(node_->counters().messages_rejected, 0u);
  EXPECT_EQ(node_->counters().track_fallback, 2u);
  int culled = 0;
  for (int i = 0; i < 8; ++i) {
    kt::expect_same(expected[i], decisions_[i], ("keyframe " + std::to_string(i)).c_str());
    culled += decisions_[i].num_culled;
  }
  EXPECT_GT(culled, 0) << "the stream should exercise culling";
  const keepless::core::Window& w = node_->window();
  ASSERT_NE(w.keyframe(w.keyframe_count() - 1).quality, nullptr);
}

TEST_F(NodeOnMemq, RejectsBadTrackedFlags) {
  fill();
  const WindowSnapshot before = snapshot(node_->window());
  keepless::keyframe_t m = kt::make_keyframe(4, 13, kt::id_range(0, 5));
  m.num_tracked = 4;  // neither 0 nor num_observations
  m.tracked.assign(4, 1);
  send(m);
  EXPECT_EQ(rejected(RejectReason::kInvalidField), 1u);
  m.num_tracked = 5;
  m.tracked.assign(5, 0);
  m.tracked[2] = 2;  // a flag is 0 or 1
  send(m);
  EXPECT_EQ(rejected(RejectReason::kInvalidField), 2u);
  EXPECT_EQ(node_->counters().messages_rejected, 2u);
  EXPECT_TRUE(snapshot(node_->window()) == before);
  // The same message with good flags is taken.
  m.tracked[2] = 1;
  send(m);
  EXPECT_EQ(node_->counters().messages_rejected, 2u);
  EXPECT_EQ(node_->window().keyframe_count(), 4u);
  EXPECT_NE(node_->window().keyframe(3).tracked, nullptr);
}

// --keep-fraction 0.3 (with --track-share S) over a sliding window whose
// culled points the VO drops: the node decides what the library does on the
// same keyframes, the first decision keeps floor(0.3 x evaluated + 0.5), and
// after every decision the points kept are exactly floor(0.3 x N + 0.5) of
// the N points evaluated so far (re-deciding a point does not compound the
// share). The share changes which points, never how many: on these
// keyframes, whose older points crowd one spatial-diversity box, so that
// the network's order prefers the new ones, it changes some decisions.
class KeepFractionOnMemq : public NodeOnMemq, public ::testing::WithParamInterface<double> {};

TEST_P(KeepFractionOnMemq, HoldsThatShareOfTheMap) {
  NodeConfig c = default_config();
  c.params.budget = keepless::core::KeepBudget{keepless::core::BudgetKind::kFraction, 0, 0.3};
  c.params.budget.track_share = GetParam();
  c.window = 8;
  make_node(c);
  kt::ReferenceNode ref(keepless::platform::window_capacities(config_), config_.params, config_.window);
  keepless::core::Params by_order = config_.params;
  by_order.budget.track_share = 0.0;
  kt::ReferenceNode order_only(keepless::platform::window_capacities(config_), by_order, config_.window);
  int changed_by_share = 0;
  std::set<std::int64_t> culled, evaluated;
  std::deque<std::vector<std::int64_t>> window;  // the ids of the node's window keyframes
  for (int i = 0; i < 12; ++i) {
    std::vector<std::int64_t> ids;
    for (std::int64_t id : kt::id_range(i * 4, 40)) {
      if (culled.count(id) == 0 && (id * 7 + i) % 5 != 0) ids.push_back(id);  // tracks of varied length
    }
    keepless::keyframe_t m = kt::make_keyframe(i + 1, 100 + i, ids);
    for (std::size_t j = 0; j < ids.size(); ++j) {  // the older points crowd one spatial-diversity box
      if (ids[j] < i * 4 + 16) m.u[j] = m.v[j] = 100.0f;
    }
    const kt::ReferenceDecision expected = ref.step(m);
    changed_by_share += order_only.step(m).culled != expected.culled;
    send(m);
    ASSERT_EQ(decisions_.size(), static_cast<std::size_t>(i + 1));
    const std::string where = "keyframe " + std::to_string(i);
    kt::expect_same(expected, decisions_[i], where.c_str());
    window.push_back(ids);
    if (window.size() > config_.window) window.pop_front();
    std::map<std::int64_t, int> views;
    for (const auto& k : window) {
      for (std::int64_t id : k) ++views[id];
    }
    for (const auto& [id, n] : views) {
      if (n >= 2) evaluated.insert(id);
    }
    if (i == 1) {
      const auto e = decisions_[i].evaluated;
      EXPECT_EQ(decisions_[i].kept, static_cast<std::int32_t>(std::floor(0.3 * e + 0.5))) << where;
    }
    for (std::int64_t id : decisions_[i].culled_point_id) culled.insert(id);
    const auto n = static_cast<double>(evaluated.size());
    EXPECT_EQ(evaluated.size() - culled.size(), static_cast<std::size_t>(std::floor(0.3 * n + 0.5))) << where;
  }
  EXPECT_GT(culled.size(), 0u);
  EXPECT_EQ(changed_by_share > 0, GetParam() > 0.0) << changed_by_share << " decisions changed by the share";
}

INSTANTIATE_TEST_SUITE_P(TrackShares, KeepFractionOnMemq, ::testing::Values(0.0, 0.5, 1.0));

}  // namespace
