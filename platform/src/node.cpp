#include "keepless/platform/node.hpp"

#include <lcm/lcm-cpp.hpp>
#include <lcm/lcm.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <vector>

#include "keepless/core/sparsifier.hpp"
#include "keepless/decision_t.hpp"
#include "keepless/decision_timing_t.hpp"
#include "keepless/keyframe_t.hpp"
#include "keepless/map_event_ack_t.hpp"
#include "keepless/map_event_t.hpp"
#include "keepless/platform/decision_message.hpp"
#include "keepless/platform/monotonic_clock.hpp"
#include "keepless/platform/recent_ids.hpp"
#include "keepless/platform/sliding_window.hpp"
#include "keepless/status_t.hpp"

namespace keepless::platform {

namespace {

// LCM sends a message up to this size in one datagram; larger ones are
// fragmented (and dropped by receivers with a small socket buffer).
constexpr std::size_t kSingleDatagramBytes = 65000;

RejectReason reason_of(core::Status s) {
  switch (s) {
    case core::Status::kCapacityExceeded: return RejectReason::kWindowCapacity;
    case core::Status::kDuplicateKeyframe: return RejectReason::kDuplicateKeyframe;
    case core::Status::kDuplicateObservation: return RejectReason::kDuplicateObservation;
    case core::Status::kUnknownKeyframe: return RejectReason::kUnknownKeyframe;
    case core::Status::kInvalidArgument: return RejectReason::kNonFinite;
    default: return RejectReason::kInvalidField;
  }
}

}  // namespace

struct Node::Impl {
  Impl(lcm::LCM& l, const NodeConfig& c)
      : lcm(l),
        config(c),
        capacities(window_capacities(c)),
        sliding(capacities, c.max_observations, c.max_event_ids),
        // Incremental: each keyframe edits the previous window's network in
        // place; the decisions are run()'s, bit for bit.
        sparsifier(capacities, c.params, core::SolveMode::kIncremental),
        order(order_bounds(c), c.max_publishers),
        culls(c.cull_memory != 0 ? c.cull_memory : capacities.max_points) {
    limits.max_observations = c.max_observations;
    limits.max_event_ids = c.max_event_ids;
    limits.max_unmapped = c.max_unmapped;
    budget.work_units = c.budget_work_units;

    // Reserved once: decode() then only resizes within capacity.
    kf.point_id.reserve(c.max_observations);
    kf.u.reserve(c.max_observations);
    kf.v.reserve(c.max_observations);
    kf.depth.reserve(c.max_observations);
    kf.intrinsics.reserve(4);
    kf.unmapped_u.reserve(c.max_unmapped);
    kf.unmapped_v.reserve(c.max_unmapped);
    kf.tracked.reserve(c.max_observations);
    unmapped.resize(c.max_unmapped);
    tracked.resize(c.max_observations);
    event.deleted_point_id.reserve(c.max_event_ids);
    event.merged_from_id.reserve(c.max_event_ids);
    event.merged_into_id.reserve(c.max_event_ids);
    event.removed_keyframe_id.reserve(c.max_event_ids);
    merged_from.resize(c.max_event_ids);
    merged_into.resize(c.max_event_ids);
    removed.resize(c.max_event_ids);
    ack.refused_id.resize(2 * std::size_t{c.max_event_ids});
    ack.refused_reason.resize(2 * std::size_t{c.max_event_ids});
    ack.num_refused = static_cast<std::int32_t>(ack.refused_id.size());
    ack_out.resize(static_cast<std::size_t>(ack.getEncodedSize()));
    // The largest keyframe_t the byte checks admit: observations, the optional
    // depths, intrinsics and unmapped keypoints, then publisher_id and the tracked flags.
    pending.resize(wire::kKeyframeHeaderBytes + (wire::kKeyframeBytesPerObservation + 4 + 1) * c.max_observations +
                   wire::kKeyframeOptionalCountBytes + 4 * 8 + 8 * std::size_t{c.max_unmapped} +
                   wire::kKeyframeTrailerBytes);
    max_decision = reserve_decision(decision, capacities);
    observations.resize(c.max_observations);
    id_scratch.resize(std::max<std::size_t>(c.max_observations, 2 * std::size_t{c.max_event_ids}));
    out.resize(max_decision);
    start_ns = monotonic_ns();
    next_status_ns = start_ns;
  }

