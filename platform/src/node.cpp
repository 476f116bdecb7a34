#include "keepless/platform/node.hpp"

#include <lcm/lcm-cpp.hpp>
#include <lcm/lcm.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <vector>

#include "keepless/core/deferred_culls.hpp"
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
  Impl(lcm::LCM& l, const NodeConfig& c, const solver::Clock* injected)
      : lcm(l),
        config(c),
        capacities(window_capacities(c)),
        sliding(capacities, c.max_observations, c.max_event_ids),
        // Incremental: each keyframe edits the previous window's network in
        // place; the decisions are run()'s, bit for bit.
        sparsifier(capacities, c.params, core::SolveMode::kIncremental),
        clock(injected != nullptr ? injected : &own_clock),
        empty_window(tiny_capacities()),
        order(order_bounds(c)),
        culls(c.cull_memory != 0 ? c.cull_memory : capacities.max_points),
        deferring(c.params.defer_keyframes > 0),
        deferred(deferring ? (c.defer_memory != 0 ? c.defer_memory : capacities.max_points) : 0,
                 c.params.defer_keyframes) {
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
    kf.track_length.reserve(c.max_observations);
    kf.age.reserve(c.max_observations);
    kf.reprojection_error.reserve(c.max_observations);
    kf.triangulation_angle.reserve(c.max_observations);
    unmapped.resize(c.max_unmapped);
    tracked.resize(c.max_observations);
    quality.resize(c.max_observations);
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
    pending_window.resize(capacities.max_keyframes);
    max_decision = reserve_decision(decision, capacities, deferring ? deferred.capacity() : 0);
    merged_kept.resize(c.max_event_ids);
    merged_kept_into.resize(c.max_event_ids);
    observations.resize(c.max_observations);
    id_scratch.resize(std::max<std::size_t>(c.max_observations, 3 * std::size_t{c.max_event_ids}));
    out.resize(max_decision);
    status.last_capacity = keepless::status_t::CAPACITY_NONE;
    status.last_capacity_sequence = -1;
    start_ns = clock->now_ns();
    next_status_ns = start_ns;
  }

  static core::Capacities tiny_capacities() {
    core::Capacities t;
    t.max_keyframes = t.max_points = t.max_observations = t.max_pair_arcs = 1;
    return t;
  }

  void reject(const char* type, const std::string& channel, std::uint32_t size, RejectReason r,
              bool decoded, std::int64_t sequence, std::int64_t id) {
    ++counters.messages_rejected;
    ++counters.rejected[static_cast<std::size_t>(r)];
    if (r == RejectReason::kNotOwner) ++counters.not_owner;
    if (config.quiet) return;
    // An invalid field is named (the decoded message's, or the counts of refused bytes).
    const bool is_kf = std::strcmp(type, "keyframe_t") == 0;
    const char* field = r != RejectReason::kInvalidField ? ""
                        : is_kf ? invalid_keyframe_field(decoded ? &kf : nullptr)
                                : invalid_map_event_field(decoded ? &event : nullptr);
    const char* sep = *field != '\0' ? ": " : "";
    if (decoded) {
      std::fprintf(stderr, "keepless_node: rejected %s seq %lld id %lld on %s (%u bytes): %s%s%s\n", type,
                   static_cast<long long>(sequence), static_cast<long long>(id), channel.c_str(), size,
                   to_string(r), sep, field);
    } else {
      std::fprintf(stderr, "keepless_node: rejected %s on %s (%u bytes): %s%s%s\n", type, channel.c_str(), size,
                   to_string(r), sep, field);
    }
  }

  DecisionRequest request() const { return {kf.sequence, kf.keyframe_id, kf.utime, kf.publisher_id}; }

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

  // The keyframe in kf, decoded (its bytes hashed to `hash`): its order
  // verdict and content check, with no state changed. Content is checked
  // against the window it would enter (empty on a takeover or a restart), so
  // an invalid message can never adopt an order.
  struct Checked {
    OrderTracker::Verdict verdict;
    RejectReason content = RejectReason::kNone;
    RejectReason reason() const { return verdict.reason != RejectReason::kNone ? verdict.reason : content; }
  };
  Checked check_decoded_keyframe(std::uint64_t now, std::uint64_t hash) {
    Checked c;
    c.verdict = order.check(kf.publisher_id, kf.sequence, kf.utime, hash, now, true);
    c.content = check_keyframe(kf, c.verdict.takeover || c.verdict.restart ? empty_window : sliding.window(),
                               id_scratch.data());
    return c;
  }
  // A keyframe the order refused, valid otherwise, may be part of a restart
  // or a resync; so may one whose id is in the window, if the order says it
  // reissues that id (rule 3: a restarted VO's, no retransmission).
  bool candidate(const Checked& c, std::uint64_t hash) {
    if (c.verdict.reason == RejectReason::kNone || c.verdict.reason == RejectReason::kNotOwner) return false;
    if (c.content == RejectReason::kNone) return true;
    return c.content == RejectReason::kDuplicateKeyframe && order.reissues(kf.sequence, kf.utime, hash) &&
           check_keyframe(kf, empty_window, id_scratch.data()) == RejectReason::kNone;
  }

  // A window beyond a capacity: counted, remembered for status_t, logged
  // with what it needed; the decision (STATUS_CAPACITY_EXCEEDED) culls nothing.
  void note_capacity(std::int64_t sequence, std::int8_t which, std::uint64_t needed, std::uint64_t held) {
    ++counters.capacity_exceeded;
    status.last_capacity = which;
    status.last_capacity_sequence = sequence;
    status.last_capacity_needed = static_cast<std::int64_t>(needed);
    status.last_capacity_held = static_cast<std::int64_t>(held);
    if (config.quiet) return;
    static const char* const kNames[] = {"points", "observations", "pair arcs", "unmapped keypoints"};
    std::fprintf(stderr,
                 "keepless_node: keyframe seq %lld: window beyond capacity: %s needed %llu, held %llu "
                 "(nothing culled)\n",
                 static_cast<long long>(sequence), kNames[which], static_cast<unsigned long long>(needed),
                 static_cast<unsigned long long>(held));
  }

  // The window's points, observations or unmapped keypoints: the push made
  // room by dropping older keyframes (SlidingWindow::push).
  void note_window_overflow(std::int64_t sequence) {
    using S = keepless::status_t;
    const SlidingWindow::Demand& d = sliding.overflow();
    if (d.observations > capacities.max_observations) {
      note_capacity(sequence, S::CAPACITY_OBSERVATIONS, d.observations, capacities.max_observations);
    } else if (d.points > capacities.max_points) {
      note_capacity(sequence, S::CAPACITY_POINTS, d.points, capacities.max_points);
    } else {
      note_capacity(sequence, S::CAPACITY_UNMAPPED, d.unmapped, capacities.max_unmapped_keypoints);
    }
  }

  // The keyframe enters the window (after the clear a takeover or restart
  // implies). Observations of points culled recently are dropped. On failure
  // nothing changed.
  // `evicted`: older keyframes the push dropped to make room, a window beyond
  // capacity (counted and logged here, once, whether decided or skipped).
  RejectReason admit_keyframe(const OrderTracker::Verdict& v, std::uint32_t* evicted) {
    if (v.resync && !config.quiet) {
      std::fprintf(stderr,
                   "keepless_node: order resynchronised at seq %lld (publisher %lld): the last accepted message "
                   "was not continued; window kept\n",
                   static_cast<long long>(kf.sequence), static_cast<long long>(kf.publisher_id));
    }
    if (v.takeover || v.restart) {
      sliding.clear();
      culls.clear();
      deferred.clear();
      sparsifier.forget_history();
      if (!config.quiet) {
        std::fprintf(stderr, "keepless_node: %s at seq %lld (publisher %lld): window cleared\n",
                     v.takeover ? "window taken over" : "publisher restart recognised",
                     static_cast<long long>(kf.sequence), static_cast<long long>(kf.publisher_id));
      }
    }
    const auto n = static_cast<std::uint32_t>(kf.num_observations);
    // Point quality only where the window holds it (--cost track); other cost models never read it.
    const bool quality_in = capacities.hold_quality && kf.num_quality != 0;
    std::uint32_t kept = 0, excluded = 0;
    for (std::uint32_t i = 0; i < n; ++i) {
      const auto point = static_cast<core::PointId>(kf.point_id[i]);
      if (culls.contains(point)) continue;
      // An excluded point (deferred culling) stays out of the window: decided already, out of BA.
      if (deferring && deferred.contains(point)) {
        ++excluded;
        continue;
      }
      observations[kept].point = point;
      observations[kept].u = static_cast<double>(kf.u[i]);
      observations[kept].v = static_cast<double>(kf.v[i]);
      observations[kept].depth = kf.num_depths != 0 ? static_cast<double>(kf.depth[i]) : 0.0;
      tracked[kept] = kf.num_tracked != 0 ? static_cast<std::uint8_t>(kf.tracked[i]) : 0;
      if (quality_in) {
        quality[kept] = {static_cast<std::uint32_t>(kf.track_length[i]), kf.age[i], kf.reprojection_error[i],
                         kf.triangulation_angle[i]};
      }
      ++kept;
    }
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
    keyframe.quality = quality_in ? quality.data() : nullptr;
    const core::Status s = sliding.push(keyframe, observations.data(), kept, evicted);
    if (s != core::Status::kOk) return reason_of(s);
    if (*evicted > 0) note_window_overflow(kf.sequence);
    counters.stale_observations += n - kept - excluded;
    counters.deferred_observations += excluded;
    if (deferring) {
      // One tick per admitted keyframe; its matched observations (tracked
      // flag 1, or every one without flags) refresh the excluded points.
      deferred.begin_keyframe();
      for (std::uint32_t i = 0; i < n; ++i) {
        (void)deferred.observe(static_cast<core::PointId>(kf.point_id[i]), kf.num_tracked == 0 || kf.tracked[i] != 0);
      }
    }
    if (kf.num_quality == 0 && config.params.cost_model == core::CostModel::kTrack &&
        counters.track_fallback++ == 0 && !config.quiet) {
      std::fprintf(stderr,
                   "keepless_node: keyframe_t without point quality (num_quality 0) at seq %lld: --cost track "
                   "ranks its points by the window alone\n",
                   static_cast<long long>(kf.sequence));
    }
    return RejectReason::kNone;
  }

  // `drain` (spin_once with a latency target): an accepted keyframe waits as
  // `pending` until the drain ends, and only a newer accepted keyframe of the
  // same stream supersedes it (STATUS_SKIPPED). Map events, undecodable bytes
  // and refused keyframes never do: before anything else is answered or
  // changes the window, the pending keyframe is decided.
  void on_keyframe(const void* data, std::uint32_t size, std::uint64_t arrival, bool drain) {
    ++counters.keyframes_received;
    const std::uint64_t t0 = clock->now_ns();
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
    kf.track_length.clear();
    kf.age.clear();
    kf.reprojection_error.clear();
    kf.triangulation_angle.clear();
    if (r == RejectReason::kNone && kf.decode(data, 0, static_cast<int>(size)) < 0) r = RejectReason::kTruncated;
    if (r != RejectReason::kNone) {
      // Ids unreadable: no decision can name the request.
      reject("keyframe_t", config.keyframe_channel, size, r, false, 0, 0);
      return;
    }
    const std::uint64_t hash = message_hash(data, size);
    const Checked c = check_decoded_keyframe(arrival, hash);
    std::uint32_t evicted = 0;  // older keyframes dropped to make room (beyond the slide)
    r = c.reason();
    if (r == RejectReason::kNone) {
      // A new stream's window replaces the old one: the old one's pending
      // keyframe is decided first, over the window it entered.
      if (c.verdict.takeover || c.verdict.restart) decide_pending();
      r = admit_keyframe(c.verdict, &evicted);
    } else if (candidate(c, hash)) {
      (void)order.extend_restart(kf.publisher_id, kf.sequence, kf.utime, hash, arrival);
    }
    const std::uint64_t t1 = clock->now_ns();
    if (r != RejectReason::kNone) {
      decide_pending();  // answers stay in arrival order
      reject("keyframe_t", config.keyframe_channel, size, r, true, kf.sequence, kf.keyframe_id);
      if (r == RejectReason::kWindowCapacity) ++counters.capacity_exceeded;
      fill_rejected_decision(decision, request(), sliding.window(), r);
      publish_decision();
      finish_timing(request(), arrival, t0, t1, t1, t1, 0, 0);
      return;
    }
    order.accept(c.verdict, kf.publisher_id, kf.sequence, kf.utime, hash, arrival, true);
    skip_pending();  // superseded by this accepted keyframe of the same stream
    if (drain) {
      has_pending = true;
      pending = request();
      pending_arrival = arrival;
      pending_t0 = t0;
      pending_t1 = t1;
      pending_evicted = evicted;
      const core::Window& w = sliding.window();
      pending_keyframes = w.keyframe_count();
      for (std::uint32_t i = 0; i < pending_keyframes; ++i) pending_window[i] = static_cast<std::int64_t>(w.keyframe(i).id);
      return;
    }
    decide(request(), arrival, t0, t1, evicted);
  }

  // Answers the pending keyframe STATUS_SKIPPED, with the window it entered.
  void skip_pending() {
    if (!has_pending) return;
    has_pending = false;
    ++counters.keyframes_skipped;
    fill_rejected_decision(decision, pending, sliding.window(), RejectReason::kNone);
    decision.status = keepless::decision_t::STATUS_SKIPPED;
    decision.reject_reason = -1;
    decision.window_keyframe_id.resize(pending_keyframes);  // within the reserve
    std::copy_n(pending_window.begin(), pending_keyframes, decision.window_keyframe_id.begin());
    decision.num_window_keyframes = static_cast<std::int32_t>(pending_keyframes);
    publish_decision();
    sparsifier.note_undecided();  // the next decided keyframe takes its turn (Scope::kNewest)
    const std::uint64_t t = clock->now_ns();
    finish_timing(pending, pending_arrival, pending_t0, pending_t1, t, t, 0, 0);
  }
  void decide_pending() {
    if (!has_pending) return;
    has_pending = false;
    decide(pending, pending_arrival, pending_t0, pending_t1, pending_evicted);
  }

  // Sparsifies the window for `req` (its keyframe is the newest in it) and
  // publishes the decision; the deadline counts from the keyframe's arrival.
  // `evicted` > 0: the push had to drop older keyframes (noted at admission).
  void decide(const DecisionRequest& req, std::uint64_t arrival, std::uint64_t t0, std::uint64_t t1,
              std::uint32_t evicted) {
    const std::uint64_t t2 = clock->now_ns();
    if (config.latency_target_ms > 0) {
      budget.clock = clock;
      budget.deadline_ns = arrival + static_cast<std::uint64_t>(config.latency_target_ms * 1e6);
    }
    // A stop for budget culls nothing; the next keyframe's update() catches up
    // (with --scope newest it decides the missed keyframes' points too).
    // A window the push had to shorten is not decided: the keyframe is held,
    // and its turn passes to the next one decided, as a skipped one's does.
    const core::Status run =
        evicted > 0 ? core::Status::kCapacityExceeded : sparsifier.update(sliding.window(), budget);
    if (evicted > 0) sparsifier.note_undecided();
    const std::uint64_t t3 = clock->now_ns();
    std::uint32_t n_culled = fill_decision(decision, req, sliding.window(), sparsifier, run);
    std::uint32_t n_deleted = 0;
    if (deferring) {
      n_deleted = defer_culls(decision, deferred);
      n_culled = static_cast<std::uint32_t>(decision.num_excluded);
    }
    if (run == core::Status::kBudgetExhausted) ++counters.budget_exhaustions;
    if (evicted == 0 && run == core::Status::kCapacityExceeded) {
      // The network's pair arcs (the window's own capacities held it).
      note_capacity(req.sequence, keepless::status_t::CAPACITY_PAIR_ARCS, sliding.window().pair_arcs(), capacities.max_pair_arcs);
    }
    if (run != core::Status::kOk && run != core::Status::kBudgetExhausted && run != core::Status::kCapacityExceeded) {
      std::fprintf(stderr, "keepless_node: sparsifier failed on keyframe seq %lld: %s (nothing culled)\n",
                   static_cast<long long>(req.sequence), core::to_string(run));
    }
    publish_decision();
    if (deferring) {
      counters.points_excluded += n_culled;
      counters.points_deleted += n_deleted;
    } else {
      counters.points_culled += n_culled;
    }
    // The solver's figures only if this decision ran it (a deferred update
    // or a held window did not: the stats are an earlier decision's).
    const bool solved = evicted == 0 && !sparsifier.deferred();
    finish_timing(req, arrival, t0, t1, t2, t3, solved ? sparsifier.solver().stats().work_units : 0,
                  solved ? sparsifier.solver().stats().phases : 0);

    // The VO deletes culled points; so does the window, off the latency path.
    // The ids are the decision's own (int64 and uint64 may alias).
    // Deferred: the excluded points leave the window too (they are decided,
    // and out of BA), but not the cull memory: the VO still tracks them.
    // Deleted ones join the cull memory; only those the memory could not
    // hold are still in the window.
    if (deferring) {
      drop(reinterpret_cast<const core::PointId*>(decision.excluded_point_id.data()), n_culled, false);
      drop(reinterpret_cast<const core::PointId*>(decision.deleted_point_id.data()), n_deleted, true);
    } else {
      drop(reinterpret_cast<const core::PointId*>(decision.culled_point_id.data()), n_culled, true);
    }
  }

  // Drops points from the window (in chunks within its point capacity);
  // `remember`: into the cull memory too.
  void drop(const core::PointId* ids, std::uint32_t n, bool remember) {
    if (remember) {
      for (std::uint32_t i = 0; i < n; ++i) culls.insert(ids[i]);
    }
    for (std::uint32_t at = 0; at < n; at += capacities.max_points) {
      const core::Status s = sliding.drop_points(ids + at, std::min(n - at, capacities.max_points));
      if (s != core::Status::kOk) {
        std::fprintf(stderr, "keepless_node: dropping culled points failed: %s\n", core::to_string(s));
      }
    }
  }

  // Latency and total_ns count from `arrival`; the stages from t0 (handling
  // began), t1 (checked), t2 (in the window), t3 (solved).
  void finish_timing(const DecisionRequest& req, std::uint64_t arrival, std::uint64_t t0, std::uint64_t t1,
                     std::uint64_t t2, std::uint64_t t3, std::uint64_t work, std::uint64_t phases) {
    const std::uint64_t t4 = clock->now_ns();
    const std::uint64_t from = std::min(arrival, t0);
    latency.record(t4 - std::min(from, t4));
    timing.sequence = req.sequence;
    timing.keyframe_id = req.keyframe_id;
    timing.validate_ns = static_cast<std::int64_t>(t1 - t0);
    timing.window_ns = static_cast<std::int64_t>(t2 - t1);
    timing.sparsify_ns = static_cast<std::int64_t>(t3 - t2);
    timing.publish_ns = static_cast<std::int64_t>(t4 - t3);
    timing.total_ns = static_cast<std::int64_t>(t4 - std::min(from, t4));
    timing.solver_work_units = static_cast<std::int64_t>(work);
    timing.solver_phases = static_cast<std::int64_t>(phases);
    const int len = timing.encode(small.data(), 0, static_cast<int>(small.size()));
    if (len > 0) lcm.publish(config.timing_channel, small.data(), static_cast<unsigned>(len));
    if (config.max_keyframes > 0 && counters.decisions_published >= config.max_keyframes) finished = true;
  }

  void on_map_event(const void* data, std::uint32_t size, std::uint64_t arrival) {
    decide_pending();  // it was queued before this event, which never supersedes it
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
    const std::uint64_t hash = message_hash(data, size);
    const OrderTracker::Verdict v = order.check(event.publisher_id, event.sequence, event.utime, hash, arrival, false);
    r = v.reason;
    if (r == RejectReason::kNone) r = check_map_event(event);
    MapEventItems items;
    items.merged_from = merged_from.data();
    items.merged_into = merged_into.data();
    items.removed = removed.data();
    items.refused_id = ack.refused_id.data();
    items.refused_reason = ack.refused_reason.data();
    bool cleared = false;
    std::uint32_t merges_applied = 0;
    std::uint32_t into_excluded = 0;  // merges into an excluded point: their sources leave the window
    if (r == RejectReason::kNone && event.reset) {
      sliding.clear();
      culls.clear();
      deferred.clear();
      sparsifier.forget_history();
      cleared = true;
    } else if (r == RejectReason::kNone) {
      split_map_event(event, sliding.window(), &culls, id_scratch.data(), items);
      if (deferring) into_excluded = split_merges_into_excluded(items);
      SlidingWindow::Edit e;
      e.deleted = reinterpret_cast<const core::PointId*>(event.deleted_point_id.data());
      e.deleted_count = static_cast<std::uint32_t>(event.num_deleted_points);
      e.merged_from = reinterpret_cast<const core::PointId*>(items.merged_from);
      e.merged_into = reinterpret_cast<const core::PointId*>(items.merged_into);
      e.merged_count = items.merged;
      e.removed = reinterpret_cast<const core::KeyframeId*>(items.removed);
      e.removed_count = items.removed_count;
      core::Status s = sliding.edit(e);
      merges_applied = sliding.merges_effective();
      if (s == core::Status::kOk && into_excluded > 0) {
        // Applied where the source was in the window (as merges_effective counts).
        std::uint32_t present = 0;
        for (std::uint32_t i = 0; i < into_excluded; ++i) {
          merged_kept_into[i].present = sliding.window().point_views(static_cast<core::PointId>(merged_kept[i])) > 0;
          present += merged_kept_into[i].present ? 1 : 0;
        }
        s = sliding.drop_points(reinterpret_cast<const core::PointId*>(merged_kept.data()), into_excluded);
        if (s == core::Status::kOk) merges_applied += present;
      }
      if (s != core::Status::kOk) r = reason_of(s);
      if (s == core::Status::kOk && deferring) forget_edited_points(items, into_excluded);
    }
    if (r != RejectReason::kNone) {
      reject("map_event_t", config.event_channel, size, r, true, event.sequence, 0);
      items = MapEventItems{};
      publish_ack(r, items, false, 0);
      return;
    }
    order.accept(v, event.publisher_id, event.sequence, event.utime, hash, arrival, false);
    counters.event_items_refused += items.refused;
    publish_ack(r, items, cleared, merges_applied);
  }

  // Deferred culling and a map event's valid items: a merge into an excluded
  // point is taken out of the merges and its source moved to merged_kept
  // (its target to merged_kept_into), to be dropped from the window (its
  // observations now belong to a point out of BA). Returns how many were.
  std::uint32_t split_merges_into_excluded(MapEventItems& items) {
    std::uint32_t kept = 0, moved = 0;
    for (std::uint32_t i = 0; i < items.merged; ++i) {
      if (deferred.contains(static_cast<core::PointId>(items.merged_into[i]))) {
        merged_kept_into[moved].into = items.merged_into[i];
        merged_kept[moved++] = items.merged_from[i];
      } else {
        items.merged_from[kept] = items.merged_from[i];
        items.merged_into[kept] = items.merged_into[i];
        ++kept;
      }
    }
    items.merged = kept;
    return moved;
  }

  // After the edit succeeded: the deleted points and merge sources are
  // forgotten (the VO removed them itself); an excluded target takes over
  // its source's matches, so it is never deleted while they are recent.
  void forget_edited_points(const MapEventItems& items, std::uint32_t into_excluded) {
    const auto nd = static_cast<std::uint32_t>(event.num_deleted_points);
    for (std::uint32_t i = 0; i < nd; ++i) (void)deferred.forget(static_cast<core::PointId>(event.deleted_point_id[i]));
    for (std::uint32_t i = 0; i < items.merged; ++i) (void)deferred.forget(static_cast<core::PointId>(items.merged_from[i]));
    for (std::uint32_t i = 0; i < into_excluded; ++i) {
      (void)deferred.merge(static_cast<core::PointId>(merged_kept[i]),
                           static_cast<core::PointId>(merged_kept_into[i].into), merged_kept_into[i].present);
    }
  }

  // `cleared`: this event reset the window; `merges`: merges that changed it.
  void publish_ack(RejectReason r, const MapEventItems& items, bool cleared, std::uint32_t merges) {
    using A = keepless::map_event_ack_t;
    ack.sequence = event.sequence;
    ack.utime = event.utime;
    ack.publisher_id = event.publisher_id;
    ack.reset = cleared;
    ack.status = r != RejectReason::kNone ? A::STATUS_REJECTED : items.refused > 0 ? A::STATUS_PARTIAL
                                                                                    : A::STATUS_APPLIED;
    ack.reject_reason = r != RejectReason::kNone ? static_cast<std::int8_t>(r) : std::int8_t{-1};
    const bool applied = r == RejectReason::kNone && !event.reset;
    ack.deleted_applied = applied ? event.num_deleted_points : 0;
    ack.merged_applied = static_cast<std::int32_t>(merges);
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
    const std::uint64_t now = clock->now_ns();
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
    status.sequence_gaps = static_cast<std::int64_t>(std::min<std::uint64_t>(order.sequence_gaps(), INT64_MAX));
    status.keyframes_skipped = static_cast<std::int64_t>(counters.keyframes_skipped);
    status.stream_restarts = static_cast<std::int64_t>(order.restarts() + order.resyncs());
    status.stream_conflicts = static_cast<std::int64_t>(counters.not_owner);
    status.publishers_seen = static_cast<std::int64_t>(order.owners_seen());
    status.publishers_active = order.owned() ? 1 : 0;
    status.stale_observations = static_cast<std::int64_t>(counters.stale_observations);
    status.event_items_refused = static_cast<std::int64_t>(counters.event_items_refused);
    const core::Window& w = sliding.window();
    status.window_keyframes = static_cast<std::int32_t>(w.keyframe_count());
    status.window_points = static_cast<std::int32_t>(w.distinct_points());
    status.window_observations = static_cast<std::int32_t>(w.total_observations());
    status.capacity_keyframes = static_cast<std::int32_t>(capacities.max_keyframes);
    status.capacity_points = static_cast<std::int32_t>(capacities.max_points);
    status.capacity_observations = static_cast<std::int32_t>(capacities.max_observations);
    status.capacity_pair_arcs = static_cast<std::int32_t>(capacities.max_pair_arcs);
    status.memory_bytes = static_cast<std::int64_t>(memory_bytes());
    status.latency_p50_ns = static_cast<std::int64_t>(latency.quantile(0.5));
    status.latency_p99_ns = static_cast<std::int64_t>(latency.quantile(0.99));
    status.latency_max_ns = static_cast<std::int64_t>(latency.max());
    status.points_excluded = static_cast<std::int64_t>(counters.points_excluded);
    status.points_deleted = static_cast<std::int64_t>(counters.points_deleted);
    status.deferred_points = static_cast<std::int32_t>(deferred.size());
    status.capacity_deferred = static_cast<std::int32_t>(deferring ? deferred.capacity() : 0);
    status.deferred_refused = static_cast<std::int64_t>(deferred.refused());
    const int len = status.encode(small.data(), 0, static_cast<int>(small.size()));
    if (len > 0) lcm.publish(config.status_channel, small.data(), static_cast<unsigned>(len));
    next_status_ns = now + std::uint64_t{config.status_period_ms} * 1000000ull;
  }

  std::size_t memory_bytes() const {
    return sliding.memory_bytes() + sparsifier.memory_bytes() + out.size() + small.size() +
           observations.size() * sizeof(core::Observation) + id_scratch.size() * sizeof(std::uint64_t) +
           (kf.point_id.capacity() * 16) + kf.depth.capacity() * 4 + kf.intrinsics.capacity() * 8 +
           kf.unmapped_u.capacity() * 8 + unmapped.size() * sizeof(core::Keypoint) +
           kf.tracked.capacity() + tracked.size() + kf.track_length.capacity() * 16 +
           quality.size() * sizeof(core::PointQuality) +
           (event.deleted_point_id.capacity() + event.merged_from_id.capacity() +
            event.merged_into_id.capacity() + event.removed_keyframe_id.capacity()) * 8 +
           (decision.window_keyframe_id.capacity() + decision.culled_point_id.capacity()) * 8 +
           (merged_from.size() + merged_into.size() + removed.size()) * 8 + ack.refused_id.capacity() * 9 +
           ack_out.size() + pending_window.size() * 8 + culls.memory_bytes() + order.memory_bytes() +
           (decision.excluded_point_id.capacity() + decision.deleted_point_id.capacity() + merged_kept.size()) * 8 +
           merged_kept_into.size() * sizeof(KeptMerge) +
           deferred.memory_bytes();
  }

  // The arrival stamp: when the handler runs, moved back by the time the
  // message already waited in LCM's queue (LCM stamps its receipt on the wall
  // clock: the kernel's for udpm, the publish for memq), at most back to when
  // the queue was last seen empty. An injected clock is the only time there
  // is: its reading alone.
  std::uint64_t arrival_ns(const lcm_recv_buf_t* rbuf) const {
    const std::uint64_t now = clock->now_ns();
    if (clock != &own_clock) return now;
    timespec wall{};
    clock_gettime(CLOCK_REALTIME, &wall);
    const std::int64_t wall_us = static_cast<std::int64_t>(wall.tv_sec) * 1000000 + wall.tv_nsec / 1000;
    return queued_arrival_ns(now, wall_us, rbuf->recv_utime, queue_empty_ns);
  }

  static void keyframe_cb(const lcm_recv_buf_t* rbuf, const char*, void* user) {
    Impl& n = *static_cast<Impl*>(user);
    n.on_keyframe(rbuf->data, rbuf->data_size, n.arrival_ns(rbuf), n.draining);
  }
  static void event_cb(const lcm_recv_buf_t* rbuf, const char*, void* user) {
    Impl& n = *static_cast<Impl*>(user);
    n.on_map_event(rbuf->data, rbuf->data_size, n.arrival_ns(rbuf));
  }

  lcm::LCM& lcm;
  NodeConfig config;
  core::Capacities capacities;
  MessageLimits limits;
  SlidingWindow sliding;
  core::Sparsifier sparsifier;
  // Arrival stamps, deadlines and latencies: CLOCK_MONOTONIC unless a clock
  // was injected.
  MonotonicClock own_clock;
  // The last time LCM's queue was seen empty (start, then every spin that
  // found nothing more): no message handled later waited longer than since.
  std::uint64_t queue_empty_ns = 0;
  const solver::Clock* clock;
  core::Window empty_window;  // what a keyframe taking the window over is checked against
  solver::Budget budget;
  keepless::keyframe_t kf{};
  keepless::map_event_t event{};
  keepless::decision_t decision{};
  keepless::decision_timing_t timing{};
  keepless::status_t status{};
  std::vector<core::Observation> observations;
  std::vector<core::Keypoint> unmapped;  // [max_unmapped]
  std::vector<std::uint8_t> tracked;     // [max_observations], the accepted observations' flags
  std::vector<core::PointQuality> quality;  // [max_observations], the accepted observations' quality
  std::vector<std::uint64_t> id_scratch;
  std::vector<std::uint8_t> out;
  std::array<std::uint8_t, 1024> small{};
  std::size_t max_decision = 0;
  OrderTracker order;
  RecentIds culls;
  bool deferring;                  // --defer T
  core::DeferredCulls deferred;    // excluded points not yet deleted (capacity 0 unless deferring)
  std::vector<std::int64_t> merged_kept;  // [max_event_ids] merge sources into excluded points
  struct KeptMerge {
    std::int64_t into = 0;  // the excluded target
    bool present = false;   // the source had observations in the window
  };
  std::vector<KeptMerge> merged_kept_into;  // [max_event_ids], beside merged_kept
  keepless::map_event_ack_t ack{};
  std::vector<std::uint8_t> ack_out;
  std::vector<std::int64_t> merged_from, merged_into, removed;  // a map event's items to apply
  // spin_once's drain: the newest accepted keyframe, in the window, undecided.
  DecisionRequest pending;
  std::uint64_t pending_arrival = 0, pending_t0 = 0, pending_t1 = 0;
  std::uint32_t pending_evicted = 0;
  std::vector<std::int64_t> pending_window;  // the window's keyframe ids after it entered
  std::uint32_t pending_keyframes = 0;
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

