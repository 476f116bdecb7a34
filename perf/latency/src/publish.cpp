#include "publish.hpp"

#include <cstring>
#include <vector>

#ifdef KEEPLESS_HAVE_LCM
#include "keepless/decision_t.hpp"
#include "keepless/platform/decision_message.hpp"
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
  e.reserved = platform::reserve_decision(e.msg, c);
#else
  e.reserved = 128 + 8 * (std::size_t{c.max_keyframes} + c.max_points);
#endif
  e.buffer.resize(e.reserved);
}

DecisionEncoder::~DecisionEncoder() = default;

std::size_t DecisionEncoder::encode(std::int64_t sequence, const core::Window& window,
                                    const core::Sparsifier& s, core::Status status) {
  Impl& e = *impl_;
#ifdef KEEPLESS_HAVE_LCM
  // Filled by the same function as keepless_node's; the stream has no
  // utime, so the sequence stands in for it.
  const std::uint32_t k = window.keyframe_count();
  platform::DecisionRequest request;
  request.sequence = sequence;
  request.keyframe_id = k > 0 ? static_cast<std::int64_t>(window.keyframe(k - 1).id) : 0;
  request.utime = sequence;
  platform::fill_decision(e.msg, request, window, s, status);
  const int n = e.msg.encode(e.buffer.data(), 0, static_cast<int>(e.buffer.size()));
  return n > 0 ? static_cast<std::size_t>(n) : 0;
#else
  const core::Summary& sum = s.summary();
  const core::PointDecision* d = s.decisions();
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