  void reject(const char* type, const std::string& channel, std::uint32_t size, RejectReason r,
              bool decoded, std::int64_t sequence, std::int64_t id) {
    ++counters.messages_rejected;
    ++counters.rejected[static_cast<std::size_t>(r)];
    if (config.quiet) return;
    if (decoded) {
      std::fprintf(stderr, "keepless_node: rejected %s seq %lld id %lld on %s (%u bytes): %s\n", type,
                   static_cast<long long>(sequence), static_cast<long long>(id), channel.c_str(), size,
                   to_string(r));
    } else {
      std::fprintf(stderr, "keepless_node: rejected %s on %s (%u bytes): %s\n", type, channel.c_str(), size,
                   to_string(r));
    }
  }

  DecisionRequest request() const { return {kf.sequence, kf.keyframe_id, kf.utime}; }

  // Publishes `decision`; returns its encoded size (0 on encode failure).
  std::size_t publish_decision() {
    const int len = decision.encode(out.data(), 0, static_cast<int>(out.size()));
    if (len < 0) {
      std::fprintf(stderr, "keepless_node: decision encode failed (%d)\n", len);
      return 0;
    }
    lcm.publish(config.decision_channel, out.data(), static_cast<unsigned>(len));
    ++counters.decisions_published;
    if (static_cast<std::size_t>(len) > kSingleDatagramBytes) ++counters.large_decisions;
    return static_cast<std::size_t>(len);
  }

  void answer_rejected(RejectReason r) {
    if (r == RejectReason::kWindowCapacity) ++counters.capacity_exceeded;
    fill_rejected_decision(decision, request(), sliding.window(), r);
    publish_decision();
  }

  // A refused run of messages became the publisher's order (OrderTracker);
  // when it went back in sequence the VO restarted: its old map is gone, so
  // is the window and the memory of culls.
  void on_adopted(const OrderTracker::Verdict& v, std::int64_t sequence) {
    if (!v.adopted || !v.went_back) return;
    sliding.clear();
    culls.clear();
    if (!config.quiet) {
      std::fprintf(stderr, "keepless_node: publisher restart recognised at seq %lld: window cleared\n",
                   static_cast<long long>(sequence));
    }
  }

