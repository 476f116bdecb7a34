// libFuzzer: the node's LCM message path (Node::handle_keyframe /
// handle_map_event) on memq://. Building a node costs milliseconds (the
// incremental network's cost tables), so one node serves every input: each
// input starts by taking the window over with publisher ids of its own (the
// node's injected clock is moved past the owner timeout, then a valid empty
// keyframe takes over and the new owner's reset empties the window: fresh
// order, empty window, no remembered culls), and the sparsifier's
// incremental state carries over, which the reference oracle below checks
// too. KEEPLESS_FUZZ_FRESH_NODE=1 builds a fresh node per input instead (to
// reproduce a finding without the history). Oracles beyond "no crash":
//   - a refused message changes no state: the window, the cull memory and
//     the owner's order (a digest of all three) are as before;
//   - every accepted keyframe's decision equals a from-scratch
//     Sparsifier::run() on the window the node must hold (the window before
//     it, or an empty one after a takeover or restart, slid, plus the
//     keyframe minus points culled earlier), and the node's window afterwards
//     is that window minus the culled points;
//   - every decodable keyframe gets exactly one decision, every decodable
//     map event exactly one acknowledgement, each naming its publisher.

#include <lcm/lcm-cpp.hpp>

#include <cstdio>
#include <cstdlib>
#include <memory>
#include <set>
#include <vector>

#include "keepless/core/sparsifier.hpp"
#include "keepless/core/window.hpp"
#include "keepless/decision_t.hpp"
#include "keepless/map_event_ack_t.hpp"
#include "keepless/platform/node.hpp"
#include "keepless/platform/recent_ids.hpp"
#include "keepless/solver/min_cost_flow.hpp"
#include "message_builders.hpp"
#include "node_message_input.hpp"

namespace core = keepless::core;
namespace fz = keepless::fuzz;
using keepless::platform::Node;
using keepless::platform::NodeConfig;

namespace {

void check(bool ok, const char* what) {
  if (ok) return;
  std::fprintf(stderr, "node_message_fuzzer: oracle failed: %s\n", what);
  std::abort();
}

struct Frame {
  core::Keyframe kf;
  std::vector<core::Observation> obs;
};
using Snapshot = std::vector<Frame>;

Snapshot snapshot(const core::Window& w) {
  Snapshot s;
  for (std::uint32_t i = 0; i < w.keyframe_count(); ++i) {
    s.push_back({w.keyframe(i), std::vector<core::Observation>(w.observations(i), w.observations(i) + w.observation_count(i))});
  }
  return s;
}

bool same(const Snapshot& a, const Snapshot& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].kf.id != b[i].kf.id || a[i].obs.size() != b[i].obs.size()) return false;
    for (std::size_t j = 0; j < a[i].obs.size(); ++j) {
      const core::Observation &x = a[i].obs[j], &y = b[i].obs[j];
      if (x.point != y.point || x.u != y.u || x.v != y.v) return false;
    }
  }
  return true;
}

// Everything a refused message must leave alone.
struct Digest {
  Snapshot window;
  std::vector<bool> culled;  // the builders' point ids 0..63
  std::uint32_t culls = 0;
  bool owned = false;
  std::int64_t owner = 0, last_sequence = 0, last_utime = 0;
  std::uint64_t last_heard = 0;
};

Digest digest(const Node& node) {
  Digest d;
  d.window = snapshot(node.window());
  for (std::uint64_t p = 0; p < 64; ++p) d.culled.push_back(node.cull_memory().contains(p));
  d.culls = node.cull_memory().size();
  d.owned = node.order().owned();
  d.owner = node.order().owner();
  d.last_sequence = node.order().last_sequence();
  d.last_utime = node.order().last_utime();
  d.last_heard = node.order().last_heard_ns();
  return d;
}

bool same(const Digest& a, const Digest& b) {
  return same(a.window, b.window) && a.culled == b.culled && a.culls == b.culls && a.owned == b.owned &&
         a.owner == b.owner && a.last_sequence == b.last_sequence && a.last_utime == b.last_utime &&
         a.last_heard == b.last_heard;
}

// The node's clock: moved only by the harness (takeovers need the owner's silence).
struct FuzzClock final : keepless::solver::Clock {
  std::uint64_t now_ns() const override { return now; }
  std::uint64_t now = 1;
};

