#pragma once
// keepless_node's configuration: LCM URL and channels, window size, message
// limits, paper parameters, real-time options. Every capacity of the node is
// derived from it once, at start.

#include <cstdint>
#include <limits>
#include <string>

#include "keepless/core/config.hpp"
#include "keepless/platform/message_validation.hpp"

namespace keepless::platform {

struct NodeConfig {
  std::string url = "udpm://239.255.76.67:7667?ttl=0";  // ttl=0: this host only
  std::string keyframe_channel = "KEEPLESS_KEYFRAME";
  std::string event_channel = "KEEPLESS_MAP_EVENT";
  std::string decision_channel = "KEEPLESS_DECISION";
  std::string timing_channel = "KEEPLESS_DECISION_TIMING";
  std::string status_channel = "KEEPLESS_STATUS";
  std::string event_ack_channel = "KEEPLESS_MAP_EVENT_ACK";  // map_event_ack_t output

  // The window's capacities: the default profile (profile_config below).
  // points, observations and pair arcs are over the whole window, sized from
  // measured real windows; 0 takes the worst case of K full keyframes. A
  // window beyond one is answered STATUS_CAPACITY_EXCEEDED.
  std::uint32_t window = 20;               // K: keyframes in the window (ORB-SLAM2-sized local map)
  std::uint32_t max_observations = 2000;   // per keyframe_t; larger messages are refused unread
  std::uint32_t max_event_ids = 1024;      // per list of a map_event_t
  std::uint32_t max_unmapped = 0;          // unmapped keypoints per keyframe_t (cost authors); more: refused
  std::uint32_t max_points = 6600;         // distinct points in the window
  std::uint32_t max_window_observations = 19100;  // observations in the window
  std::uint32_t max_pair_arcs = 51000;     // point -> pair arcs (sum over points of n(n-1)/2)
  // Refused at start (exit 2) when the fixed memory would exceed it.
  std::uint64_t max_memory_mb = 1024;

  // Stream-order policy (message_validation.hpp, OrderTracker).
  std::uint64_t max_sequence_jump = 1000000;  // messages
  double max_utime_jump_s = 600;
  std::uint32_t restart_confirm = 3;  // valid keyframes back near the start that are a restart
  // Another publisher id takes the window over only after its owner has been
  // silent this long; 0: never.
  double owner_timeout_s = 1.0;
  // Culled point ids remembered (a keyframe already in flight cannot bring
  // them back); 0: the window's point capacity.
  std::uint32_t cull_memory = 0;
  // Deferred culling (params.defer_keyframes = T > 0, --defer T): excluded
  // points held until the rule deletes them; 0: the window's point capacity.
  std::uint32_t defer_memory = 0;

  core::Params params;  // M, theta, box, scope, floor, cost model
  std::uint64_t budget_work_units = std::numeric_limits<std::uint64_t>::max();
  // Deadline per decision, from the keyframe's arrival; 0: none. A deadline
  // that fires makes that decision depend on timing (it culls nothing), so
  // byte-for-byte replays run with 0.
  double latency_target_ms = 5.0;

  std::string cpus;  // e.g. "0,1"; empty: leave affinity alone
  bool mlock = false;
  std::uint32_t queue_capacity = 256;  // messages LCM holds per input channel while the node is busy
  std::uint32_t status_period_ms = 1000;
  std::uint64_t max_keyframes = 0;  // exit after this many decisions; 0: run until signalled
  bool quiet = false;               // no per-reject log lines
};

enum class ParseResult : std::uint8_t { kOk = 0, kHelp, kError, kVersion };

// Parses keepless_node's flags into `config` (defaults kept for absent flags).
// On kError, `error` says which flag and why.
[[nodiscard]] ParseResult parse_node_arguments(int argc, const char* const* argv,
                                               NodeConfig& config, std::string& error);
std::string node_usage();

OrderBounds order_bounds(const NodeConfig& config);

// The window's fixed capacities for `config`: max_points,
// max_window_observations and max_pair_arcs, or where 0 the worst case of K
// full keyframes (every observation a distinct point; for pair arcs, every
// point in every keyframe).
core::Capacities window_capacities(const NodeConfig& config);

// Named capacity sets (--profile): "small", "default", "large". Sets the
// window, the per-message limits and the window's capacities of `config`
// (nothing else); false for another name.
[[nodiscard]] bool apply_profile(const std::string& name, NodeConfig& config);

// The node's fixed memory for `config`, predicted before allocating it
// (memory_estimate.hpp: the window pair, the sparsifier, the message buffers
// and the cull memory); keepless_node refuses to start above --max-memory-mb.
double estimate_node_bytes(const NodeConfig& config);

}  // namespace keepless::platform
