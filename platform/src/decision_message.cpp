#include "keepless/platform/decision_message.hpp"

#include <algorithm>

namespace keepless::platform {

namespace {

void set_request(keepless::decision_t& m, const DecisionRequest& r) {
  m.sequence = r.sequence;
  m.keyframe_id = r.keyframe_id;
  m.utime = r.utime;
  m.publisher_id = r.publisher_id;
}

// Within the capacity reserved for max_keyframes: no allocation.
void set_window(keepless::decision_t& m, const core::Window& w) {
  const std::uint32_t k = w.keyframe_count();
  m.window_keyframe_id.resize(k);
  for (std::uint32_t i = 0; i < k; ++i) m.window_keyframe_id[i] = static_cast<std::int64_t>(w.keyframe(i).id);
  m.num_window_keyframes = static_cast<std::int32_t>(k);
}

void clear_counts(keepless::decision_t& m) {
  m.points = m.evaluated = m.kept = m.culled = m.skipped = m.pairs = 0;
  m.max_flow = m.total_cost = 0;
  m.culled_point_id.resize(0);
  m.num_culled = 0;
  m.excluded_point_id.resize(0);
  m.num_excluded = 0;
  m.deleted_point_id.resize(0);
  m.num_deleted = 0;
}

}  // namespace

std::size_t reserve_decision(keepless::decision_t& msg, const core::Capacities& c,
                             std::uint32_t deferred_capacity) {
  msg.window_keyframe_id.clear();
  msg.culled_point_id.clear();
  msg.excluded_point_id.clear();
  msg.deleted_point_id.clear();
  msg.window_keyframe_id.reserve(c.max_keyframes);
  // A decision lists at most every window point; with deferral it culls
  // (excludes) those, and deletes at most what is held plus what it culls.
  msg.culled_point_id.reserve(c.max_points);
  std::size_t ids = c.max_points;
  if (deferred_capacity > 0) {
    msg.excluded_point_id.reserve(c.max_points);
    msg.deleted_point_id.reserve(std::size_t{c.max_points} + deferred_capacity);
    // culled_point_id is then empty: excluded and deleted are the lists.
    ids = std::size_t{c.max_points} + deferred_capacity;
  }
  msg.num_window_keyframes = 0;
  msg.num_culled = 0;
  msg.num_excluded = 0;
  msg.num_deleted = 0;
  return static_cast<std::size_t>(msg.getEncodedSize()) + 8 * (std::size_t{c.max_keyframes} + ids);
}

std::uint32_t fill_decision(keepless::decision_t& msg, const DecisionRequest& request,
                            const core::Window& window, const core::Sparsifier& s, core::Status result) {
  set_request(msg, request);
  msg.reject_reason = -1;
  set_window(msg, window);
  clear_counts(msg);
  if (result != core::Status::kOk && result != core::Status::kBudgetExhausted) {
    msg.status = result == core::Status::kCapacityExceeded ? keepless::decision_t::STATUS_CAPACITY_EXCEEDED
                                                           : keepless::decision_t::STATUS_REJECTED_INPUT;
    return 0;
  }
  msg.status = result == core::Status::kOk ? keepless::decision_t::STATUS_OPTIMAL
                                           : keepless::decision_t::STATUS_BUDGET_EXHAUSTED;
  const core::Summary& sum = s.summary();
  msg.points = static_cast<std::int32_t>(sum.points);
  msg.evaluated = static_cast<std::int32_t>(sum.evaluated);
  msg.kept = static_cast<std::int32_t>(sum.kept);
  msg.culled = static_cast<std::int32_t>(sum.culled);
  msg.skipped = static_cast<std::int32_t>(sum.skipped);
  msg.pairs = static_cast<std::int32_t>(sum.pairs);
  msg.max_flow = sum.max_flow;
  msg.total_cost = sum.total_cost;
  // sum.culled counts the kCull verdicts; the reserve bounds it (decisions
  // never exceed max_points), and the loop is bounded by both.
  const std::size_t room = std::min<std::size_t>(sum.culled, msg.culled_point_id.capacity());
  msg.culled_point_id.resize(room);
  const core::PointDecision* d = s.decisions();
  const std::uint32_t count = s.decision_count();
  std::uint32_t n = 0;
  for (std::uint32_t i = 0; i < count && n < room; ++i) {
    if (d[i].verdict == core::Verdict::kCull) msg.culled_point_id[n++] = static_cast<std::int64_t>(d[i].point);
  }
  msg.culled_point_id.resize(n);
  msg.num_culled = static_cast<std::int32_t>(n);
  return n;
}

std::uint32_t defer_culls(keepless::decision_t& msg, core::DeferredCulls& deferred) {
  // Within the reserve (reserve_decision with the deferred capacity). The
  // ids travel as int64 bit patterns; int64 and uint64 may alias.
  const auto culled = static_cast<std::uint32_t>(msg.culled_point_id.size());
  msg.excluded_point_id.resize(culled);
  msg.deleted_point_id.resize(msg.deleted_point_id.capacity());
  std::uint32_t n_excluded = 0;
  const std::uint32_t n_deleted = deferred.defer(
      reinterpret_cast<const core::PointId*>(msg.culled_point_id.data()), culled,
      reinterpret_cast<core::PointId*>(msg.excluded_point_id.data()), &n_excluded,
      reinterpret_cast<core::PointId*>(msg.deleted_point_id.data()));
  msg.excluded_point_id.resize(n_excluded);
  msg.num_excluded = static_cast<std::int32_t>(n_excluded);
  msg.deleted_point_id.resize(n_deleted);
  msg.num_deleted = static_cast<std::int32_t>(n_deleted);
  msg.culled_point_id.resize(0);
  msg.num_culled = 0;
  return n_deleted;
}

void fill_rejected_decision(keepless::decision_t& msg, const DecisionRequest& request,
                            const core::Window& window, RejectReason reason) {
  set_request(msg, request);
  msg.status = reason == RejectReason::kWindowCapacity ? keepless::decision_t::STATUS_CAPACITY_EXCEEDED
                                                       : keepless::decision_t::STATUS_REJECTED_INPUT;
  msg.reject_reason = static_cast<std::int8_t>(reason);
  set_window(msg, window);
  clear_counts(msg);
}

}  // namespace keepless::platform
