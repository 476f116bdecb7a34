#pragma once
// The node on memq:// in one process: a bus, the node, and the decisions,
// acknowledgements and statuses it publishes, collected for assertions.

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <memory>
#include <string>
#include <vector>

#include "keepless/decision_t.hpp"
#include "keepless/map_event_ack_t.hpp"
#include "keepless/platform/node.hpp"
#include "keepless/solver/min_cost_flow.hpp"
#include "keepless/status_t.hpp"
#include "message_builders.hpp"

namespace keepless::testing {

using keepless::platform::Node;
using keepless::platform::NodeConfig;
using keepless::platform::RejectReason;
namespace kt = keepless::testing;

struct WindowSnapshot {
  struct Obs {
    std::uint64_t point;
    double u, v;
    bool operator==(const Obs& o) const { return point == o.point && u == o.u && v == o.v; }
  };
  std::vector<std::uint64_t> ids;
  std::vector<std::vector<Obs>> obs;
  bool operator==(const WindowSnapshot& o) const { return ids == o.ids && obs == o.obs; }
};

inline WindowSnapshot snapshot(const keepless::core::Window& w) {
  WindowSnapshot s;
  for (std::uint32_t i = 0; i < w.keyframe_count(); ++i) {
    s.ids.push_back(w.keyframe(i).id);
    std::vector<WindowSnapshot::Obs> o;
    for (std::uint32_t j = 0; j < w.observation_count(i); ++j) {
      o.push_back({w.observations(i)[j].point, w.observations(i)[j].u, w.observations(i)[j].v});
    }
    s.obs.push_back(o);
  }
  return s;
}

// The node's injected clock: every reading advances it by `tick` ns, so
// latencies are non-zero and deterministic; tests move it on with advance().
struct TickingClock final : keepless::solver::Clock {
  std::uint64_t now_ns() const override { return now += tick; }
  void advance(std::uint64_t ns) { now += ns; }
  mutable std::uint64_t now = 1000000000ull;
  std::uint64_t tick = 1000;  // 1 us a reading
};

class NodeOnMemq : public ::testing::Test {
 protected:
  void SetUp() override { make_node(default_config()); }

  static NodeConfig default_config() {
    NodeConfig c;
    c.url = "memq://";
    c.latency_target_ms = 0;  // decisions compared with the library must not depend on timing
    c.window = 4;
    c.max_observations = 64;
    c.max_event_ids = 16;
    c.params.pair_capacity = 5;  // small M so windows cull something
    c.status_period_ms = 3600 * 1000;
    c.quiet = true;
    return c;
  }

  void make_node(const NodeConfig& c) {
    config_ = c;
    node_.reset();
    bus_ = std::make_unique<lcm::LCM>("memq://");
    ASSERT_TRUE(bus_->good());
    clock_ = TickingClock{};
    node_ = std::make_unique<Node>(*bus_, config_, &clock_);
    ASSERT_TRUE(node_->start());
    decisions_.clear();
    statuses_.clear();
    acks_.clear();
    // subscribeFunction, not the member-function subscribe: GCC's UBSan
    // misreports LCM's pointer-to-member call in lcm-cpp-impl.hpp.
    bus_->subscribeFunction(config_.decision_channel, &NodeOnMemq::on_decision, this);
    bus_->subscribeFunction(config_.status_channel, &NodeOnMemq::on_status, this);
    bus_->subscribeFunction(config_.event_ack_channel, &NodeOnMemq::on_ack, this);
  }
  static void on_ack(const lcm::ReceiveBuffer*, const std::string&, const keepless::map_event_ack_t* a,
                     NodeOnMemq* self) {
    self->acks_.push_back(*a);
  }

  static void on_decision(const lcm::ReceiveBuffer*, const std::string&, const keepless::decision_t* d,
                          NodeOnMemq* self) {
    self->decisions_.push_back(*d);
  }
  static void on_status(const lcm::ReceiveBuffer*, const std::string&, const keepless::status_t* s,
                        NodeOnMemq* self) {
    self->statuses_.push_back(*s);
  }

  void pump() {
    for (int i = 0; i < 1000 && bus_->handleTimeout(0) > 0; ++i) {
    }
  }
  void send_bytes(const std::string& channel, const std::vector<std::uint8_t>& bytes) {
    bus_->publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
    pump();
  }
  void send(const keepless::keyframe_t& m) { send_bytes(config_.keyframe_channel, kt::encode(m)); }
  void send(keepless::map_event_t e) {
    kt::finalize(e);
    send_bytes(config_.event_channel, kt::encode(e));
  }

  // Three overlapping keyframes, sequences 1..3, ids 10..12.
  void fill() {
    send(kt::make_keyframe(1, 10, kt::id_range(0, 30)));
    send(kt::make_keyframe(2, 11, kt::id_range(10, 30)));
    send(kt::make_keyframe(3, 12, kt::id_range(20, 30)));
    ASSERT_EQ(node_->window().keyframe_count(), 3u);
    ASSERT_EQ(decisions_.size(), 3u);
    ASSERT_EQ(node_->counters().messages_rejected, 0u);
  }

  // fill() on a node that culls nothing (M = 100): map-event edits alone
  // shape the window.
  void fill_without_culling() {
    NodeConfig c = default_config();
    c.params.pair_capacity = 100;
    make_node(c);
    fill();  // 10: 0..29, 11: 10..39, 12: 20..49
  }

  std::uint64_t rejected(RejectReason r) const { return node_->counters().rejected[static_cast<int>(r)]; }

  // The bad message was counted under `r` alone and the window is as before;
  // the next valid keyframe is still accepted.
  void expect_rejected_only(RejectReason r, const WindowSnapshot& before) {
    EXPECT_EQ(rejected(r), 1u) << to_string(r);
    EXPECT_EQ(node_->counters().messages_rejected, 1u);
    EXPECT_TRUE(snapshot(node_->window()) == before) << "window changed";
    const std::size_t decisions_before = decisions_.size();
    send(kt::make_keyframe(100, 50, kt::id_range(25, 30)));
    ASSERT_EQ(decisions_.size(), decisions_before + 1);
    EXPECT_EQ(decisions_.back().status, keepless::decision_t::STATUS_OPTIMAL);
    EXPECT_EQ(decisions_.back().keyframe_id, 50);
    EXPECT_EQ(node_->window().find_keyframe(50), 3);
  }

  NodeConfig config_;
  TickingClock clock_;
  std::unique_ptr<lcm::LCM> bus_;
  std::unique_ptr<Node> node_;
  std::vector<keepless::decision_t> decisions_;
  std::vector<keepless::status_t> statuses_;
  std::vector<keepless::map_event_ack_t> acks_;
};

}  // namespace keepless::testing
