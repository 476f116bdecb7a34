// solve_warm and canonicalize on seeded networks: after random edits (data
// changes, re-targeted and retired arcs, renewed nodes), a warm re-solve
// must reach the same value and cost as a fresh solve, with a valid
// certificate; after canonicalize, warm and fresh flows must be identical.

#include <gtest/gtest.h>

#include <vector>

#include "flow_certificate.hpp"
#include "keepless/solver/min_cost_flow.hpp"
#include "random_networks.hpp"

namespace keepless::solver::test {
namespace {

constexpr Capacity kTestCapacity{kMaxTestNodes, kMaxTestArcs};

// Edits about a tenth of the arcs of `net` in `solver` and in the mirror.
void random_edits(MinCostFlow& solver, TestNetwork& net, SplitMix64& rng, bool keep_shape) {
  const auto m = static_cast<std::int64_t>(net.arcs.size());
  if (m == 0) return;
  const std::int64_t edits = 1 + m / 10;
  for (std::int64_t e = 0; e < edits; ++e) {
    const auto a = static_cast<ArcId>(rng.range(0, m - 1));
    TestArc& arc = net.arcs[static_cast<std::size_t>(a)];
    const auto kind = rng.range(0, 99);
    if (keep_shape || kind < 50) {  // data only: what a window slide mostly does
      if (!keep_shape && rng.chance(30)) arc.capacity = rng.range(0, 20);
      arc.cost = rng.chance(20) ? 0 : rng.range(0, 50);
      ASSERT_EQ(solver.set_arc(a, arc.capacity, arc.cost), Status::kOptimal);
    } else if (kind < 80) {  // the slot is reused for another arc
      arc.from = static_cast<NodeId>(rng.range(0, net.node_count - 1));
      arc.to = static_cast<NodeId>(rng.range(0, net.node_count - 1));
      arc.capacity = rng.range(0, 20);
      arc.cost = rng.range(0, 50);
      ASSERT_EQ(solver.replace_arc(a, arc.from, arc.to, arc.capacity, arc.cost), Status::kOptimal);
    } else if (kind < 95) {  // retired
      arc.capacity = 0;
      ASSERT_EQ(solver.set_arc(a, 0, arc.cost), Status::kOptimal);
    } else {
      ASSERT_EQ(solver.renew_node(static_cast<NodeId>(rng.range(0, net.node_count - 1))),
                Status::kOptimal);
    }
  }
}

// Source arcs first (in id order), then every other arc: canonicalize over
// this order makes the whole flow a function of the network.
std::vector<ArcId> full_order(const TestNetwork& net) {
  std::vector<ArcId> order;
  for (std::size_t i = 0; i < net.arcs.size(); ++i) {
    if (net.arcs[i].from == net.source) order.push_back(static_cast<ArcId>(i));
  }
  for (std::size_t i = 0; i < net.arcs.size(); ++i) {
    if (net.arcs[i].from != net.source) order.push_back(static_cast<ArcId>(i));
  }
  return order;
}

void expect_same_optimum(MinCostFlow& warm, const TestNetwork& net) {
  ASSERT_TRUE(warm.balanced()) << net.label;
  ASSERT_TRUE(is_fresh_optimum(warm, net));
  MinCostFlow fresh(kTestCapacity);
  ASSERT_EQ(load(fresh, net), Status::kOptimal);
  ASSERT_EQ(fresh.solve(net.source, net.sink), Status::kOptimal);

  const std::vector<ArcId> order = full_order(net);
  const auto count = static_cast<std::int32_t>(order.size());
  ASSERT_EQ(warm.canonicalize(order.data(), count), Status::kOptimal) << net.label;
  ASSERT_EQ(fresh.canonicalize(order.data(), count), Status::kOptimal) << net.label;
  ASSERT_TRUE(is_certified_min_cost_flow(warm, net));
  ASSERT_EQ(warm.total_cost(), fresh.total_cost()) << net.label;
  ASSERT_EQ(arc_flows(warm), arc_flows(fresh)) << net.label << ": canonical flows differ";
}

template <typename Generator>
void check_warm_streams(std::uint64_t seeds, bool keep_shape, Generator generate) {
  MinCostFlow solver(kTestCapacity);
  for (std::uint64_t seed = 0; seed < seeds && !::testing::Test::HasFailure(); ++seed) {
    TestNetwork net = generate(seed);
    SplitMix64 rng(seed + 17);
    ASSERT_EQ(load(solver, net), Status::kOptimal);
    ASSERT_EQ(solver.solve(net.source, net.sink), Status::kOptimal);
    for (int round = 0; round < 4 && !::testing::Test::HasFailure(); ++round) {
      random_edits(solver, net, rng, keep_shape);
      const Status s = solver.solve_warm(net.source, net.sink);
      ASSERT_EQ(s, Status::kOptimal) << net.label << " round " << round;
      EXPECT_TRUE(solver.stats().warm) << net.label;
      expect_same_optimum(solver, net);
    }
  }
}

TEST(WarmStart, GeneralNetworksReachTheFreshOptimum) {
  check_warm_streams(400, false, [](std::uint64_t seed) {
    return random_general_network(seed, CostShape::kSmall);
  });
  check_warm_streams(150, false, [](std::uint64_t seed) {
    return random_general_network(seed, CostShape::kLarge);
  });
  check_warm_streams(150, false, [](std::uint64_t seed) {
    return random_general_network(seed, CostShape::kAllEqual);
  });
}

TEST(WarmStart, LayeredNetworksReachTheFreshOptimum) {
  check_warm_streams(300, false, [](std::uint64_t seed) { return random_layered_network(seed); });
}

// Paper-shaped networks whose source arcs keep their capacities (so they
// never bind): the from-scratch solve is already lexicographically greatest
// on the source arcs, so canonicalize moves nothing, and a warm re-solve
// canonicalized on the source arcs alone gives the from-scratch flows.
TEST(WarmStart, PaperShapedScratchIsCanonicalAndWarmMatchesIt) {
  MinCostFlow solver(kTestCapacity);
  std::uint64_t swaps = 0;
  for (std::uint64_t seed = 0; seed < 300 && !HasFailure(); ++seed) {
    TestNetwork net = random_layered_network(seed);
    std::vector<ArcId> source_arcs;
    for (std::size_t i = 0; i < net.arcs.size(); ++i) {
      if (net.arcs[i].from == net.source) source_arcs.push_back(static_cast<ArcId>(i));
    }
    const auto count = static_cast<std::int32_t>(source_arcs.size());
    SplitMix64 rng(seed * 3 + 1);
    ASSERT_EQ(load(solver, net), Status::kOptimal);
    ASSERT_EQ(solver.solve(net.source, net.sink), Status::kOptimal);
    for (int round = 0; round < 4 && !HasFailure(); ++round) {
      random_edits(solver, net, rng, true);
      ASSERT_EQ(solver.solve_warm(net.source, net.sink), Status::kOptimal) << net.label;
      ASSERT_EQ(solver.canonicalize(source_arcs.data(), count), Status::kOptimal);
      swaps += solver.stats().canonical_swaps;
      ASSERT_TRUE(is_certified_min_cost_flow(solver, net));

      MinCostFlow fresh(kTestCapacity);
      ASSERT_EQ(load(fresh, net), Status::kOptimal);
      ASSERT_EQ(fresh.solve(net.source, net.sink), Status::kOptimal);
      const std::vector<Flow> scratch = arc_flows(fresh);
      ASSERT_EQ(fresh.canonicalize(source_arcs.data(), count), Status::kOptimal);
      EXPECT_EQ(fresh.stats().canonical_swaps, 0u) << net.label << ": scratch was not canonical";
      ASSERT_EQ(arc_flows(fresh), scratch) << net.label;
      ASSERT_EQ(arc_flows(solver), scratch) << net.label << " round " << round;
    }
  }
  // The warm starts must actually have landed on other optima sometimes.
  EXPECT_GT(swaps, 0u);
}

TEST(WarmStart, WithoutStateItIsAFreshSolve) {
  const TestNetwork net = random_general_network(3, CostShape::kSmall);
  MinCostFlow warm(kTestCapacity), fresh(kTestCapacity);
  ASSERT_EQ(load(warm, net), Status::kOptimal);
  ASSERT_EQ(load(fresh, net), Status::kOptimal);
  ASSERT_EQ(warm.solve_warm(net.source, net.sink), Status::kOptimal);
  EXPECT_FALSE(warm.stats().warm);
  ASSERT_EQ(fresh.solve(net.source, net.sink), Status::kOptimal);
  EXPECT_EQ(arc_flows(warm), arc_flows(fresh));
  // Another source or sink: no usable state either.
  if (net.node_count > 2) {
    const NodeId other = net.source == 0 ? (net.sink == 1 ? 2 : 1) : 0;
    ASSERT_EQ(warm.solve_warm(other, net.sink), Status::kOptimal);
    EXPECT_FALSE(warm.stats().warm);
  }
}

TEST(WarmStart, EditsAreValidated) {
  MinCostFlow solver(Capacity{4, 4});
  ASSERT_EQ(solver.reset(3), Status::kOptimal);
  ASSERT_EQ(solver.add_arc(0, 1, 2, 1), Status::kOptimal);
  EXPECT_EQ(solver.set_arc(1, 1, 1), Status::kInvalidInput);
  EXPECT_EQ(solver.set_arc(0, -1, 1), Status::kInvalidInput);
  EXPECT_EQ(solver.set_arc(0, 1, Cost{1} << 31), Status::kInvalidInput);
  EXPECT_EQ(solver.replace_arc(0, 0, 3, 1, 1), Status::kInvalidInput);
  EXPECT_EQ(solver.replace_arc(-1, 0, 1, 1, 1), Status::kInvalidInput);
  EXPECT_EQ(solver.renew_node(3), Status::kInvalidInput);
  EXPECT_EQ(solver.capacity(0), 2);
  EXPECT_EQ(solver.head(0), 1);
}

TEST(WarmStart, CanonicalizeNeedsAFinishedSolve) {
  MinCostFlow solver(kTestCapacity);
  const TestNetwork net = random_layered_network(5);
  ASSERT_EQ(load(solver, net), Status::kOptimal);
  const ArcId first = 0;
  EXPECT_EQ(solver.canonicalize(&first, 1), Status::kInvalidInput);  // not solved
  ASSERT_EQ(solver.solve(net.source, net.sink), Status::kOptimal);
  const ArcId bad = solver.arc_count();
  EXPECT_EQ(solver.canonicalize(&bad, 1), Status::kInvalidInput);
  EXPECT_EQ(solver.canonicalize(nullptr, 1), Status::kInvalidInput);
  EXPECT_EQ(solver.canonicalize(nullptr, 0), Status::kOptimal);
  ASSERT_EQ(solver.set_arc(0, solver.capacity(0), solver.cost(0) + 1), Status::kOptimal);
  EXPECT_EQ(solver.canonicalize(&first, 1), Status::kInvalidInput);  // edited since
  ASSERT_EQ(solver.solve(net.source, net.sink, Budget{0}), Status::kBudgetExhausted);
  EXPECT_EQ(solver.canonicalize(&first, 1), Status::kInvalidInput);  // unfinished
}

}  // namespace
}  // namespace keepless::solver::test