  // `decide` false: a newer keyframe is already queued, so this one enters
  // the window and is answered STATUS_SKIPPED at once.
  void on_keyframe(const void* data, std::uint32_t size, bool decide) {
    const std::uint64_t t0 = monotonic_ns();
    ++counters.keyframes_received;
    RejectReason r = check_keyframe_bytes(data, size, limits);
    // decode() leaves a vector untouched when its count is 0: clear first
    // (capacity stays, nothing allocates).
    kf.point_id.clear();
    kf.u.clear();
    kf.v.clear();
    kf.depth.clear();
    kf.intrinsics.clear();
    kf.unmapped_u.clear();
    kf.unmapped_v.clear();
    kf.tracked.clear();
    if (r == RejectReason::kNone && kf.decode(data, 0, static_cast<int>(size)) < 0) r = RejectReason::kTruncated;
    if (r != RejectReason::kNone) {
      // Ids unreadable: no decision can name the request.
      reject("keyframe_t", config.keyframe_channel, size, r, false, 0, 0);
      return;
    }
    const OrderTracker::Verdict v = order.check(kf.publisher_id, kf.sequence, kf.utime);
    on_adopted(v, kf.sequence);
    r = v.reason;
    if (r == RejectReason::kNone) r = check_keyframe(kf, sliding.window(), id_scratch.data());
    const std::uint64_t t1 = monotonic_ns();
    if (r == RejectReason::kNone) {
      // Points culled by a decision the VO may not have applied yet when it
      // sent this keyframe stay culled.
      const auto n = static_cast<std::uint32_t>(kf.num_observations);
      std::uint32_t kept = 0;
      for (std::uint32_t i = 0; i < n; ++i) {
        const auto point = static_cast<core::PointId>(kf.point_id[i]);
        if (culls.contains(point)) continue;
        observations[kept].point = point;
        observations[kept].u = static_cast<double>(kf.u[i]);
        observations[kept].v = static_cast<double>(kf.v[i]);
        observations[kept].depth = kf.num_depths != 0 ? static_cast<double>(kf.depth[i]) : 0.0;
        tracked[kept] = kf.num_tracked != 0 ? static_cast<std::uint8_t>(kf.tracked[i]) : 0;
        ++kept;
      }
      counters.stale_observations += n - kept;
      core::Keyframe keyframe;
      keyframe.id = static_cast<core::KeyframeId>(kf.keyframe_id);
      std::copy(kf.centre, kf.centre + 3, keyframe.centre);
      std::copy(kf.orientation, kf.orientation + 4, keyframe.orientation);
      if (kf.num_intrinsics == 4) {
        keyframe.fx = kf.intrinsics[0];
        keyframe.fy = kf.intrinsics[1];
        keyframe.cx = kf.intrinsics[2];
        keyframe.cy = kf.intrinsics[3];
      }
      const auto m = static_cast<std::uint32_t>(kf.num_unmapped);
      for (std::uint32_t i = 0; i < m; ++i) {
        unmapped[i] = {static_cast<double>(kf.unmapped_u[i]), static_cast<double>(kf.unmapped_v[i])};
      }
      keyframe.unmapped = unmapped.data();
      keyframe.unmapped_count = m;
      keyframe.tracked = kf.num_tracked != 0 ? tracked.data() : nullptr;
      const core::Status s = sliding.push(keyframe, observations.data(), kept);
      if (s != core::Status::kOk) r = reason_of(s);
    }
    if (r != RejectReason::kNone) {
      reject("keyframe_t", config.keyframe_channel, size, r, true, kf.sequence, kf.keyframe_id);
      answer_rejected(r);
      finish_timing(t0, t1, t1, t1, 0, 0);
      return;
    }
    order.accept(kf.publisher_id, kf.sequence, kf.utime);
    const std::uint64_t t2 = monotonic_ns();
    if (!decide) {
      ++counters.keyframes_skipped;
      fill_rejected_decision(decision, request(), sliding.window(), RejectReason::kNone);
      decision.status = keepless::decision_t::STATUS_SKIPPED;
      decision.reject_reason = -1;
      publish_decision();
      finish_timing(t0, t1, t2, t2, 0, 0);
      return;
    }

    if (config.latency_target_ms > 0) {
      budget.clock = &clock;
      budget.deadline_ns = t0 + static_cast<std::uint64_t>(config.latency_target_ms * 1e6);
    }
    // A stop for budget culls nothing; the next keyframe's update() catches up.
    const core::Status run = sparsifier.update(sliding.window(), budget);
    const std::uint64_t t3 = monotonic_ns();
    const std::uint32_t n_culled = fill_decision(decision, request(), sliding.window(), sparsifier, run);
    if (run == core::Status::kBudgetExhausted) ++counters.budget_exhaustions;
    if (run == core::Status::kCapacityExceeded) ++counters.capacity_exceeded;
    if (run != core::Status::kOk && run != core::Status::kBudgetExhausted) {
      std::fprintf(stderr, "keepless_node: sparsifier failed on keyframe seq %lld: %s (nothing culled)\n",
                   static_cast<long long>(kf.sequence), core::to_string(run));
    }
    publish_decision();
    counters.points_culled += n_culled;
    finish_timing(t0, t1, t2, t3, sparsifier.solver().stats().work_units, sparsifier.solver().stats().phases);

    // The VO deletes culled points; so does the window, off the latency path.
    // The ids are the decision's own (int64 and uint64 may alias).
    if (n_culled > 0) {
      const auto* culled = reinterpret_cast<const core::PointId*>(decision.culled_point_id.data());
      for (std::uint32_t i = 0; i < n_culled; ++i) culls.insert(culled[i]);
      const core::Status s = sliding.drop_points(culled, n_culled);
      if (s != core::Status::kOk) {
        std::fprintf(stderr, "keepless_node: dropping culled points failed: %s\n", core::to_string(s));
      }
    }
  }