Node::Node(lcm::LCM& lcm, const NodeConfig& config, const solver::Clock* clock)
    : impl_(std::make_unique<Impl>(lcm, config, clock)) {}

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
  impl_->queue_empty_ns = impl_->clock->now_ns();  // nothing is queued before the subscriptions
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
  const std::uint64_t now = n.clock->now_ns();
  if (now >= n.next_status_ns) n.publish_status(false);
  const std::uint64_t until_status_ms = (n.next_status_ns - std::min(n.next_status_ns, now)) / 1000000ull;
  const int wait = static_cast<int>(std::min<std::uint64_t>(static_cast<std::uint64_t>(std::max(timeout_ms, 0)),
                                                            until_status_ms));
  // With a latency target, drain what is queued before deciding: of
  // consecutive accepted keyframes only the newest is decided, the older
  // ones are answered SKIPPED. (Without one, replays stay byte-for-byte:
  // every keyframe is decided.)
  n.draining = n.config.latency_target_ms > 0;
  const int got = n.lcm.handleTimeout(wait);
  lcm_t* l = n.lcm.getUnderlyingLCM();
  if (got <= 0) n.queue_empty_ns = n.clock->now_ns();
  for (std::uint32_t i = 0; got > 0 && n.draining && i < 2 * n.config.queue_capacity; ++i) {
    if (lcm_handle_timeout(l, 0) <= 0) {
      n.queue_empty_ns = n.clock->now_ns();
      break;
    }
  }
  n.draining = false;
  n.decide_pending();
  return got;
}

void Node::publish_status(bool final) { impl_->publish_status(final); }
bool Node::finished() const { return impl_->finished; }
void Node::handle_keyframe(const void* data, std::uint32_t size) {
  impl_->on_keyframe(data, size, impl_->clock->now_ns(), false);
}
void Node::handle_map_event(const void* data, std::uint32_t size) {
  impl_->on_map_event(data, size, impl_->clock->now_ns());
}
const core::Window& Node::window() const { return impl_->sliding.window(); }
const NodeCounters& Node::counters() const { return impl_->counters; }
const LatencyHistogram& Node::latency() const { return impl_->latency; }
const OrderTracker& Node::order() const { return impl_->order; }
const RecentIds& Node::cull_memory() const { return impl_->culls; }
const core::DeferredCulls& Node::deferred_culls() const { return impl_->deferred; }
std::size_t Node::memory_bytes() const { return impl_->memory_bytes(); }
std::size_t Node::max_decision_bytes() const { return impl_->max_decision; }

}  // namespace keepless::platform
