// Window: atomic add_keyframe (every failure leaves it unchanged), removal with
// compaction, the distinct-point table under churn, fixed memory.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <random>
#include <tuple>
#include <vector>

#include "keepless/core/window.hpp"

namespace keepless::core {
namespace {

// Everything a caller can observe of a window.
struct Snapshot {
  struct Frame {
    KeyframeId id;
    std::vector<double> pose;
    std::vector<std::tuple<PointId, double, double>> obs;
    bool operator==(const Frame& o) const { return id == o.id && pose == o.pose && obs == o.obs; }
  };
  std::vector<Frame> frames;
  std::uint32_t total = 0;
  std::uint32_t distinct = 0;
  bool operator==(const Snapshot& o) const {
    return frames == o.frames && total == o.total && distinct == o.distinct;
  }
};

Snapshot snapshot(const Window& w) {
  Snapshot s;
  for (std::uint32_t i = 0; i < w.keyframe_count(); ++i) {
    Snapshot::Frame f;
    f.id = w.keyframe(i).id;
    f.pose.assign(w.keyframe(i).centre, w.keyframe(i).centre + 3);
    f.pose.insert(f.pose.end(), w.keyframe(i).orientation, w.keyframe(i).orientation + 4);
    for (std::uint32_t j = 0; j < w.observation_count(i); ++j) {
      const Observation& o = w.observations(i)[j];
      f.obs.emplace_back(o.point, o.u, o.v);
    }
    s.frames.push_back(f);
  }
  s.total = w.total_observations();
  s.distinct = w.distinct_points();
  return s;
}

Keyframe kf(KeyframeId id, double x = 0) {
  Keyframe k;
  k.id = id;
  k.centre[0] = x;
  return k;
}

std::vector<Observation> obs(std::initializer_list<PointId> points) {
  std::vector<Observation> v;
  for (PointId p : points) v.push_back({p, 10.0 * static_cast<double>(p), 5.0});
  return v;
}

Status add(Window& w, const Keyframe& k, const std::vector<Observation>& o) {
  return w.add_keyframe(k, o.data(), static_cast<std::uint32_t>(o.size()));
}

constexpr Capacities kSmall{3, 5, 8, 64};

TEST(Window, StartsEmpty) {
  Window w(kSmall);
  EXPECT_EQ(w.keyframe_count(), 0u);
  EXPECT_EQ(w.total_observations(), 0u);
  EXPECT_EQ(w.distinct_points(), 0u);
  EXPECT_EQ(w.find_keyframe(1), -1);
  EXPECT_EQ(w.capacities().max_observations, 8u);
}

TEST(Window, AddsInInsertionOrder) {
  Window w(kSmall);
  ASSERT_EQ(add(w, kf(30, 1), obs({1, 2, 3})), Status::kOk);
  ASSERT_EQ(add(w, kf(10, 2), obs({2, 3, 4})), Status::kOk);
  ASSERT_EQ(add(w, kf(20, 3), {}), Status::kOk);  // a keyframe without observations
  EXPECT_EQ(w.keyframe_count(), 3u);
  EXPECT_EQ(w.keyframe(0).id, 30u);
  EXPECT_EQ(w.keyframe(1).id, 10u);
  EXPECT_EQ(w.keyframe(2).id, 20u);
  EXPECT_EQ(w.keyframe(1).centre[0], 2.0);
  EXPECT_EQ(w.find_keyframe(10), 1);
  EXPECT_EQ(w.observation_count(1), 3u);
  EXPECT_EQ(w.observation_count(2), 0u);
  EXPECT_EQ(w.observations(1)[2].point, 4u);
  EXPECT_EQ(w.observations(1)[2].u, 40.0);
  EXPECT_EQ(w.total_observations(), 6u);
  EXPECT_EQ(w.distinct_points(), 4u);
}

TEST(Window, KeyframeCapacity) {
  Window w(kSmall);
  ASSERT_EQ(add(w, kf(1), obs({1})), Status::kOk);
  ASSERT_EQ(add(w, kf(2), obs({1})), Status::kOk);
  ASSERT_EQ(add(w, kf(3), obs({1})), Status::kOk);
  const Snapshot before = snapshot(w);
  EXPECT_EQ(add(w, kf(4), obs({1})), Status::kCapacityExceeded);
  EXPECT_EQ(add(w, kf(4), {}), Status::kCapacityExceeded);
  EXPECT_EQ(snapshot(w), before);
}

TEST(Window, ObservationCapacity) {
  Window w(kSmall);
  ASSERT_EQ(add(w, kf(1), obs({1, 2, 3, 4, 5})), Status::kOk);
  const Snapshot before = snapshot(w);
  EXPECT_EQ(add(w, kf(2), obs({1, 2, 3, 4})), Status::kCapacityExceeded);  // 9 > 8
  EXPECT_EQ(snapshot(w), before);
  EXPECT_EQ(add(w, kf(2), obs({1, 2, 3})), Status::kOk);  // exactly 8
  EXPECT_EQ(w.total_observations(), 8u);
  EXPECT_EQ(add(w, kf(3), obs({1})), Status::kCapacityExceeded);
  EXPECT_EQ(w.keyframe_count(), 2u);
}

// One keyframe's limit (Capacities::max_keyframe_observations) sizes the
// per-keyframe scratch: a keyframe beyond it is refused and changes nothing,
// whatever room the window has left; one within it adds as usual.
TEST(Window, KeyframeObservationCapacity) {
  Capacities c = kSmall;
  c.max_keyframe_observations = 3;
  EXPECT_EQ(keyframe_observation_limit(c), 3u);
  Window w(c);
  ASSERT_EQ(add(w, kf(1), obs({1, 2, 3})), Status::kOk);
  const Snapshot before = snapshot(w);
  EXPECT_EQ(add(w, kf(2), obs({1, 2, 3, 4})), Status::kCapacityExceeded);  // 4 > 3, 7 <= 8
  EXPECT_EQ(snapshot(w), before);
  EXPECT_EQ(add(w, kf(2), obs({4, 5})), Status::kOk);
  // 0 or a limit above the window's: the window's.
  c.max_keyframe_observations = 0;
  EXPECT_EQ(keyframe_observation_limit(c), kSmall.max_observations);
  c.max_keyframe_observations = kSmall.max_observations + 1;
  EXPECT_EQ(keyframe_observation_limit(c), kSmall.max_observations);
  // The scratch is what one keyframe needs, not the window's.
  c.max_keyframe_observations = 1;
  EXPECT_LT(Window(c).memory_bytes(), Window(kSmall).memory_bytes());
}

TEST(Window, DistinctPointCapacity) {
  Window w(kSmall);
  ASSERT_EQ(add(w, kf(1), obs({1, 2, 3, 4})), Status::kOk);
  const Snapshot before = snapshot(w);
  EXPECT_EQ(add(w, kf(2), obs({1, 6, 7})), Status::kCapacityExceeded);  // 6 distinct > 5
  EXPECT_EQ(snapshot(w), before);
  EXPECT_EQ(add(w, kf(2), obs({1, 2, 5})), Status::kOk);  // exactly 5 distinct
  EXPECT_EQ(w.distinct_points(), 5u);
  EXPECT_EQ(add(w, kf(3), obs({9})), Status::kCapacityExceeded);
  // Removing a keyframe frees the points only it observed.
  ASSERT_EQ(w.remove_keyframe(1), Status::kOk);
  EXPECT_EQ(w.distinct_points(), 3u);
  EXPECT_EQ(add(w, kf(3), obs({9, 8})), Status::kOk);
  EXPECT_EQ(w.distinct_points(), 5u);
}

TEST(Window, NonFiniteNumbersAreRejected) {
  const double bad[] = {std::numeric_limits<double>::quiet_NaN(),
                        std::numeric_limits<double>::infinity(),
                        -std::numeric_limits<double>::infinity()};
  Window w(kSmall);
  ASSERT_EQ(add(w, kf(1), obs({1, 2})), Status::kOk);
  const Snapshot before = snapshot(w);
  for (double x : bad) {
    for (int i = 0; i < 3; ++i) {
      Keyframe k = kf(2);
      k.centre[i] = x;
      EXPECT_EQ(add(w, k, obs({1})), Status::kInvalidArgument);
    }
    for (int i = 0; i < 4; ++i) {
      Keyframe k = kf(2);
      k.orientation[i] = x;
      EXPECT_EQ(add(w, k, obs({1})), Status::kInvalidArgument);
    }
    auto o = obs({1, 3, 4});
    o[2].u = x;
    EXPECT_EQ(add(w, kf(2), o), Status::kInvalidArgument);
    o = obs({1, 3, 4});
    o[1].v = x;
    EXPECT_EQ(add(w, kf(2), o), Status::kInvalidArgument);
    EXPECT_EQ(snapshot(w), before);
  }
  EXPECT_EQ(w.add_keyframe(kf(2), nullptr, 1), Status::kInvalidArgument);
  EXPECT_EQ(w.add_keyframe(kf(2), nullptr, 0), Status::kOk);
}

TEST(Window, DuplicatesAreRejected) {
  Window w(kSmall);
  ASSERT_EQ(add(w, kf(7), obs({1, 2})), Status::kOk);
  const Snapshot before = snapshot(w);
  EXPECT_EQ(add(w, kf(7), obs({3})), Status::kDuplicateKeyframe);
  EXPECT_EQ(add(w, kf(8), obs({3, 4, 3})), Status::kDuplicateObservation);
  EXPECT_EQ(add(w, kf(8), obs({1, 1})), Status::kDuplicateObservation);
  EXPECT_EQ(snapshot(w), before);
  EXPECT_EQ(add(w, kf(8), obs({1, 3})), Status::kOk);  // another keyframe may see point 1
}

TEST(Window, RemoveKeyframeCompacts) {
  Window w(Capacities{4, 16, 16, 64});
  ASSERT_EQ(add(w, kf(1, 1), obs({1, 2, 3})), Status::kOk);
  ASSERT_EQ(add(w, kf(2, 2), obs({3, 4})), Status::kOk);
  ASSERT_EQ(add(w, kf(3, 3), obs({4, 5, 6, 1})), Status::kOk);
  EXPECT_EQ(w.remove_keyframe(99), Status::kUnknownKeyframe);
  ASSERT_EQ(w.remove_keyframe(2), Status::kOk);
  EXPECT_EQ(w.keyframe_count(), 2u);
  EXPECT_EQ(w.find_keyframe(2), -1);
  EXPECT_EQ(w.find_keyframe(3), 1);
  EXPECT_EQ(w.keyframe(1).centre[0], 3.0);
  ASSERT_EQ(w.observation_count(1), 4u);
  EXPECT_EQ(w.observations(1)[0].point, 4u);
  EXPECT_EQ(w.observations(1)[3].point, 1u);
  EXPECT_EQ(w.observations(1)[3].u, 10.0);
  EXPECT_EQ(w.observations(0)[2].point, 3u);
  EXPECT_EQ(w.total_observations(), 7u);
  EXPECT_EQ(w.distinct_points(), 6u);  // 3 and 4 are still seen elsewhere
  ASSERT_EQ(w.remove_keyframe(1), Status::kOk);
  EXPECT_EQ(w.distinct_points(), 4u);  // 4, 5, 6, 1
  EXPECT_EQ(w.remove_keyframe(1), Status::kUnknownKeyframe);
  ASSERT_EQ(w.remove_keyframe(3), Status::kOk);
  EXPECT_EQ(w.keyframe_count(), 0u);
  EXPECT_EQ(w.total_observations(), 0u);
  EXPECT_EQ(w.distinct_points(), 0u);
  EXPECT_EQ(add(w, kf(2), obs({1})), Status::kOk);  // ids can be reused
}

TEST(Window, ClearEmptiesEverything) {
  Window w(kSmall);
  ASSERT_EQ(add(w, kf(1), obs({1, 2})), Status::kOk);
  w.clear();
  EXPECT_EQ(w.keyframe_count(), 0u);
  EXPECT_EQ(w.total_observations(), 0u);
  EXPECT_EQ(w.distinct_points(), 0u);
  EXPECT_EQ(add(w, kf(1), obs({1, 2, 3, 4, 5})), Status::kOk);
}

// A sliding window over many keyframes whose point ids collide in the hash
// table on purpose (multiples of 2^20): the distinct count and the stored
// observations follow a std::map model exactly, and memory never changes.
TEST(Window, ChurnMatchesModel) {
  const Capacities caps{6, 64, 200, 1024};
  Window w(caps);
  const std::size_t bytes = w.memory_bytes();
  EXPECT_GT(bytes, 0u);
  std::mt19937_64 rng(42);
  std::map<KeyframeId, std::vector<Observation>> model;
  std::vector<KeyframeId> order;
  KeyframeId next = 0;
  for (int step = 0; step < 3000; ++step) {
    if (order.size() == caps.max_keyframes || (!order.empty() && rng() % 3 == 0)) {
      const std::size_t victim = rng() % order.size();
      ASSERT_EQ(w.remove_keyframe(order[victim]), Status::kOk);
      model.erase(order[victim]);
      order.erase(order.begin() + static_cast<std::ptrdiff_t>(victim));
    } else {
      std::vector<Observation> o;
      const std::uint64_t n = rng() % 30;
      for (std::uint64_t i = 0; i < n; ++i) {
        const PointId p = (rng() % 80) << 20;
        bool dup = false;
        for (const auto& x : o) dup = dup || x.point == p;
        if (!dup) o.push_back({p, static_cast<double>(rng() % 640), static_cast<double>(rng() % 480)});
      }
      std::map<PointId, int> distinct;
      for (const auto& kv : model) {
        for (const auto& x : kv.second) distinct[x.point];
      }
      std::uint32_t total = 0;
      for (const auto& kv : model) total += static_cast<std::uint32_t>(kv.second.size());
      for (const auto& x : o) distinct[x.point];
      const bool fits = distinct.size() <= caps.max_points && total + o.size() <= caps.max_observations;
      const Status s = add(w, kf(next), o);
      ASSERT_EQ(s, fits ? Status::kOk : Status::kCapacityExceeded);
      if (fits) {
        model[next] = o;
        order.push_back(next);
      }
      ++next;
    }
    std::map<PointId, int> distinct;
    std::uint32_t total = 0;
    for (const auto& kv : model) {
      for (const auto& x : kv.second) distinct[x.point];
      total += static_cast<std::uint32_t>(kv.second.size());
    }
    ASSERT_EQ(w.distinct_points(), distinct.size());
    ASSERT_EQ(w.total_observations(), total);
    ASSERT_EQ(w.keyframe_count(), order.size());
    for (std::uint32_t s = 0; s < w.keyframe_count(); ++s) {
      ASSERT_EQ(w.keyframe(s).id, order[s]);
      const auto& o = model[order[s]];
      ASSERT_EQ(w.observation_count(s), o.size());
      for (std::uint32_t i = 0; i < o.size(); ++i) {
        ASSERT_EQ(w.observations(s)[i].point, o[i].point);
        ASSERT_EQ(w.observations(s)[i].u, o[i].u);
      }
    }
  }
  EXPECT_EQ(w.memory_bytes(), bytes);
}

TEST(Window, MemoryIsFixedAndScalesWithCapacities) {
  Window small(kSmall);
  Window big(Capacities{});
  EXPECT_GT(small.memory_bytes(), 0u);
  EXPECT_GT(big.memory_bytes(), small.memory_bytes());
  // Default capacities hold at least the pool and the keyframes.
  EXPECT_GE(big.memory_bytes(), std::size_t{40000} * sizeof(Observation) + 32 * sizeof(Keyframe));
  const std::size_t before = small.memory_bytes();
  ASSERT_EQ(add(small, kf(1), obs({1, 2, 3})), Status::kOk);
  ASSERT_EQ(small.remove_keyframe(1), Status::kOk);
  small.clear();
  EXPECT_EQ(small.memory_bytes(), before);
}

}  // namespace
}  // namespace keepless::core