  // Inside spin_once's drain a keyframe waits in `pending` until the next
  // message shows whether it is the newest.
  void receive_keyframe(const void* data, std::uint32_t size) {
    if (!draining || size > pending.size()) {  // oversize: refused unread, pending stays the newest
      on_keyframe(data, size, true);
      return;
    }
    skip_pending();
    std::copy_n(static_cast<const std::uint8_t*>(data), size, pending.begin());
    pending_size = size;
    has_pending = true;
  }
  void skip_pending() {
    if (!has_pending) return;
    has_pending = false;
    on_keyframe(pending.data(), pending_size, false);
  }
  void decide_pending() {
    if (!has_pending) return;
    has_pending = false;
    on_keyframe(pending.data(), pending_size, true);
  }

  void finish_timing(std::uint64_t t0, std::uint64_t t1, std::uint64_t t2, std::uint64_t t3,
                     std::uint64_t work, std::uint64_t phases) {
    const std::uint64_t t4 = monotonic_ns();
    latency.record(t4 - t0);
    timing.sequence = kf.sequence;
    timing.keyframe_id = kf.keyframe_id;
    timing.validate_ns = static_cast<std::int64_t>(t1 - t0);
    timing.window_ns = static_cast<std::int64_t>(t2 - t1);
    timing.sparsify_ns = static_cast<std::int64_t>(t3 - t2);
    timing.publish_ns = static_cast<std::int64_t>(t4 - t3);
    timing.total_ns = static_cast<std::int64_t>(t4 - t0);
    timing.solver_work_units = static_cast<std::int64_t>(work);
    timing.solver_phases = static_cast<std::int64_t>(phases);
    const int len = timing.encode(small.data(), 0, static_cast<int>(small.size()));
    if (len > 0) lcm.publish(config.timing_channel, small.data(), static_cast<unsigned>(len));
    if (config.max_keyframes > 0 && counters.decisions_published >= config.max_keyframes) finished = true;
  }

  void on_map_event(const void* data, std::uint32_t size) {
    skip_pending();  // it was queued before this event
    ++counters.map_events_received;
    RejectReason r = check_map_event_bytes(data, size, limits);
    event.deleted_point_id.clear();
    event.merged_from_id.clear();
    event.merged_into_id.clear();
    event.removed_keyframe_id.clear();
    if (r == RejectReason::kNone && event.decode(data, 0, static_cast<int>(size)) < 0) r = RejectReason::kTruncated;
    if (r != RejectReason::kNone) {
      reject("map_event_t", config.event_channel, size, r, false, 0, 0);
      return;
    }
    const OrderTracker::Verdict v = order.check(event.publisher_id, event.sequence, event.utime);
    on_adopted(v, event.sequence);
    r = v.reason;
    if (r == RejectReason::kNone) r = check_map_event(event);
    MapEventItems items;
    items.merged_from = merged_from.data();
    items.merged_into = merged_into.data();
    items.removed = removed.data();
    items.refused_id = ack.refused_id.data();
    items.refused_reason = ack.refused_reason.data();
    if (r == RejectReason::kNone && event.reset) {
      sliding.clear();
      culls.clear();
    } else if (r == RejectReason::kNone) {
      split_map_event(event, sliding.window(), &culls, id_scratch.data(), items);
      SlidingWindow::Edit e;
      e.deleted = reinterpret_cast<const core::PointId*>(event.deleted_point_id.data());
      e.deleted_count = static_cast<std::uint32_t>(event.num_deleted_points);
      e.merged_from = reinterpret_cast<const core::PointId*>(items.merged_from);
      e.merged_into = reinterpret_cast<const core::PointId*>(items.merged_into);
      e.merged_count = items.merged;
      e.removed = reinterpret_cast<const core::KeyframeId*>(items.removed);
      e.removed_count = items.removed_count;
      const core::Status s = sliding.edit(e);
      if (s != core::Status::kOk) r = reason_of(s);
    }
    if (r != RejectReason::kNone) {
      reject("map_event_t", config.event_channel, size, r, true, event.sequence, 0);
      items = MapEventItems{};
      publish_ack(r, items);
      return;
    }
    order.accept(event.publisher_id, event.sequence, event.utime);
    counters.event_items_refused += items.refused;
    publish_ack(r, items);
  }

