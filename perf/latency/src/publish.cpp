#include "publish.hpp"

#include <cstring>
#include <vector>

#ifdef KEEPLESS_HAVE_LCM
#include "keepless/decision_t.hpp"
#endif

namespace keepless::perf {

struct DecisionEncoder::Impl {
  std::vector<std::uint8_t> buffer;
#ifdef KEEPLESS_HAVE_LCM
  keepless::decision_t msg{};
#endif
  std::size_t reserved = 0;
};

DecisionEncoder::DecisionEncoder(const core::Capacities& c) : impl_(std::make_unique<Impl>()) {
  Impl& e = *impl_;
#ifdef KEEPLESS_HAVE_LCM
  e.msg.window_keyframe_id.reserve(c.max_keyframes);
  e.msg.culled_point_id.reserve(c.max_points);
  e.msg.num_window_keyframes = 0;
  e.msg.num_culled = 0;
  e.reserved = static_cast<std::size_t>(e.msg.getEncodedSize()) +
               8 * (std::size_t{c.max_keyframes} + c.max_points);
#else
  e.reserved = 128 + 8 * (std::size_t{c.max_keyframes} + c.max_points);
#endif
  e.buffer.resize(e.reserved);
}

DecisionEncoder::~DecisionEncoder() = default;

std::size_t DecisionEncoder::encode(std::int64_t sequence, const core::Window& window,
                                    const core::Sparsifier& s, core::Status status) {
  Impl& e = *impl_;
  const core::Summary& sum = s.summary();
  const core::PointDecision* d = s.decisions();
#ifdef KEEPLESS_HAVE_LCM
  keepless::decision_t& m = e.msg;
  m.sequence = sequence;
  const std::uint32_t k = window.keyframe_count();
  m.keyframe_id = k > 0 ? static_cast<std::int64_t>(window.keyframe(k - 1).id) : 0;
  m.utime = sequence;
  m.status = status == core::Status::kOk ? keepless::decision_t::STATUS_OPTIMAL
                                         : keepless::decision_t::STATUS_BUDGET_EXHAUSTED;
  m.reject_reason = -1;
  m.points = static_cast<std::int32_t>(sum.points);
  m.evaluated = static_cast<std::int32_t>(sum.evaluated);
  m.kept = static_cast<std::int32_t>(sum.kept);
  m.culled = static_cast<std::int32_t>(sum.culled);
  m.skipped = static_cast<std::int32_t>(sum.skipped);
  m.pairs = static_cast<std::int32_t>(sum.pairs);
  m.max_flow = sum.max_flow;
  m.total_cost = sum.total_cost;
  m.window_keyframe_id.resize(k);  // within the reserved capacity: no allocation
  for (std::uint32_t i = 0; i < k; ++i) m.window_keyframe_id[i] = static_cast<std::int64_t>(window.keyframe(i).id);
  m.num_window_keyframes = static_cast<std::int32_t>(k);
  m.culled_point_id.resize(sum.culled);
  std::uint32_t c = 0;
  for (std::uint32_t i = 0; i < s.decision_count(); ++i) {
    if (d[i].verdict == core::Verdict::kCull) m.culled_point_id[c++] = static_cast<std::int64_t>(d[i].point);
  }
  m.num_culled = static_cast<std::int32_t>(c);
  const int n = m.encode(e.buffer.data(), 0, static_cast<int>(e.buffer.size()));
  return n > 0 ? static_cast<std::size_t>(n) : 0;
#else
  std::size_t at = 0;
  const auto put = [&e, &at](std::uint64_t x) {
    std::memcpy(e.buffer.data() + at, &x, 8);
    at += 8;
  };
  put(static_cast<std::uint64_t>(sequence));
  put(static_cast<std::uint64_t>(status));
  put(sum.kept);
  put(sum.culled);
  for (std::uint32_t i = 0; i < window.keyframe_count(); ++i) put(window.keyframe(i).id);
  for (std::uint32_t i = 0; i < s.decision_count(); ++i) {
    if (d[i].verdict == core::Verdict::kCull) put(d[i].point);
  }
  return at;
#endif
}

std::size_t DecisionEncoder::memory_bytes() const {
  const Impl& e = *impl_;
  std::size_t bytes = sizeof(Impl) + e.buffer.capacity();
#ifdef KEEPLESS_HAVE_LCM
  bytes += 8 * (e.msg.window_keyframe_id.capacity() + e.msg.culled_point_id.capacity());
#endif
  return bytes;
}

const char* DecisionEncoder::format() {
#ifdef KEEPLESS_HAVE_LCM
  return "lcm decision_t";
#else
  return "raw bytes (no LCM)";
#endif
}

}  // namespace keepless::perf
