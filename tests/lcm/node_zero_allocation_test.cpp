// The node's receive path allocates nothing in steady state: after a warm-up,
// a counting global operator new (replaced for this binary only) sees zero
// calls while keyframes, map events, rejected messages and statuses go
// through LCM (memq://) into the node and decisions come out.

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "counting_new.hpp"  // this binary's only inclusion
#include "keepless/platform/node.hpp"
#include "message_builders.hpp"

namespace {

namespace kt = keepless::testing;

// The node every test here runs: small capacities on memq://, quiet, and no
// status timer (a status is published by hand where a test wants one).
keepless::platform::NodeConfig small_node(double latency_target_ms) {
  keepless::platform::NodeConfig c;
  c.latency_target_ms = latency_target_ms;
  c.url = "memq://";
  c.window = 5;
  c.max_observations = 128;
  c.max_event_ids = 32;
  c.quiet = true;
  c.status_period_ms = 3600 * 1000;
  return c;
}

// memq:// delivers in handleTimeout: every queued message is handled (by the node) here.
void pump(lcm::LCM& bus) {
  while (bus.handleTimeout(0) > 0) {
  }
}

void publish(lcm::LCM& bus, const std::string& channel, const std::vector<std::uint8_t>& bytes) {
  bus.publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
  pump(bus);
}

// `defer`: deferred culling's T (0: off); `defer_memory`: its capacity (0: the window's points).
void steady_state(std::uint32_t defer, std::uint32_t defer_memory = 0) {
  keepless::platform::NodeConfig c = small_node(0);
  c.params.defer_keyframes = defer;
  c.defer_memory = defer_memory;
  c.params.pair_capacity = 8;
  c.max_unmapped = 16;
  lcm::LCM bus(c.url);
  ASSERT_TRUE(bus.good());
  keepless::platform::Node node(bus, c);
  ASSERT_TRUE(node.start());

  // Every message encoded up front.
  std::vector<std::vector<std::uint8_t>> keyframes, events, bad;
  std::int64_t seq = 0;
  for (int i = 0; i < 40; ++i) {
    keepless::keyframe_t m = kt::make_keyframe(++seq, i, kt::id_range(i * 10, 100 + (i % 3) * 10));
    if (i % 2 == 1) {  // the optional arrays decode into reserved vectors too
      m.num_depths = m.num_observations;
      m.depth.assign(static_cast<std::size_t>(m.num_observations), 2.5f);
      m.num_intrinsics = 4;
      m.intrinsics = {500.0, 500.0, 320.0, 240.0};
      m.num_unmapped = 16;
      m.unmapped_u.assign(16, 100.0f);
      m.unmapped_v.assign(16, 200.0f);
    }
    keyframes.push_back(kt::encode(m));
    keepless::map_event_t e = kt::make_event(++seq);
    e.deleted_point_id = {i * 10 + 1, i * 10 + 2};
    e.merged_from_id = {i * 10 + 5};
    e.merged_into_id = {i * 10 + 4};
    kt::finalize(e);
    events.push_back(kt::encode(e));
  }
  keepless::keyframe_t nan = kt::make_keyframe(1, 999, kt::id_range(0, 10));
  nan.centre[0] = std::numeric_limits<double>::quiet_NaN();
  bad.push_back(kt::encode(nan));
  bad.push_back(kt::encode(kt::make_keyframe(1, 998, kt::id_range(0, 129))));
  std::vector<std::uint8_t> truncated = kt::encode(kt::make_keyframe(1, 997, kt::id_range(0, 10)));
  truncated.resize(truncated.size() - 3);
  bad.push_back(truncated);

  auto step = [&](int i) {
    publish(bus, c.keyframe_channel, keyframes[i]);
    publish(bus, c.event_channel, events[i]);
    publish(bus, c.keyframe_channel, bad[static_cast<std::size_t>(i) % bad.size()]);
  };
  // Warm-up: fill the window, touch every path once.
  for (int i = 0; i < 10; ++i) step(i);
  node.publish_status(false);
  pump(bus);
  ASSERT_EQ(node.window().keyframe_count(), 5u);

  keepless::test::AllocationCounter counter;
  for (int i = 10; i < 40; ++i) step(i);
  node.publish_status(false);
  pump(bus);
  const std::uint64_t allocations = counter.stop();

  EXPECT_EQ(allocations, 0u);
  EXPECT_EQ(node.counters().decisions_published, 40u + 14u);  // the 14 decodable bad ones are answered too
  EXPECT_EQ(node.counters().messages_rejected, 40u);
  if (defer == 0) {
    EXPECT_GT(node.counters().points_culled, 0u);
  } else {
    EXPECT_EQ(node.counters().points_culled, 0u);
    EXPECT_GT(node.counters().points_excluded, 0u);
    EXPECT_GT(node.counters().points_deleted, 0u);
    if (defer_memory > 0) {
      EXPECT_GT(node.deferred_culls().refused(), 0u);
    }
  }
}

TEST(NodeZeroAllocation, SteadyStateReceivePathAllocatesNothing) { steady_state(0); }

// Deferred culling: excluding, observing excluded points, expiring, and map
// events that delete or merge them.
TEST(NodeZeroAllocation, DeferredCullingAllocatesNothing) { steady_state(2); }
// ... and with a memory so small that excluded points are refused (deleted at once).
TEST(NodeZeroAllocation, AFullDeferredMemoryAllocatesNothing) { steady_state(6, 4); }

// The drain (a latency target on): queued keyframes, map events and refused
// messages handled by spin_once, pending keyframes skipped or decided, with
// no allocation either.
TEST(NodeZeroAllocation, TheDrainAllocatesNothing) {
  keepless::platform::NodeConfig c = small_node(60000);  // drains, never fires
  c.params.pair_capacity = 8;
  lcm::LCM bus(c.url);
  ASSERT_TRUE(bus.good());
  keepless::platform::Node node(bus, c);
  ASSERT_TRUE(node.start());
  std::vector<std::vector<std::uint8_t>> messages;  // keyframe, keyframe, event, junk: one round each
  std::int64_t seq = 0;
  for (int i = 0; i < 40; ++i) {
    messages.push_back(kt::encode(kt::make_keyframe(++seq, 2 * i, kt::id_range(i * 10, 100))));
    messages.push_back(kt::encode(kt::make_keyframe(++seq, 2 * i + 1, kt::id_range(i * 10 + 5, 100))));
    keepless::map_event_t e = kt::make_event(++seq);
    e.deleted_point_id = {i * 10 + 1};
    kt::finalize(e);
    messages.push_back(kt::encode(e));
  }
  const std::vector<std::uint8_t> junk = {1, 2, 3};
  auto round = [&](int i) {
    for (int j = 0; j < 3; ++j) {
      const auto& m = messages[static_cast<std::size_t>(3 * i + j)];
      bus.publish(j < 2 ? c.keyframe_channel : c.event_channel, m.data(), static_cast<unsigned>(m.size()));
    }
    bus.publish(c.keyframe_channel, junk.data(), static_cast<unsigned>(junk.size()));
    while (node.spin_once(0) > 0) {
    }
  };
  for (int i = 0; i < 10; ++i) round(i);
  keepless::test::AllocationCounter counter;
  for (int i = 10; i < 40; ++i) round(i);
  const std::uint64_t allocations = counter.stop();
  EXPECT_EQ(allocations, 0u);
  EXPECT_EQ(node.counters().keyframes_skipped, 40u) << "the first of each pair is superseded by the second";
  EXPECT_EQ(node.counters().decisions_published, 80u);
}

// A window beyond a capacity is answered STATUS_CAPACITY_EXCEEDED on the same
// preallocated memory: older keyframes evicted to make room for the window's
// points and observations (SlidingWindow::push's retries), or a window whose
// network needs more pair arcs than held, left undecided.
void beyond_capacity(std::uint32_t max_points, std::uint32_t max_window_observations, std::uint32_t max_pair_arcs,
                     std::int64_t shift) {
  keepless::platform::NodeConfig c = small_node(0);
  c.max_points = max_points;
  c.max_window_observations = max_window_observations;
  c.max_pair_arcs = max_pair_arcs;
  // Every pair carries all its shared points and keeps them (theta 0): nothing
  // is culled, so the window fills up.
  c.params.pair_capacity = 100;
  c.params.theta = 0.0;
  lcm::LCM bus(c.url);
  ASSERT_TRUE(bus.good());
  keepless::platform::Node node(bus, c);
  ASSERT_TRUE(node.start());
  std::vector<std::vector<std::uint8_t>> keyframes;
  for (int i = 0; i < 40; ++i) {
    // Every third keyframe crowded (all new points), the others overlapping the last.
    const std::int64_t count = i % 3 == 2 ? 128 : 100;
    keyframes.push_back(kt::encode(kt::make_keyframe(i + 1, i, kt::id_range(i * shift, count))));
  }
  for (int i = 0; i < 10; ++i) publish(bus, c.keyframe_channel, keyframes[i]);
  node.publish_status(false);
  pump(bus);
  const std::uint64_t before = node.counters().capacity_exceeded;
  ASSERT_GT(before, 0u) << "the warm-up should have met the capacity: decisions "
                         << node.counters().decisions_published << ", rejected " << node.counters().messages_rejected
                         << ", culled " << node.counters().points_culled;
  keepless::test::AllocationCounter counter;
  for (int i = 10; i < 40; ++i) publish(bus, c.keyframe_channel, keyframes[i]);
  node.publish_status(false);
  pump(bus);
  const std::uint64_t allocations = counter.stop();
  EXPECT_EQ(allocations, 0u);
  EXPECT_GT(node.counters().capacity_exceeded, before + 5);
  EXPECT_EQ(node.counters().decisions_published, 40u);
}

TEST(NodeZeroAllocation, EvictionsBeyondTheWindowsPointsAllocateNothing) { beyond_capacity(250, 400, 51000, 60); }
TEST(NodeZeroAllocation, AWindowBeyondItsPairArcsAllocatesNothing) { beyond_capacity(6600, 2000, 400, 10); }

}  // namespace