  void publish_ack(RejectReason r, const MapEventItems& items) {
    using A = keepless::map_event_ack_t;
    ack.sequence = event.sequence;
    ack.utime = event.utime;
    ack.publisher_id = event.publisher_id;
    ack.reset = event.reset;
    ack.status = r != RejectReason::kNone ? A::STATUS_REJECTED : items.refused > 0 ? A::STATUS_PARTIAL
                                                                                    : A::STATUS_APPLIED;
    ack.reject_reason = r != RejectReason::kNone ? static_cast<std::int8_t>(r) : std::int8_t{-1};
    const bool applied = r == RejectReason::kNone && !event.reset;
    ack.deleted_applied = applied ? event.num_deleted_points : 0;
    ack.merged_applied = static_cast<std::int32_t>(items.merged);
    ack.removed_applied = static_cast<std::int32_t>(items.removed_count);
    std::fill(std::begin(ack.refused), std::end(ack.refused), 0);
    for (std::uint32_t i = 0; i < items.refused; ++i) ++ack.refused[static_cast<std::size_t>(ack.refused_reason[i])];
    // Within the reserved size: no allocation.
    ack.refused_id.resize(items.refused);
    ack.refused_reason.resize(items.refused);
    ack.num_refused = static_cast<std::int32_t>(items.refused);
    const int len = ack.encode(ack_out.data(), 0, static_cast<int>(ack_out.size()));
    if (len > 0) lcm.publish(config.event_ack_channel, ack_out.data(), static_cast<unsigned>(len));
    ack.refused_id.resize(ack.refused_id.capacity());
    ack.refused_reason.resize(ack.refused_reason.capacity());
  }

  void publish_status(bool final) {
    const std::uint64_t now = monotonic_ns();
    status.uptime_ns = static_cast<std::int64_t>(now - start_ns);
    status.is_final = final;
    status.keyframes_received = static_cast<std::int64_t>(counters.keyframes_received);
    status.map_events_received = static_cast<std::int64_t>(counters.map_events_received);
    status.messages_rejected = static_cast<std::int64_t>(counters.messages_rejected);
    for (std::size_t i = 0; i < 16; ++i) {
      status.rejected[i] = i < kRejectReasonCount ? static_cast<std::int64_t>(counters.rejected[i]) : 0;
    }
    status.decisions_published = static_cast<std::int64_t>(counters.decisions_published);
    status.budget_exhaustions = static_cast<std::int64_t>(counters.budget_exhaustions);
    status.capacity_exceeded = static_cast<std::int64_t>(counters.capacity_exceeded);
    status.large_decisions = static_cast<std::int64_t>(counters.large_decisions);
    status.points_culled = static_cast<std::int64_t>(counters.points_culled);
    status.last_sequence = order.last_sequence();
    status.sequence_gaps = static_cast<std::int64_t>(order.sequence_gaps());
    status.keyframes_skipped = static_cast<std::int64_t>(counters.keyframes_skipped);
    status.stream_restarts = static_cast<std::int64_t>(order.restarts());
    status.stream_conflicts = static_cast<std::int64_t>(order.conflicts());
    status.publishers_seen = static_cast<std::int64_t>(order.publishers_seen());
    status.publishers_active = static_cast<std::int32_t>(order.publishers_active());
    status.stale_observations = static_cast<std::int64_t>(counters.stale_observations);
    status.event_items_refused = static_cast<std::int64_t>(counters.event_items_refused);
    const core::Window& w = sliding.window();
    status.window_keyframes = static_cast<std::int32_t>(w.keyframe_count());
    status.window_points = static_cast<std::int32_t>(w.distinct_points());
    status.window_observations = static_cast<std::int32_t>(w.total_observations());
    status.capacity_keyframes = static_cast<std::int32_t>(capacities.max_keyframes);
    status.capacity_points = static_cast<std::int32_t>(capacities.max_points);
    status.capacity_observations = static_cast<std::int32_t>(capacities.max_observations);
    status.memory_bytes = static_cast<std::int64_t>(memory_bytes());
    status.latency_p50_ns = static_cast<std::int64_t>(latency.quantile(0.5));
    status.latency_p99_ns = static_cast<std::int64_t>(latency.quantile(0.99));
    status.latency_max_ns = static_cast<std::int64_t>(latency.max());
    const int len = status.encode(small.data(), 0, static_cast<int>(small.size()));
    if (len > 0) lcm.publish(config.status_channel, small.data(), static_cast<unsigned>(len));
    next_status_ns = now + std::uint64_t{config.status_period_ms} * 1000000ull;
  }

