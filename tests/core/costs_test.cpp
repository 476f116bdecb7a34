// The three costs of section III-B at their edges, and N(p, f) as the network
// counts it (seen through c_s at a digit boundary).

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "keepless/core/costs.hpp"
#include "keepless/core/network.hpp"
#include "keepless/core/window.hpp"
#include "keepless/solver/min_cost_flow.hpp"
#include "reference_sparsifier.hpp"

namespace keepless::core {
namespace {

TEST(InBox, ClosedBordersAreInside) {
  EXPECT_TRUE(in_box(0, 0, 64, 48));
  EXPECT_TRUE(in_box(32, 0, 64, 48));
  EXPECT_TRUE(in_box(-32, 0, 64, 48));
  EXPECT_TRUE(in_box(0, 24, 64, 48));
  EXPECT_TRUE(in_box(0, -24, 64, 48));
  EXPECT_TRUE(in_box(32, -24, 64, 48));
  EXPECT_TRUE(in_box(-32, 24, 64, 48));
}

TEST(InBox, JustBeyondIsOutside) {
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(in_box(std::nextafter(32.0, inf), 0, 64, 48));
  EXPECT_FALSE(in_box(-std::nextafter(32.0, inf), 0, 64, 48));
  EXPECT_FALSE(in_box(0, std::nextafter(24.0, inf), 64, 48));
  EXPECT_FALSE(in_box(0, -std::nextafter(24.0, inf), 64, 48));
  EXPECT_FALSE(in_box(33, 0, 64, 48));
  EXPECT_FALSE(in_box(0, 25, 64, 48));
  EXPECT_FALSE(in_box(32, 24.5, 64, 48));
}

TEST(InBox, OddAndZeroSizes) {
  EXPECT_TRUE(in_box(31.5, 23.5, 63, 47));
  EXPECT_FALSE(in_box(31.75, 0, 63, 47));
  EXPECT_TRUE(in_box(0, 0, 0, 0));
  EXPECT_FALSE(in_box(std::numeric_limits<double>::denorm_min(), 0, 0, 0));
}

TEST(ConnectivityCost, HandTables) {
  std::int64_t t[8] = {};
  connectivity_costs(2, t);
  EXPECT_EQ(t[2], 1);
  connectivity_costs(3, t);  // c(2) = ceil(3/1 * 1) = 3
  EXPECT_EQ(t[3], 1);
  EXPECT_EQ(t[2], 3);
  connectivity_costs(4, t);  // 2, 6
  EXPECT_EQ(t[4], 1);
  EXPECT_EQ(t[3], 2);
  EXPECT_EQ(t[2], 6);
  connectivity_costs(5, t);  // ceil(5/3) = 2, ceil(4/2*2) = 4, 12
  EXPECT_EQ(t[5], 1);
  EXPECT_EQ(t[4], 2);
  EXPECT_EQ(t[3], 4);
  EXPECT_EQ(t[2], 12);
  connectivity_costs(6, t);  // ceil(6/4) = 2, ceil(5/3*2) = 4, 8, 24
  EXPECT_EQ(t[6], 1);
  EXPECT_EQ(t[5], 2);
  EXPECT_EQ(t[4], 4);
  EXPECT_EQ(t[3], 8);
  EXPECT_EQ(t[2], 24);
  connectivity_costs(7, t);  // ceil(7/5) = 2, 6/4*2 = 3 exactly, 5/3*3 = 5, 10, 30
  EXPECT_EQ(t[7], 1);
  EXPECT_EQ(t[6], 2);
  EXPECT_EQ(t[5], 3);
  EXPECT_EQ(t[4], 5);
  EXPECT_EQ(t[3], 10);
  EXPECT_EQ(t[2], 30);
}

// The ceilings compound: c_m(2) grows about as m^3/10 (not m^2/2), and
// kMaxPointViews is the largest m whose c_m(2) is within the solver's arc
// cost bound 2^30.
TEST(ConnectivityCost, GrowthAndTheSolversCostBound) {
  std::vector<std::int64_t> t(kMaxPointViews + 2);
  connectivity_costs(20, t.data());
  EXPECT_EQ(t[2], 840);
  connectivity_costs(1024, t.data());
  EXPECT_EQ(t[2], 108107574);
  connectivity_costs(kMaxPointViews, t.data());
  EXPECT_EQ(t[2], 1071887514);
  EXPECT_LE(t[2], std::int64_t{1} << 30);
  connectivity_costs(kMaxPointViews + 1, t.data());
  EXPECT_EQ(t[2], 1074123210);
  EXPECT_GT(t[2], std::int64_t{1} << 30);
}

TEST(ConnectivityCost, TooFewViewsWritesNothing) {
  std::int64_t t[3] = {-7, -7, -7};
  connectivity_costs(0, t);
  connectivity_costs(1, t);
  EXPECT_EQ(t[0], -7);
  EXPECT_EQ(t[1], -7);
  EXPECT_EQ(t[2], -7);
}

// For every m up to 64: c_m(m) = 1 and c_m(n) is the smallest integer with
// (n-1) c_m(n) >= (n+1) c_m(n+1), i.e. the ceiling, checked without dividing.
TEST(ConnectivityCost, IsTheExactCeilingForEveryM) {
  for (std::uint32_t m = 2; m <= 64; ++m) {
    std::vector<std::int64_t> t(m + 1, 0);
    connectivity_costs(m, t.data());
    EXPECT_EQ(t[m], 1);
    for (std::uint32_t n = 2; n < m; ++n) {
      const std::int64_t rhs = static_cast<std::int64_t>(n + 1) * t[n + 1];
      EXPECT_GE(static_cast<std::int64_t>(n - 1) * t[n], rhs) << "m=" << m << " n=" << n;
      EXPECT_LT(static_cast<std::int64_t>(n - 1) * (t[n] - 1), rhs) << "m=" << m << " n=" << n;
      EXPECT_EQ(t[n], test::ref_connectivity_cost(n, m));
    }
  }
}

TEST(SpatialCost, DigitBoundaries) {
  EXPECT_EQ(spatial_cost(0, 0), 0);        // log10(1)
  EXPECT_EQ(spatial_cost(0, 1000000), 0);
  EXPECT_EQ(spatial_cost(1, 8), 0);        // 9
  EXPECT_EQ(spatial_cost(2, 4), 0);        // 9
  EXPECT_EQ(spatial_cost(1, 9), 1);        // 10
  EXPECT_EQ(spatial_cost(3, 3), 1);        // 10
  EXPECT_EQ(spatial_cost(98, 1), 1);       // 99
  EXPECT_EQ(spatial_cost(2, 49), 1);       // 99
  EXPECT_EQ(spatial_cost(99, 1), 2);       // 100
  EXPECT_EQ(spatial_cost(11, 9), 2);       // 100
  EXPECT_EQ(spatial_cost(9, 111), 3);      // 1000
  EXPECT_EQ(spatial_cost(998, 1), 2);      // 999
}

TEST(SpatialCost, LargeCountsStayExact) {
  EXPECT_EQ(spatial_cost(1000000000, 1000000000), 18);  // 1e18 + 1
  EXPECT_EQ(spatial_cost(999999999, 1000000000), 17);   // 999999999000000001
  const std::uint64_t max32 = 0xffffffffULL;
  EXPECT_EQ(spatial_cost(max32, max32), 19);  // 1.8e19, still below 2^64
  const std::uint64_t max64 = ~std::uint64_t{0};
  EXPECT_EQ(spatial_cost(max64, max64), 38);  // 3.4e38, needs 128 bits
  EXPECT_EQ(spatial_cost(max64, 1), 19);      // 2^64 = 1.8e19
}

TEST(BaselineCost, HandValues) {
  const double o[3] = {0, 0, 0};
  const auto at = [&](double x, double y, double z) {
    const double c[3] = {x, y, z};
    return baseline_cost(o, c);
  };
  EXPECT_EQ(at(0, 0, 0), 10);    // 10 / 1
  EXPECT_EQ(at(1, 0, 0), 10);    // 10 / 1.1 = 9.09
  EXPECT_EQ(at(3, 4, 0), 7);     // d = 5: 10 / 1.5 = 6.67
  EXPECT_EQ(at(0, 6, 8), 5);     // d = 10: 10 / 2 exactly
  EXPECT_EQ(at(12, 0, 16), 4);   // d = 20: 3.33
  EXPECT_EQ(at(0, 0, -40), 2);   // d = 40: 10 / 5 exactly
  EXPECT_EQ(at(90, 0, 0), 1);    // d = 90: 10 / 10 exactly
  EXPECT_EQ(at(2, 3, 6), 6);     // d = 7: 10 / 1.7 = 5.88
  EXPECT_EQ(at(1e6, 0, 0), 1);
  const double a[3] = {1.5, -2, 3}, b[3] = {4.5, 2, 3};  // d = 5
  EXPECT_EQ(baseline_cost(a, b), 7);
  EXPECT_EQ(baseline_cost(b, a), 7);
  EXPECT_EQ(baseline_cost(a, a), 10);
}

// N(p, f) through the network: frame 0 holds p plus 8 neighbours that are
// clearly inside and one candidate keypoint; frame 1 gives N = 1. So c_s =
// floor(log10(N0 + 1)) is 1 exactly when the candidate counts (N0 = 9) and 0
// when it does not (N0 = 8), and the keypoint itself must not count.
class NeighbourCount : public ::testing::Test {
 protected:
  std::int64_t spatial_cost_with(double u0, double v0, const std::vector<Observation>& extra) {
    Window window(caps_);
    std::vector<Observation> f0{{1, u0, v0}};
    for (int i = 1; i <= 8; ++i) f0.push_back({100u + i, u0 + i, v0 - i});
    for (const auto& o : extra) f0.push_back(o);
    std::vector<Observation> f1{{1, 500, 400}, {7, 510, 410}, {8, 600, 400}};
    Keyframe k0, k1;
    k0.id = 10;
    k1.id = 11;
    k1.centre[0] = 3;
    EXPECT_EQ(window.add_keyframe(k0, f0.data(), static_cast<std::uint32_t>(f0.size())), Status::kOk);
    EXPECT_EQ(window.add_keyframe(k1, f1.data(), static_cast<std::uint32_t>(f1.size())), Status::kOk);
    PaperNetwork network(caps_);
    solver::MinCostFlow solver(PaperNetwork::solver_capacity(caps_));
    EXPECT_EQ(network.build(window, Params{}, solver), Status::kOk);
    EXPECT_EQ(network.pair_arc_count(), 1u);
    // The reference's all-pairs count must agree.
    const auto frames = test::ref_frames_of(window);
    const auto n0 = test::ref_nearby(frames[0], 0, Params{});
    EXPECT_EQ(test::ref_spatial_cost(n0, 1), network.arc_spatial_cost(0));
    return network.arc_spatial_cost(0);
  }
  Capacities caps_{4, 256, 256, 256};
};

TEST_F(NeighbourCount, SelfIsExcluded) {
  EXPECT_EQ(spatial_cost_with(320, 240, {}), 0);  // N0 = 8, not 9
}

TEST_F(NeighbourCount, CoLocatedOtherKeypointCounts) {
  EXPECT_EQ(spatial_cost_with(320, 240, {{50, 320, 240}}), 1);
}

TEST_F(NeighbourCount, BordersAreInside) {
  const double bases[][2] = {{320, 240}, {101.5, 77.25}, {0, 0}, {-64, -48}};
  const double inside[][2] = {{32, 0}, {-32, 0}, {0, 24}, {0, -24}, {32, 24}, {-32, -24}, {32, -24}};
  for (const auto& b : bases) {
    for (const auto& d : inside) {
      EXPECT_EQ(spatial_cost_with(b[0], b[1], {{50, b[0] + d[0], b[1] + d[1]}}), 1)
          << "base " << b[0] << "," << b[1] << " offset " << d[0] << "," << d[1];
    }
  }
}

TEST_F(NeighbourCount, JustBeyondIsOutside) {
  const double bases[][2] = {{320, 240}, {101.5, 77.25}, {0, 0}, {-64, -48}};
  const double outside[][2] = {{32.001, 0}, {-32.001, 0}, {0, 24.001}, {0, -24.001},
                               {33, 0},     {0, 25},      {32, 24.5},  {-40, 30}};
  for (const auto& b : bases) {
    for (const auto& d : outside) {
      EXPECT_EQ(spatial_cost_with(b[0], b[1], {{50, b[0] + d[0], b[1] + d[1]}}), 0)
          << "base " << b[0] << "," << b[1] << " offset " << d[0] << "," << d[1];
    }
  }
}

TEST_F(NeighbourCount, CountsEveryKeypointOfTheFrame) {
  // All neighbours here are seen by frame 0 only and still count: 8 + 90 = 98
  // gives log10(99) -> 1, 8 + 91 = 99 gives log10(100) -> 2.
  std::vector<Observation> extra;
  for (std::uint64_t i = 0; i < 90; ++i) {
    extra.push_back({300 + i, 300.0 + static_cast<double>(i % 40), 230.0 + static_cast<double>(i / 40)});
  }
  EXPECT_EQ(spatial_cost_with(320, 240, extra), 1);
  extra.push_back({400, 352, 264});  // the corner of the box
  EXPECT_EQ(spatial_cost_with(320, 240, extra), 2);
}

}  // namespace
}  // namespace keepless::core
