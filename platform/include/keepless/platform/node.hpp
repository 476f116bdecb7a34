#pragma once
// keepless_node's loop body: receives keyframe_t / map_event_t as raw LCM
// buffers, validates them before they touch the window, slides the window,
// updates the sparsifier (Sparsifier::update: the previous window's network
// edited in place, run()'s decisions), publishes decision_t
// (+ decision_timing_t), answers map events with map_event_ack_t, and
// publishes a periodic status_t. Everything is allocated in
// the constructor; handling a message allocates nothing (LCM's own C library
// aside).

#include <cstddef>
#include <cstdint>
#include <memory>

#include "keepless/core/deferred_culls.hpp"
#include "keepless/core/window.hpp"
#include "keepless/platform/latency_histogram.hpp"
#include "keepless/platform/message_validation.hpp"
#include "keepless/platform/node_config.hpp"

namespace lcm {
class LCM;
}
namespace keepless::solver {
class Clock;
}

namespace keepless::platform {

class RecentIds;

struct NodeCounters {
  std::uint64_t keyframes_received = 0;
  std::uint64_t map_events_received = 0;
  std::uint64_t messages_rejected = 0;
  std::uint64_t rejected[kRejectReasonCount] = {};
  std::uint64_t decisions_published = 0;
  std::uint64_t budget_exhaustions = 0;
  std::uint64_t capacity_exceeded = 0;
  std::uint64_t large_decisions = 0;  // above one LCM datagram
  std::uint64_t points_culled = 0;
  std::uint64_t keyframes_skipped = 0;    // answered STATUS_SKIPPED
  std::uint64_t not_owner = 0;            // refused: another publisher owns the window
  std::uint64_t stale_observations = 0;   // observations of recently culled points dropped
  std::uint64_t event_items_refused = 0;  // map-event items refused (acknowledged)
  // Deferred culling (--defer T): points excluded, points deleted, and
  // observations of excluded points kept out of the window.
  std::uint64_t points_excluded = 0;
  std::uint64_t points_deleted = 0;
  std::uint64_t deferred_observations = 0;
  // --cost track: accepted keyframes without point quality (num_quality 0),
  // priced by the window's connectivity alone.
  std::uint64_t track_fallback = 0;
};

class Node {
 public:
  // Sizes everything from `config`. `lcm` must outlive the node. `clock`
  // (tests): arrival stamps, deadlines, latencies and the owner timeout read
  // it instead of CLOCK_MONOTONIC; it must outlive the node.
  Node(lcm::LCM& lcm, const NodeConfig& config, const solver::Clock* clock = nullptr);
  ~Node();
  Node(const Node&) = delete;
  Node& operator=(const Node&) = delete;

  // Subscribes the two input channels; false if LCM is not usable.
  [[nodiscard]] bool start();
  // Handles messages for at most timeout_ms and publishes a status when due.
  // Returns <0 on an LCM error.
  int spin_once(int timeout_ms);
  void publish_status(bool final);
  // --max-keyframes reached.
  bool finished() const;

  // The handlers behind the subscriptions (public for tests), outside a
  // drain: a keyframe is decided at once. Arrival is the clock's now.
  void handle_keyframe(const void* data, std::uint32_t size);
  void handle_map_event(const void* data, std::uint32_t size);

  const core::Window& window() const;
  const NodeCounters& counters() const;
  const LatencyHistogram& latency() const;
  const OrderTracker& order() const;
  const RecentIds& cull_memory() const;
  const core::DeferredCulls& deferred_culls() const;
  std::size_t memory_bytes() const;
  // Largest decision_t this node can publish, bytes.
  std::size_t max_decision_bytes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace keepless::platform
