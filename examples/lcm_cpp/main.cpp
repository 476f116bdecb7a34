// A VO's side of the bus in C++: wait for keepless_node's status, publish a
// few keyframe_t on KEEPLESS_KEYFRAME and read one decision_t per keyframe
// back on KEEPLESS_DECISION.
//
//   lcm_cpp [URL]     (default udpm://239.255.76.67:7667?ttl=0, keepless_node's)
//
// Start the node first, e.g. `keepless_node --url URL` (its 5 ms latency target
// may answer a keyframe budget_exhausted on a loaded machine; 0 turns it off).

#include <cstdint>
#include <cstdio>
#include <string>

#include <lcm/lcm-cpp.hpp>

#include "keepless/decision_t.hpp"
#include "keepless/keyframe_t.hpp"
#include "keepless/status_t.hpp"

namespace {

constexpr int kKeyframes = 6;
constexpr int kPointsPerKeyframe = 300;  // more shared per keyframe pair than the node's M = 100
constexpr int kStep = 60;

struct Inbox {
  bool node_up = false;
  std::int64_t publisher_id = 0;  // ours: decisions for other publishers are not ours to count
  std::int64_t sequence = -1;     // the keyframe_t just published
  int decisions = 0;
  int refused = 0;  // STATUS_REJECTED_INPUT, STATUS_CAPACITY_EXCEEDED: the node did not take the keyframe
  int culled = 0;
  // Plain functions with a context (subscribeFunction): GCC's UBSan misreports
  // LCM's pointer-to-member call in the member-function subscribe.
  static void on_status(const lcm::ReceiveBuffer*, const std::string&, const keepless::status_t*, Inbox* in) {
    in->node_up = true;
  }
  static void on_decision(const lcm::ReceiveBuffer*, const std::string&, const keepless::decision_t* d,
                          Inbox* in) {
    // Every VO on the bus gets its decisions on this channel: answer only ours.
    if (d->publisher_id != in->publisher_id || d->sequence != in->sequence) return;
    std::printf("decision for keyframe %lld: status %d, %d points, kept %d, culled %d\n",
                static_cast<long long>(d->keyframe_id), d->status, d->points, d->kept, d->culled);
    ++in->decisions;
    if (d->status == keepless::decision_t::STATUS_REJECTED_INPUT ||
        d->status == keepless::decision_t::STATUS_CAPACITY_EXCEEDED) {
      std::fprintf(stderr, "lcm_cpp: keyframe %lld refused: status %d, reject_reason %d (status_t.REJECT_*)\n",
                   static_cast<long long>(d->keyframe_id), d->status, d->reject_reason);
      ++in->refused;
    }
    in->culled += d->num_culled;  // culled_point_id[0, num_culled): delete these map points
  }
};

// Waits up to `ms` for messages; false when nothing came.
bool wait(lcm::LCM& bus, int ms) { return bus.handleTimeout(ms) > 0; }

}  // namespace

int main(int argc, char** argv) {
  const std::string url = argc > 1 ? argv[1] : "udpm://239.255.76.67:7667?ttl=0";
  lcm::LCM bus(url);
  if (!bus.good()) {
    std::fprintf(stderr, "lcm_cpp: cannot open %s\n", url.c_str());
    return 1;
  }
  Inbox inbox;
  bus.subscribeFunction("KEEPLESS_STATUS", &Inbox::on_status, &inbox);
  bus.subscribeFunction("KEEPLESS_DECISION", &Inbox::on_decision, &inbox);
  for (int i = 0; i < 100 && !inbox.node_up; ++i) wait(bus, 100);  // the node's status: it is up
  if (!inbox.node_up) {
    std::fprintf(stderr, "lcm_cpp: no keepless_node status on %s within 10 s\n", url.c_str());
    return 1;
  }
  for (int k = 0; k < kKeyframes; ++k) {
    // snippet-begin: publish
    keepless::keyframe_t kf{};  // value-initialised: the optional arrays' counts are 0
    kf.sequence = k + 1;       // strictly increasing per publisher
    kf.utime = 1000000 + 100000 * k;
    kf.keyframe_id = k;
    kf.centre[0] = 0.2 * k;    // camera centre, metres
    kf.orientation[0] = 1.0;   // world-from-camera quaternion w, x, y, z
    kf.image_width = 640;
    kf.image_height = 480;
    for (int i = 0; i < kPointsPerKeyframe; ++i) {
      const int id = k * kStep + i;  // map point ids your VO gave its points
      kf.point_id.push_back(id);
      kf.u.push_back(static_cast<float>((id * 37) % 620 + 10));
      kf.v.push_back(static_cast<float>((id * 53) % 460 + 10));
    }
    kf.num_observations = kPointsPerKeyframe;
    kf.publisher_id = 42;  // any identity of this process
    bus.publish("KEEPLESS_KEYFRAME", &kf);
    // snippet-end: publish
    inbox.publisher_id = kf.publisher_id;
    inbox.sequence = kf.sequence;
    const int before = inbox.decisions;
    for (int i = 0; i < 50 && inbox.decisions == before; ++i) wait(bus, 100);  // decision_t
  }
  std::printf("lcm_cpp: %d decisions for %d keyframes, %d refused, %d points culled\n", inbox.decisions,
              kKeyframes, inbox.refused, inbox.culled);
  return inbox.decisions == kKeyframes && inbox.refused == 0 && inbox.culled > 0 ? 0 : 1;
}