NodeConfig config() {
  NodeConfig c;
  c.url = "memq://";
  c.window = 4;
  c.max_observations = 16;
  c.max_event_ids = 8;
  c.params.pair_capacity = 3;
  c.latency_target_ms = 0;
  c.cull_memory = 2048;  // > 64 steps x 16 observations: no eviction within one input, the reference mirrors it
  c.quiet = true;
  return c;
}

struct Heard {
  std::vector<keepless::decision_t> decisions;
  std::vector<keepless::map_event_ack_t> acks;
  static void on_decision(const lcm::ReceiveBuffer*, const std::string&, const keepless::decision_t* d, Heard* h) {
    h->decisions.push_back(*d);
  }
  static void on_ack(const lcm::ReceiveBuffer*, const std::string&, const keepless::map_event_ack_t* a, Heard* h) {
    h->acks.push_back(*a);
  }
};

lcm::LCM& bus() {
  static lcm::LCM* b = new lcm::LCM("memq://");
  return *b;
}

void pump() {
  for (int i = 0; i < 100 && bus().handleTimeout(0) > 0; ++i) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static Heard heard;
  static bool subscribed = false;
  const NodeConfig c = config();
  if (!subscribed) {
    bus().subscribeFunction(c.decision_channel, &Heard::on_decision, &heard);
    bus().subscribeFunction(c.event_ack_channel, &Heard::on_ack, &heard);
    subscribed = true;
  }
  static std::unique_ptr<Node> shared;
  static FuzzClock clock;
  static std::int64_t inputs = 0;
  static const bool fresh = std::getenv("KEEPLESS_FUZZ_FRESH_NODE") != nullptr;
  fz::Stream stream;
  if (shared && !fresh) {
    // Ids far from the few an input builds. After the owner's silence a
    // valid keyframe of the new id takes the window over; its reset empties it.
    stream.publisher_base = 0x5eed000000000000 + 4 * ++inputs;
    clock.now += static_cast<std::uint64_t>(c.owner_timeout_s * 1e9) + 1;
    keepless::keyframe_t take = keepless::testing::make_keyframe(-2, 0, {});
    take.utime = 0;
    take.publisher_id = stream.publisher_base;
    keepless::map_event_t reset{};
    reset.sequence = -1;
    reset.reset = true;
    reset.publisher_id = stream.publisher_base;
    const std::vector<std::uint8_t> k = keepless::testing::encode(take);
    const std::vector<std::uint8_t> b = keepless::testing::encode(reset);
    heard.acks.clear();
    shared->handle_keyframe(k.data(), static_cast<std::uint32_t>(k.size()));
    shared->handle_map_event(b.data(), static_cast<std::uint32_t>(b.size()));
    pump();
    check(heard.acks.size() == 1 && heard.acks[0].reset, "the new owner's reset was not honoured");
  }
  if (!shared || fresh) {
    shared = std::make_unique<Node>(bus(), c, &clock);
    stream.publisher_base = 0;
  }
  Node& node = *shared;
  heard.decisions.clear();
  heard.acks.clear();
  check(node.window().keyframe_count() == 0, "the input does not start from an empty window");
  const core::Capacities caps = keepless::platform::window_capacities(c);
  keepless::platform::MessageLimits limits;
  limits.max_observations = c.max_observations;
  limits.max_event_ids = c.max_event_ids;
  std::set<core::PointId> culled;  // the node's memory of culls, mirrored

  fz::Reader r(data, size);
  for (int step = 0; step < 64 && !r.done(); ++step) {
    const Digest before_state = digest(node);
    Snapshot before = before_state.window;
    const std::uint64_t rejected = node.counters().messages_rejected;
    const std::uint64_t restarts = node.order().restarts(), takeovers = node.order().takeovers();
    const std::size_t decisions = heard.decisions.size(), acks = heard.acks.size();
    const fz::Message m = fz::next_message(r, stream);
    if (m.op == fz::kAdvanceClock) {  // the owner falls silent: another id may take over
      clock.now += static_cast<std::uint64_t>(c.owner_timeout_s * 1e9) * static_cast<std::uint64_t>(m.timeouts);
      continue;
    }
    const bool keyframe = m.is_keyframe();
    bool decodable = true;
    std::int64_t event_publisher = 0;
    keepless::keyframe_t kf = m.keyframe;
    if (keyframe) {
      keepless::keyframe_t probe{};
      // The node decodes only what passes the byte checks (a declared count
      // is bounded before decode() can allocate for it).
      decodable = keepless::platform::check_keyframe_bytes(m.bytes.data(), m.bytes.size(), limits) ==
                      keepless::platform::RejectReason::kNone &&
                  probe.decode(m.bytes.data(), 0, static_cast<int>(m.bytes.size())) == static_cast<int>(m.bytes.size());
      if (decodable) kf = probe;
      node.handle_keyframe(m.bytes.data(), static_cast<std::uint32_t>(m.bytes.size()));
    } else {
      keepless::map_event_t probe{};
      decodable = keepless::platform::check_map_event_bytes(m.bytes.data(), m.bytes.size(), limits) ==
                      keepless::platform::RejectReason::kNone &&
                  probe.decode(m.bytes.data(), 0, static_cast<int>(m.bytes.size())) == static_cast<int>(m.bytes.size());
      event_publisher = probe.publisher_id;
      node.handle_map_event(m.bytes.data(), static_cast<std::uint32_t>(m.bytes.size()));
    }
    pump();
    const bool cleared = node.order().restarts() != restarts || node.order().takeovers() != takeovers;
    if (node.counters().messages_rejected != rejected) {
      check(!cleared, "a refused message restarted or took over the stream");
      check(same(before_state, digest(node)), "a refused message changed the window, the culls or the order");
    }
    if (!keyframe) {
      if (decodable) {
        check(heard.acks.size() == acks + 1, "a decodable map event was not acknowledged once");
        check(heard.acks.back().publisher_id == event_publisher, "an ack names another publisher");
      }
      if (heard.acks.size() > acks && heard.acks.back().reset) {
        check(heard.acks.back().status == keepless::map_event_ack_t::STATUS_APPLIED, "a refused event reset the window");
        check(node.window().keyframe_count() == 0, "an ack says reset, the window is not empty");
        culled.clear();  // an accepted reset clears the node's memory too
      }
      continue;
    }
    if (decodable) {
      check(heard.decisions.size() == decisions + 1, "a decodable keyframe was not answered once");
      check(heard.decisions.back().publisher_id == kf.publisher_id, "a decision names another publisher");
    }
    if (heard.decisions.size() == decisions) continue;
    const keepless::decision_t& d = heard.decisions.back();
    if (d.status != keepless::decision_t::STATUS_OPTIMAL) continue;
    if (cleared) {  // a takeover or a restart: the old window and culls are gone
      before.clear();
      culled.clear();
    }

    // The reference: the window before, slid, plus the keyframe minus culled points.
    Snapshot expected = before;
    if (expected.size() == c.window) expected.erase(expected.begin());
    Frame f;
    f.kf.id = static_cast<core::KeyframeId>(kf.keyframe_id);
    std::copy(kf.centre, kf.centre + 3, f.kf.centre);
    std::copy(kf.orientation, kf.orientation + 4, f.kf.orientation);
    for (int i = 0; i < kf.num_observations; ++i) {
      const auto p = static_cast<core::PointId>(kf.point_id[i]);
      if (culled.count(p) == 0) f.obs.push_back({p, static_cast<double>(kf.u[i]), static_cast<double>(kf.v[i])});
    }
    expected.push_back(f);
    core::Window w(caps);
    for (const Frame& fr : expected) {
      check(w.add_keyframe(fr.kf, fr.obs.data(), static_cast<std::uint32_t>(fr.obs.size())) == core::Status::kOk,
            "reference window refused an accepted keyframe");
    }
    core::Sparsifier s(caps, c.params);
    check(s.run(w) == core::Status::kOk, "reference solve failed");
    std::vector<std::int64_t> want;
    for (std::uint32_t i = 0; i < s.decision_count(); ++i) {
      if (s.decisions()[i].verdict == core::Verdict::kCull) want.push_back(static_cast<std::int64_t>(s.decisions()[i].point));
    }
    check(d.culled_point_id == want, "decision differs from a from-scratch run");
    for (std::int64_t p : want) culled.insert(static_cast<core::PointId>(p));
    for (Frame& fr : expected) {
      std::vector<core::Observation> kept;
      for (const core::Observation& o : fr.obs) {
        if (culled.count(o.point) == 0) kept.push_back(o);
      }
      fr.obs = kept;
    }
    check(same(expected, snapshot(node.window())), "window after the decision differs from the reference");
  }
  return 0;
}
