// libFuzzer: the node's LCM message path (Node::handle_keyframe /
// handle_map_event) on memq://. Building a node costs milliseconds (the
// incremental network's cost tables), so one node serves every input: each
// input starts with an accepted reset from publisher ids of its own (fresh
// order state, empty window, no remembered culls), and the sparsifier's
// incremental state carries over, which the reference oracle below checks
// too. KEEPLESS_FUZZ_FRESH_NODE=1 builds a fresh node per input instead (to
// reproduce a finding without the history). Oracles beyond "no crash":
//   - a rejected message leaves the window exactly as it was;
//   - every accepted keyframe's decision equals a from-scratch
//     Sparsifier::run() on the window the node must hold (the window before
//     it, slid, plus the keyframe minus points culled earlier), and the
//     node's window afterwards is that window minus the culled points;
//   - every decodable keyframe gets exactly one decision, every decodable
//     map event exactly one acknowledgement.

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
  static std::int64_t inputs = 0;
  static const bool fresh = std::getenv("KEEPLESS_FUZZ_FRESH_NODE") != nullptr;
  fz::Stream stream;
  if (shared && !fresh) {
    // Ids far from the few an input builds (a bit flip can still forge one:
    // then the node rightly refuses the reset as stale, and a fresh node is built).
    stream.publisher_base = 0x5eed000000000000 + 4 * ++inputs;
    keepless::map_event_t reset{};
    reset.reset = true;
    reset.publisher_id = stream.publisher_base;
    const std::vector<std::uint8_t> b = keepless::testing::encode(reset);
    heard.acks.clear();
    shared->handle_map_event(b.data(), static_cast<std::uint32_t>(b.size()));
    pump();
    const bool reset_done = heard.acks.size() == 1 && heard.acks[0].status == keepless::map_event_ack_t::STATUS_APPLIED;
    if (!reset_done) shared.reset();
  }
  if (!shared || fresh) {
    shared = std::make_unique<Node>(bus(), c);
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
  bool mirrored = true;            // false after a restart (the node may have cleared it)

  fz::Reader r(data, size);
  for (int step = 0; step < 64 && !r.done(); ++step) {
    const Snapshot before = snapshot(node.window());
    const std::uint64_t rejected = node.counters().messages_rejected;
    const std::uint64_t restarts = node.order().restarts();
    const std::size_t decisions = heard.decisions.size(), acks = heard.acks.size();
    const std::uint8_t op = r.u8() % fz::kOpCount;
    bool keyframe = false, decodable = true;
    keepless::keyframe_t kf{};
    if (op == fz::kKeyframe || op == fz::kFlippedKeyframe || op == fz::kRawKeyframe) {
      keyframe = true;
      std::vector<std::uint8_t> bytes;
      if (op == fz::kRawKeyframe) {
        std::size_t n = 0;
        const std::uint8_t* raw = r.rest(&n);
        bytes.assign(raw, raw + n);
      } else {
        kf = fz::build_keyframe(r, stream);
        bytes = keepless::testing::encode(kf);
        if (op == fz::kFlippedKeyframe && !bytes.empty()) bytes[r.u8() % bytes.size()] ^= static_cast<std::uint8_t>(1u << (r.u8() % 8));
      }
      keepless::keyframe_t probe{};
      // The node decodes only what passes the byte checks (a declared count
      // is bounded before decode() can allocate for it).
      decodable = keepless::platform::check_keyframe_bytes(bytes.data(), bytes.size(), limits) ==
                      keepless::platform::RejectReason::kNone &&
                  probe.decode(bytes.data(), 0, static_cast<int>(bytes.size())) == static_cast<int>(bytes.size());
      if (decodable) kf = probe;
      node.handle_keyframe(bytes.data(), static_cast<std::uint32_t>(bytes.size()));
    } else {
      keepless::map_event_t e = fz::build_map_event(r, stream);
      std::vector<std::uint8_t> bytes = keepless::testing::encode(e);
      if (op == fz::kFlippedMapEvent && !bytes.empty()) bytes[r.u8() % bytes.size()] ^= static_cast<std::uint8_t>(1u << (r.u8() % 8));
      keepless::map_event_t probe{};
      decodable = keepless::platform::check_map_event_bytes(bytes.data(), bytes.size(), limits) ==
                      keepless::platform::RejectReason::kNone &&
                  probe.decode(bytes.data(), 0, static_cast<int>(bytes.size())) == static_cast<int>(bytes.size());
      node.handle_map_event(bytes.data(), static_cast<std::uint32_t>(bytes.size()));
    }
    pump();
    const bool restarted = node.order().restarts() != restarts;
    if (restarted) mirrored = false;
    if (node.counters().messages_rejected != rejected && !restarted) {
      check(same(before, snapshot(node.window())), "a rejected message changed the window");
    }
    if (!keyframe) {
      if (decodable) check(heard.acks.size() == acks + 1, "a decodable map event was not acknowledged once");
      if (heard.acks.size() > acks && heard.acks.back().reset &&
          heard.acks.back().status == keepless::map_event_ack_t::STATUS_APPLIED) {
        culled.clear();  // an accepted reset clears the node's memory too
        mirrored = true;
      }
      continue;
    }
    if (decodable) check(heard.decisions.size() == decisions + 1, "a decodable keyframe was not answered once");
    if (heard.decisions.size() == decisions) continue;
    const keepless::decision_t& d = heard.decisions.back();
    if (d.status != keepless::decision_t::STATUS_OPTIMAL || !mirrored || restarted) continue;

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