  std::size_t memory_bytes() const {
    return sliding.memory_bytes() + sparsifier.memory_bytes() + out.size() + small.size() +
           observations.size() * sizeof(core::Observation) + id_scratch.size() * sizeof(std::uint64_t) +
           (kf.point_id.capacity() * 16) + kf.depth.capacity() * 4 + kf.intrinsics.capacity() * 8 +
           kf.unmapped_u.capacity() * 8 + unmapped.size() * sizeof(core::Keypoint) +
           kf.tracked.capacity() + tracked.size() +
           (event.deleted_point_id.capacity() + event.merged_from_id.capacity() +
            event.merged_into_id.capacity() + event.removed_keyframe_id.capacity()) * 8 +
           (decision.window_keyframe_id.capacity() + decision.culled_point_id.capacity()) * 8 +
           (merged_from.size() + merged_into.size() + removed.size()) * 8 + ack.refused_id.capacity() * 9 +
           ack_out.size() + pending.size() + culls.memory_bytes() + order.memory_bytes();
  }

  static void keyframe_cb(const lcm_recv_buf_t* rbuf, const char*, void* user) {
    static_cast<Impl*>(user)->receive_keyframe(rbuf->data, rbuf->data_size);
  }
  static void event_cb(const lcm_recv_buf_t* rbuf, const char*, void* user) {
    static_cast<Impl*>(user)->on_map_event(rbuf->data, rbuf->data_size);
  }

