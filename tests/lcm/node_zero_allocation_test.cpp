// The node's receive path allocates nothing in steady state: after a warm-up,
// a counting global operator new (replaced for this binary only) sees zero
// calls while keyframes, map events, rejected messages and statuses go
// through LCM (memq://) into the node and decisions come out.

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <new>
#include <vector>

#include "keepless/platform/node.hpp"
#include "message_builders.hpp"

namespace {
std::atomic<bool> g_counting{false};
std::atomic<std::uint64_t> g_allocations{0};

void* counted(std::size_t size) {
  if (g_counting.load(std::memory_order_relaxed)) g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void* counted_aligned(std::size_t size, std::align_val_t align) {
  if (g_counting.load(std::memory_order_relaxed)) g_allocations.fetch_add(1, std::memory_order_relaxed);
  const auto a = static_cast<std::size_t>(align);
  const std::size_t rounded = (size + a - 1) / a * a;
  if (void* p = std::aligned_alloc(a, rounded == 0 ? a : rounded)) return p;
  throw std::bad_alloc();
}
}  // namespace

void* operator new(std::size_t size) { return counted(size); }
void* operator new[](std::size_t size) { return counted(size); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  try {
    return counted(size);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept {
  try {
    return counted(size);
  } catch (...) {
    return nullptr;
  }
}
void* operator new(std::size_t size, std::align_val_t a) { return counted_aligned(size, a); }
void* operator new[](std::size_t size, std::align_val_t a) { return counted_aligned(size, a); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }

namespace {

namespace kt = keepless::testing;

TEST(NodeZeroAllocation, SteadyStateReceivePathAllocatesNothing) {
  keepless::platform::NodeConfig c;
  c.latency_target_ms = 0;
  c.url = "memq://";
  c.window = 5;
  c.max_observations = 128;
  c.max_event_ids = 32;
  c.params.pair_capacity = 8;
  c.quiet = true;
  c.status_period_ms = 3600 * 1000;
  lcm::LCM bus(c.url);
  ASSERT_TRUE(bus.good());
  keepless::platform::Node node(bus, c);
  ASSERT_TRUE(node.start());

  // Every message encoded up front.
  std::vector<std::vector<std::uint8_t>> keyframes, events, bad;
  std::int64_t seq = 0;
  for (int i = 0; i < 40; ++i) {
    keyframes.push_back(kt::encode(kt::make_keyframe(++seq, i, kt::id_range(i * 10, 100 + (i % 3) * 10))));
    keepless::map_event_t e = kt::make_event(++seq);
    e.deleted_point_id = {i * 10 + 1, i * 10 + 2};
    e.merged_from_id = {i * 10 + 5};
    e.merged_into_id = {i * 10 + 4};
    kt::finalize(e);
    events.push_back(kt::encode(e));
  }
  keepless::keyframe_t nan = kt::make_keyframe(1, 999, kt::id_range(0, 10));
  nan.centre[0] = std::numeric_limits<double>::quiet_NaN();
  bad.push_back(kt::encode(nan));
  bad.push_back(kt::encode(kt::make_keyframe(1, 998, kt::id_range(0, 129))));
  std::vector<std::uint8_t> truncated = kt::encode(kt::make_keyframe(1, 997, kt::id_range(0, 10)));
  truncated.resize(truncated.size() - 3);
  bad.push_back(truncated);

  const std::string& kf_channel = c.keyframe_channel;
  const std::string& ev_channel = c.event_channel;
  auto pump = [&] {
    while (bus.handleTimeout(0) > 0) {
    }
  };
  auto step = [&](int i) {
    bus.publish(kf_channel, keyframes[i].data(), static_cast<unsigned>(keyframes[i].size()));
    pump();
    bus.publish(ev_channel, events[i].data(), static_cast<unsigned>(events[i].size()));
    pump();
    const auto& b = bad[static_cast<std::size_t>(i) % bad.size()];
    bus.publish(kf_channel, b.data(), static_cast<unsigned>(b.size()));
    pump();
  };
  // Warm-up: fill the window, touch every path once.
  for (int i = 0; i < 10; ++i) step(i);
  node.publish_status(false);
  pump();
  ASSERT_EQ(node.window().keyframe_count(), 5u);

  g_allocations = 0;
  g_counting = true;
  for (int i = 10; i < 40; ++i) step(i);
  node.publish_status(false);
  pump();
  g_counting = false;

  EXPECT_EQ(g_allocations.load(), 0u);
  EXPECT_EQ(node.counters().decisions_published, 40u + 14u);  // the 14 decodable bad ones are answered too
  EXPECT_EQ(node.counters().messages_rejected, 40u);
  EXPECT_GT(node.counters().points_culled, 0u);
}

}  // namespace
