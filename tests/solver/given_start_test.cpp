// solve_from on seeded networks: a start that is optimal and carries the
// terminal gap is certified in one pass and adopted as it is; any other
// start (one unit of gap short, wrong flows, wild potentials) is
// re-optimised to the fresh optimum; a budget below the pass stops at the
// zero flow; canonicalize and solve_warm carry on from an adopted start.

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <vector>

#include "flow_certificate.hpp"
#include "keepless/solver/min_cost_flow.hpp"
#include "random_networks.hpp"

namespace keepless::solver::test {
namespace {

constexpr Capacity kTestCapacity{kMaxTestNodes, kMaxTestArcs};

struct Start {
  std::vector<Flow> flow;
  std::vector<Cost> potential;
};

Cost max_cost(const TestNetwork& net) {
  Cost c = 0;
  for (const TestArc& a : net.arcs) {
    if (a.capacity > 0 && a.from != a.to) c = std::max(c, a.cost);
  }
  return c;
}

// A fresh solve's optimum, with its potentials raised by `lift` at every node
// the source cannot reach in the residual graph: reduced costs only grow
// across that cut (no residual arc leaves the reachable side), so the
// potentials stay a certificate, and the sink gains the gap.
Start optimum_with_gap(const TestNetwork& net, Cost lift) {
  MinCostFlow fresh(kTestCapacity);
  EXPECT_EQ(load(fresh, net), Status::kOptimal);
  EXPECT_EQ(fresh.solve(net.source, net.sink), Status::kOptimal);
  Start s;
  s.flow = arc_flows(fresh);
  const std::vector<char> reached = residual_reach(net, s.flow);
  EXPECT_FALSE(reached[static_cast<std::size_t>(net.sink)]) << net.label;
  for (NodeId v = 0; v < net.node_count; ++v) {
    s.potential.push_back(fresh.potential(v) + (reached[static_cast<std::size_t>(v)] ? 0 : lift));
  }
  return s;
}

// The lift that makes potential(sink) - potential(source) exactly `gap`.
Cost lift_for_gap(const TestNetwork& net, Cost gap) {
  const Start s = optimum_with_gap(net, 0);
  return gap - (s.potential[static_cast<std::size_t>(net.sink)] -
                s.potential[static_cast<std::size_t>(net.source)]);
}

Cost bound(const TestNetwork& net) { return Cost{net.node_count - 1} * max_cost(net); }

template <typename Each>
void for_networks(Each each) {
  for (std::uint64_t seed = 0; seed < 150 && !::testing::Test::HasFailure(); ++seed) {
    each(random_general_network(seed, CostShape::kSmall));
    each(random_general_network(seed, CostShape::kAllEqual));
    each(random_layered_network(seed));
  }
}

TEST(GivenStart, AnOptimumWithTheGapIsAdoptedAsItIs) {
  MinCostFlow solver(kTestCapacity);
  for_networks([&](const TestNetwork& net) {
    const Cost lift = std::max<Cost>(0, lift_for_gap(net, bound(net) + 1));
    const Start s = optimum_with_gap(net, lift);
    ASSERT_EQ(load(solver, net), Status::kOptimal);
    ASSERT_EQ(solver.solve_from(net.source, net.sink, s.flow.data(), s.potential.data()),
              Status::kOptimal)
        << net.label;
    EXPECT_TRUE(solver.stats().certified) << net.label;
    EXPECT_EQ(solver.stats().phases, 0u);
    EXPECT_EQ(solver.stats().work_units, net.arcs.size());
    EXPECT_EQ(arc_flows(solver), s.flow) << net.label;
    for (NodeId v = 0; v < net.node_count; ++v) {
      EXPECT_EQ(solver.potential(v), s.potential[static_cast<std::size_t>(v)]);
    }
    EXPECT_TRUE(is_fresh_optimum(solver, net));
  });
}

TEST(GivenStart, OneUnitOfGapShortIsReoptimised) {
  MinCostFlow solver(kTestCapacity);
  std::uint32_t tried = 0;
  for_networks([&](const TestNetwork& net) {
    const Cost lift = lift_for_gap(net, bound(net));
    if (lift < 0 || max_cost(net) == 0) return;  // the optimum's own gap is already larger
    const Start s = optimum_with_gap(net, lift);
    ASSERT_EQ(load(solver, net), Status::kOptimal);
    ASSERT_EQ(solver.solve_from(net.source, net.sink, s.flow.data(), s.potential.data()),
              Status::kOptimal);
    EXPECT_FALSE(solver.stats().certified) << net.label;
    EXPECT_TRUE(is_fresh_optimum(solver, net));
    ++tried;
  });
  EXPECT_GT(tried, 200u);
}

TEST(GivenStart, WrongStartsAreReoptimised) {
  MinCostFlow solver(kTestCapacity);
  SplitMix64 rng(7);
  for_networks([&](const TestNetwork& net) {
    Start s;
    for (const TestArc& a : net.arcs) s.flow.push_back(rng.range(-2, a.capacity + 2));
    for (NodeId v = 0; v < net.node_count; ++v) {
      const auto kind = rng.range(0, 9);
      s.potential.push_back(kind == 0   ? std::numeric_limits<Cost>::max()
                            : kind == 1 ? std::numeric_limits<Cost>::min()
                                        : rng.range(-1000, 1000));
    }
    ASSERT_EQ(load(solver, net), Status::kOptimal);
    ASSERT_EQ(solver.solve_from(net.source, net.sink, s.flow.data(), s.potential.data()),
              Status::kOptimal)
        << net.label;
    EXPECT_TRUE(is_fresh_optimum(solver, net));
  });
}

// A start circulating flow through the source along many arcs into it: the
// sink-side search reached the source over those arcs' reverse records and
// marked positions past the source's forward block (a heap overflow; ASan
// in the sanitizer suite). Such records are not the source's candidates.
TEST(GivenStart, AFlowCirculatingThroughTheSourceIsCompleted) {
  TestNetwork net;
  net.label = "circulation through the source";
  net.node_count = 4;  // s = 0, t = 1, a = 2, 3 unused
  net.arcs.push_back({0, 2, 100, 0});
  for (int k = 0; k < 100; ++k) net.arcs.push_back({2, 0, 1, 0});
  net.arcs.push_back({2, 1, 1, 0});
  net.arcs.push_back({2, 1, 1, 5});
  MinCostFlow solver(Capacity{4, 103});
  ASSERT_EQ(load(solver, net), Status::kOptimal);
  std::vector<Flow> flow(net.arcs.size(), 0);
  flow[0] = 2;  // s -> a -> s twice: zero cost, and no flow to the sink yet
  flow[71] = flow[72] = 1;
  std::vector<Cost> potential(4, 0);
  ASSERT_EQ(solver.solve_from(0, 1, flow.data(), potential.data()), Status::kOptimal);
  EXPECT_EQ(solver.flow_value(), 2);
  EXPECT_EQ(solver.total_cost(), 5);
  EXPECT_TRUE(is_fresh_optimum(solver, net));
}

class StoppedClock final : public Clock {
 public:
  std::uint64_t now_ns() const override { return 1000; }
};

TEST(GivenStart, ABudgetBelowOnePassStopsAtTheZeroFlow) {
  MinCostFlow solver(kTestCapacity);
  const StoppedClock clock;
  for (std::uint64_t seed = 0; seed < 50; ++seed) {
    const TestNetwork net = random_layered_network(seed);
    const Start s = optimum_with_gap(net, bound(net) + 1);
    Budget short_of_a_pass;
    short_of_a_pass.work_units = net.arcs.size() - 1;
    Budget too_late;
    too_late.clock = &clock;
    too_late.deadline_ns = 1000;
    for (const Budget& b : {short_of_a_pass, too_late}) {
      ASSERT_EQ(load(solver, net), Status::kOptimal);
      ASSERT_EQ(solver.solve_from(net.source, net.sink, s.flow.data(), s.potential.data(), b),
                Status::kBudgetExhausted);
      EXPECT_EQ(solver.flow_value(), 0);
      EXPECT_EQ(arc_flows(solver), std::vector<Flow>(net.arcs.size(), 0));
      ASSERT_EQ(solver.solve_warm(net.source, net.sink), Status::kOptimal);
      EXPECT_TRUE(is_fresh_optimum(solver, net));
    }
  }
}

TEST(GivenStart, CanonicalizeAndWarmSolvesCarryOnFromIt) {
  MinCostFlow solver(kTestCapacity);
  for (std::uint64_t seed = 0; seed < 100 && !HasFailure(); ++seed) {
    TestNetwork net = random_general_network(seed, CostShape::kAllEqual);
    const Start s = optimum_with_gap(net, bound(net) + 1);
    ASSERT_EQ(load(solver, net), Status::kOptimal);
    ASSERT_EQ(solver.solve_from(net.source, net.sink, s.flow.data(), s.potential.data()),
              Status::kOptimal);
    ASSERT_TRUE(solver.stats().certified);
    std::vector<ArcId> order(net.arcs.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<ArcId>(i);
    ASSERT_EQ(solver.canonicalize(order.data(), static_cast<std::int32_t>(order.size())),
              Status::kOptimal);
    MinCostFlow fresh(kTestCapacity);
    ASSERT_EQ(load(fresh, net), Status::kOptimal);
    ASSERT_EQ(fresh.solve(net.source, net.sink), Status::kOptimal);
    ASSERT_EQ(fresh.canonicalize(order.data(), static_cast<std::int32_t>(order.size())),
              Status::kOptimal);
    EXPECT_EQ(arc_flows(solver), arc_flows(fresh)) << net.label;

    // An edit, then a warm re-solve from the adopted state.
    if (net.arcs.empty()) continue;
    TestArc& a = net.arcs[seed % net.arcs.size()];
    a.cost = (a.cost + 7) % 50;
    ASSERT_EQ(solver.set_arc(static_cast<ArcId>(seed % net.arcs.size()), a.capacity, a.cost),
              Status::kOptimal);
    ASSERT_EQ(solver.solve_warm(net.source, net.sink), Status::kOptimal);
    EXPECT_TRUE(solver.stats().warm);
    EXPECT_TRUE(is_fresh_optimum(solver, net));
  }
}

TEST(GivenStart, RefusesMissingArraysAndBadTerminals) {
  MinCostFlow solver(kTestCapacity);
  const TestNetwork net = random_layered_network(1);
  ASSERT_EQ(load(solver, net), Status::kOptimal);
  const Start s = optimum_with_gap(net, bound(net) + 1);
  EXPECT_EQ(solver.solve_from(net.source, net.sink, nullptr, s.potential.data()), Status::kInvalidInput);
  EXPECT_EQ(solver.solve_from(net.source, net.sink, s.flow.data(), nullptr), Status::kInvalidInput);
  EXPECT_EQ(solver.solve_from(net.source, net.source, s.flow.data(), s.potential.data()),
            Status::kInvalidInput);
  EXPECT_EQ(solver.solve_from(-1, net.sink, s.flow.data(), s.potential.data()), Status::kInvalidInput);
}

}  // namespace
}  // namespace keepless::solver::test