  lcm::LCM& lcm;
  NodeConfig config;
  core::Capacities capacities;
  MessageLimits limits;
  SlidingWindow sliding;
  core::Sparsifier sparsifier;
  // The solver reads the deadline on the node's own clock (CLOCK_MONOTONIC).
  struct MonotonicClock final : solver::Clock {
    std::uint64_t now_ns() const override { return monotonic_ns(); }
  } clock;
  solver::Budget budget;
  keepless::keyframe_t kf{};
  keepless::map_event_t event{};
  keepless::decision_t decision{};
  keepless::decision_timing_t timing{};
  keepless::status_t status{};
  std::vector<core::Observation> observations;
  std::vector<core::Keypoint> unmapped;  // [max_unmapped]
  std::vector<std::uint8_t> tracked;     // [max_observations], the accepted observations' flags
  std::vector<std::uint64_t> id_scratch;
  std::vector<std::uint8_t> out;
  std::array<std::uint8_t, 1024> small{};
  std::size_t max_decision = 0;
  OrderTracker order;
  RecentIds culls;
  keepless::map_event_ack_t ack{};
  std::vector<std::uint8_t> ack_out;
  std::vector<std::int64_t> merged_from, merged_into, removed;  // a map event's items to apply
  // spin_once's drain: the newest keyframe waits here (raw bytes).
  std::vector<std::uint8_t> pending;
  std::uint32_t pending_size = 0;
  bool has_pending = false;
  bool draining = false;
  NodeCounters counters;
  LatencyHistogram latency;
  std::uint64_t start_ns = 0;
  std::uint64_t next_status_ns = 0;
  bool finished = false;
  lcm_subscription_t* keyframe_sub = nullptr;
  lcm_subscription_t* event_sub = nullptr;
};

Node::Node(lcm::LCM& lcm, const NodeConfig& config) : impl_(std::make_unique<Impl>(lcm, config)) {}

Node::~Node() {
  lcm_t* l = impl_->lcm.getUnderlyingLCM();
  if (l != nullptr) {
    if (impl_->keyframe_sub != nullptr) lcm_unsubscribe(l, impl_->keyframe_sub);
    if (impl_->event_sub != nullptr) lcm_unsubscribe(l, impl_->event_sub);
  }
}

bool Node::start() {
  lcm_t* l = impl_->lcm.getUnderlyingLCM();
  if (!impl_->lcm.good() || l == nullptr) return false;
  // The C API: the C++ wrapper would build a std::string per message.
  impl_->keyframe_sub = lcm_subscribe(l, impl_->config.keyframe_channel.c_str(), &Impl::keyframe_cb, impl_.get());
  impl_->event_sub = lcm_subscribe(l, impl_->config.event_channel.c_str(), &Impl::event_cb, impl_.get());
  if (impl_->keyframe_sub == nullptr || impl_->event_sub == nullptr) return false;
  const int queue = static_cast<int>(impl_->config.queue_capacity);
  return lcm_subscription_set_queue_capacity(impl_->keyframe_sub, queue) == 0 &&
         lcm_subscription_set_queue_capacity(impl_->event_sub, queue) == 0;
}

int Node::spin_once(int timeout_ms) {
  Impl& n = *impl_;
  const std::uint64_t now = monotonic_ns();
  if (now >= n.next_status_ns) n.publish_status(false);
  const std::uint64_t until_status_ms = (n.next_status_ns - std::min(n.next_status_ns, now)) / 1000000ull;
  const int wait = static_cast<int>(std::min<std::uint64_t>(static_cast<std::uint64_t>(std::max(timeout_ms, 0)),
                                                            until_status_ms));
  // With a latency target, drain what is queued before deciding: only the
  // newest keyframe is decided, the older ones are answered SKIPPED at once.
  // (Without one, replays stay byte-for-byte: every keyframe is decided.)
  n.draining = n.config.latency_target_ms > 0;
  const int got = n.lcm.handleTimeout(wait);
  lcm_t* l = n.lcm.getUnderlyingLCM();
  for (std::uint32_t i = 0; got > 0 && n.draining && i < 2 * n.config.queue_capacity; ++i) {
    if (lcm_handle_timeout(l, 0) <= 0) break;
  }
  n.draining = false;
  n.decide_pending();
  return got;
}

void Node::publish_status(bool final) { impl_->publish_status(final); }
bool Node::finished() const { return impl_->finished; }
void Node::handle_keyframe(const void* data, std::uint32_t size) { impl_->on_keyframe(data, size, true); }
void Node::handle_map_event(const void* data, std::uint32_t size) { impl_->on_map_event(data, size); }
const core::Window& Node::window() const { return impl_->sliding.window(); }
const NodeCounters& Node::counters() const { return impl_->counters; }
const LatencyHistogram& Node::latency() const { return impl_->latency; }
const OrderTracker& Node::order() const { return impl_->order; }
std::size_t Node::memory_bytes() const { return impl_->memory_bytes(); }
std::size_t Node::max_decision_bytes() const { return impl_->max_decision; }

}  // namespace keepless::platform
