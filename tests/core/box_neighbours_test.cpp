// BoxCounter (core/src/box_neighbours.hpp) against the definition: N(p, f)
// is the number of other keypoints q of the frame with in_box(q.u - o.u,
// q.v - o.v, w, h), tested pair by pair. Frames: lattices whose box borders
// land exactly, clusters, duplicates, coordinates a few ulps either side of
// a border (where q - o rounds onto the border), tiny, huge and signed
// values, spans that overflow, and boxes from 0 x 0 to the int32 maximum.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "box_neighbours.hpp"
#include "keepless/core/costs.hpp"

namespace keepless::core {
namespace {

std::vector<std::uint32_t> brute_force(const std::vector<Observation>& obs, std::int32_t w,
                                       std::int32_t h) {
  std::vector<std::uint32_t> n(obs.size(), 0);
  for (std::size_t i = 0; i < obs.size(); ++i) {
    for (std::size_t j = 0; j < obs.size(); ++j) {
      if (j != i && in_box(obs[j].u - obs[i].u, obs[j].v - obs[i].v, w, h)) ++n[i];
    }
  }
  return n;
}

::testing::AssertionResult exact(BoxCounter& counter, const std::vector<Observation>& obs,
                                 std::int32_t w, std::int32_t h) {
  std::vector<std::uint32_t> got(obs.size() + 1, 12345);
  counter.count(obs.data(), static_cast<std::uint32_t>(obs.size()), w, h, got.data());
  if (got.back() != 12345) return ::testing::AssertionFailure() << "wrote past the end";
  const std::vector<std::uint32_t> want = brute_force(obs, w, h);
  for (std::size_t i = 0; i < obs.size(); ++i) {
    if (got[i] != want[i]) {
      return ::testing::AssertionFailure()
             << "box " << w << "x" << h << ", keypoint " << i << " of " << obs.size() << " at ("
             << obs[i].u << ", " << obs[i].v << "): N " << got[i] << ", want " << want[i];
    }
  }
  return ::testing::AssertionSuccess();
}

Observation at(double u, double v) { return Observation{0, u, v}; }

const std::int32_t kBoxes[][2] = {
    {64, 48}, {0, 0}, {1, 1},       {63, 47},
    {2, 0},   {0, 7}, {1000, 1000}, {std::numeric_limits<std::int32_t>::max(), 3}};

TEST(BoxCounter, EmptyAndSingleFrames) {
  BoxCounter counter(4);
  std::uint32_t out[2] = {7, 7};
  counter.count(nullptr, 0, 64, 48, out);
  EXPECT_EQ(out[0], 7u);  // nothing written
  const Observation one = at(3, 4);
  counter.count(&one, 1, 64, 48, out);
  EXPECT_EQ(out[0], 0u);
}

TEST(BoxCounter, LatticeBordersAreInside) {
  // An 8 x 6 pixel lattice: with the 64 x 48 box, neighbours sit exactly on
  // the borders; duplicates and half-pixel offsets too.
  std::mt19937_64 rng(1);
  BoxCounter counter(400);
  for (int round = 0; round < 20; ++round) {
    std::vector<Observation> obs;
    const int n = 1 + static_cast<int>(rng() % 400);
    for (int i = 0; i < n; ++i) {
      double u = 8.0 * static_cast<double>(rng() % 40);
      const double v = 6.0 * static_cast<double>(rng() % 40);
      if (rng() % 10 == 0) u += 0.5;
      obs.push_back(at(u, v));
    }
    for (const auto& box : kBoxes) ASSERT_TRUE(exact(counter, obs, box[0], box[1]));
  }
}

TEST(BoxCounter, ClusteredAndUniformKeypoints) {
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> image(0.0, 640.0), spread(-3.0, 3.0);
  BoxCounter counter(1500);
  for (int round = 0; round < 8; ++round) {
    std::vector<Observation> obs;
    const int clusters = 1 + round;
    const int n = 200 + 160 * round;
    for (int i = 0; i < n; ++i) {
      if (i % 3 == 0) {
        obs.push_back(at(image(rng), image(rng) * 0.75));
      } else {
        const double cu = 40.0 * static_cast<double>(i % clusters),
                     cv = 30.0 * static_cast<double>(i % clusters);
        obs.push_back(at(cu + spread(rng), cv + spread(rng)));
      }
    }
    ASSERT_TRUE(exact(counter, obs, 64, 48));
    ASSERT_TRUE(exact(counter, obs, 5, 3));
  }
}

// Keypoints a few ulps either side of base + k * half for bases from tiny to
// huge and of both signs: where q - o is inexact and rounds onto (or off)
// the border.
TEST(BoxCounter, RoundingAtTheBorder) {
  const double bases[] = {0.0, -0.0, 1e-300, 1e-20,  0.1,   3.0,
                          1e5, 1e15, -1e15,  4.5e15, 1e300, -7.25};
  std::mt19937_64 rng(3);
  BoxCounter counter(400);
  for (const auto& box : kBoxes) {
    const double half_w = 0.5 * box[0], half_h = 0.5 * box[1];
    for (double base : bases) {
      std::vector<Observation> obs;
      for (int k = -2; k <= 2; ++k) {
        for (int ulps = -3; ulps <= 3; ++ulps) {
          double u = base + k * half_w, v = base - k * half_h;
          for (int s = 0; s < std::abs(ulps); ++s) {
            u = std::nextafter(u, ulps > 0 ? HUGE_VAL : -HUGE_VAL);
            v = std::nextafter(v, ulps > 0 ? -HUGE_VAL : HUGE_VAL);
          }
          obs.push_back(at(u, v));
          obs.push_back(at(u, base + static_cast<double>(rng() % 3) * half_h));
          obs.push_back(at(base + static_cast<double>(rng() % 3) * half_w, v));
        }
      }
      obs.push_back(at(1e-20, 1e-20));  // tiny next to 0 and to the borders
      obs.push_back(at(half_w + 1e-20, -half_h - 1e-20));
      ASSERT_TRUE(exact(counter, obs, box[0], box[1])) << "base " << base;
    }
  }
}

// Spans wider than a double (the quantised sort degenerates to one run),
// outliers far from a cluster, and identical keypoints.
TEST(BoxCounter, ExtremeSpansAndDuplicates) {
  const double max = std::numeric_limits<double>::max();
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> image(0.0, 100.0);
  BoxCounter counter(500);
  for (int round = 0; round < 6; ++round) {
    std::vector<Observation> obs;
    for (int i = 0; i < 300; ++i) obs.push_back(at(image(rng), image(rng)));
    obs.push_back(at(max, -max));
    obs.push_back(at(-max, max));
    obs.push_back(at(max, max));
    obs.push_back(at(1e300 * round, -1e-300));
    for (int i = 0; i < 50; ++i) obs.push_back(at(12.5, 7.25));  // identical keypoints
    if (round % 2 == 1) {
      for (Observation& o : obs) std::swap(o.u, o.v);
    }
    for (const auto& box : kBoxes) ASSERT_TRUE(exact(counter, obs, box[0], box[1]));
  }
  std::vector<Observation> same(40, at(-3.0, 2.0));
  ASSERT_TRUE(exact(counter, same, 0, 0));
  ASSERT_TRUE(exact(counter, same, 64, 48));
}

// The counter is reused frame after frame at any size up to its capacity.
TEST(BoxCounter, ReuseAcrossFrameSizes) {
  std::mt19937_64 rng(5);
  BoxCounter counter(1200);
  for (int round = 0; round < 10; ++round) {
    const std::uint32_t n = round % 3 == 0 ? 1200 : static_cast<std::uint32_t>(rng() % 1200);
    std::vector<Observation> obs;
    for (std::uint32_t i = 0; i < n; ++i) {
      obs.push_back(
          at(static_cast<double>(rng() % 6400) / 10.0, static_cast<double>(rng() % 4800) / 10.0));
    }
    ASSERT_TRUE(exact(counter, obs, 64, 48)) << "round " << round;
  }
  EXPECT_GT(counter.memory_bytes(), 1200u * 8);
}

}  // namespace
}  // namespace keepless::core
