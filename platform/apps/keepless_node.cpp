// keepless_node: the onboard sparsifier. Subscribes to the VO's keyframe_t and
// map_event_t channels, keeps a sliding window of the last K keyframes, and
// answers every keyframe with a decision_t (culled point ids). See docs/node.md.

#include <lcm/lcm-cpp.hpp>

#include <cerrno>
#include <csignal>
#include <cstring>
#include <cstdio>
#include <memory>
#include <new>
#include <stdexcept>
#include <string>

#include "cli/cli.hpp"
#include "keepless/core/sparsifier.hpp"
#include "keepless/platform/cpu_pinning.hpp"
#include "keepless/core/deferred_culls.hpp"
#include "keepless/platform/node.hpp"
#include "keepless/platform/recent_ids.hpp"
#include "keepless/platform/node_config.hpp"

namespace {

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

}  // namespace

int main(int argc, char** argv) {
  using namespace keepless;
  platform::NodeConfig config;
  std::string error;
  switch (platform::parse_node_arguments(argc, argv, config, error)) {
    case platform::ParseResult::kHelp:
      std::fputs(platform::node_usage().c_str(), stdout);
      return 0;
    case platform::ParseResult::kVersion:
      return cli::print_version("keepless_node");
    case platform::ParseResult::kError:
      return cli::usage_error("keepless_node", error);
    case platform::ParseResult::kOk:
      break;
  }
  if (core::Sparsifier::validate(config.params) != core::Status::kOk) {
    std::fprintf(stderr, "keepless_node: invalid parameters (M >= 1, 0 <= theta <= 1, box >= 0)\n");
    return 2;
  }

  // Real-time set-up is best effort: report what the OS refused, keep going.
  if (!config.cpus.empty()) {
    const platform::PinResult pin = platform::pin_to_cpus(config.cpus);
    if (pin.ok) {
      std::fprintf(stderr, "keepless_node: pinned to CPUs %s\n", pin.granted.c_str());
    } else {
      std::fprintf(stderr, "keepless_node: could not pin to CPUs %s (%s); running on %s\n", config.cpus.c_str(),
                   pin.error.c_str(), pin.granted.c_str());
    }
  }

  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);

  lcm::LCM bus(config.url);
  if (!bus.good()) {
    std::fprintf(stderr, "keepless_node: cannot open LCM URL '%s'\n", config.url.c_str());
    return 1;
  }
  // The fixed memory is checked against the limit before it is allocated, in
  // the MB (10^6 bytes) the start line and the docs print it in.
  const double need = platform::estimate_node_bytes(config);
  if (need > static_cast<double>(config.max_memory_mb) * 1e6) {
    std::fprintf(stderr,
                 "keepless_node: these flags need about %.1f MB of fixed memory, above --max-memory-mb %llu "
                 "(lower --window, --max-observations, --max-points, --max-window-observations or --max-pair-arcs, "
                 "or use --profile small)\n",
                 need / 1e6, static_cast<unsigned long long>(config.max_memory_mb));
    return 2;
  }
  const auto cannot_allocate = [need] {
    std::fprintf(stderr, "keepless_node: cannot allocate the fixed memory (about %.1f MB) for these flags\n",
                 need / 1e6);
    return 2;
  };
  std::unique_ptr<platform::Node> owned;
  try {
    owned = std::make_unique<platform::Node>(bus, config);
  } catch (const std::bad_alloc&) {
    return cannot_allocate();
  } catch (const std::length_error&) {  // 32-bit: an array larger than the address space
    return cannot_allocate();
  }
  platform::Node& node = *owned;
  if (!node.start()) {
    std::fprintf(stderr, "keepless_node: cannot subscribe on '%s'\n", config.url.c_str());
    return 1;
  }
  // Lock after everything is allocated, so the locked set is the working set.
  if (config.mlock) {
    const platform::LockResult lock = platform::lock_memory();
    if (lock.ok) {
      std::fprintf(stderr, "keepless_node: memory locked\n");
    } else {
      std::fprintf(stderr, "keepless_node: mlockall refused (%s); running unlocked\n", lock.error.c_str());
    }
  }
  const core::Capacities caps = platform::window_capacities(config);
  std::fprintf(stderr,
               "keepless_node: %s  in %s,%s  out %s,%s,%s,%s  window %u keyframes, %u obs/keyframe, "
               "capacity %u points %u observations %u pair arcs, %.1f MB fixed (%.1f MB predicted), largest decision "
               "%zu bytes\n",
               config.url.c_str(), config.keyframe_channel.c_str(), config.event_channel.c_str(),
               config.decision_channel.c_str(), config.event_ack_channel.c_str(), config.timing_channel.c_str(),
               config.status_channel.c_str(), config.window, config.max_observations, caps.max_points,
               caps.max_observations, caps.max_pair_arcs,
               static_cast<double>(node.memory_bytes()) / 1e6, need / 1e6, node.max_decision_bytes());
  // The capacities status_t does not carry, fixed from here on.
  std::fprintf(stderr,
               "keepless_node: also fixed: cull memory %u ids, deferred %u points, %u unmapped keypoints/keyframe, "
               "%u ids per map-event list, LCM queue %u messages per channel\n",
               node.cull_memory().capacity(), node.deferred_culls().capacity(), config.max_unmapped,
               config.max_event_ids, config.queue_capacity);

  while (!g_stop && !node.finished()) {
    if (node.spin_once(100) < 0) {
      if (g_stop || errno == EINTR) continue;  // a signal interrupted the wait
      std::fprintf(stderr, "keepless_node: LCM error (%s), exiting\n", std::strerror(errno));
      break;
    }
  }
  node.publish_status(true);
  const platform::NodeCounters& c = node.counters();
  std::fprintf(stderr,
               "keepless_node: %s after %llu keyframes, %llu map events, %llu decisions (%llu skipped), "
               "%llu rejected, %llu sequence gaps, latency p50 %.3f ms p99 %.3f ms max %.3f ms\n",
               g_stop ? "stopped by signal" : "done", static_cast<unsigned long long>(c.keyframes_received),
               static_cast<unsigned long long>(c.map_events_received),
               static_cast<unsigned long long>(c.decisions_published),
               static_cast<unsigned long long>(c.keyframes_skipped),
               static_cast<unsigned long long>(c.messages_rejected),
               static_cast<unsigned long long>(node.order().sequence_gaps()), node.latency().quantile(0.5) / 1e6,
               node.latency().quantile(0.99) / 1e6, static_cast<double>(node.latency().max()) / 1e6);
  return 0;
}
