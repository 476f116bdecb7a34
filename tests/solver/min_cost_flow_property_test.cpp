// Property tests of MinCostFlow on thousands of seeded networks: every result
// is checked against its own optimality certificate and cross-checked with
// LEMON (Preflow for the maximum flow value, NetworkSimplex for the minimum
// cost at that value).

#include <gtest/gtest.h>

#include <algorithm>
#include <utility>
#include <vector>

#include "flow_certificate.hpp"
#include "keepless/solver/min_cost_flow.hpp"
#include "lemon_reference.hpp"
#include "random_networks.hpp"

namespace keepless::solver::test {
namespace {

constexpr Capacity kTestCapacity{kMaxTestNodes, kMaxTestArcs};
// A solver with more room than needed must give the same answer.
constexpr Capacity kRoomyCapacity{2 * kMaxTestNodes, 3 * kMaxTestArcs};
// Far above what these networks need (a few thousand units), but finite, so a
// solver that stops making progress fails here instead of hanging the suite.
constexpr Budget kGenerous{20'000'000};

// Loads and solves `net` without a budget; returns the per-arc flows.
std::vector<Flow> solve_flows(MinCostFlow& solver, const TestNetwork& net) {
  EXPECT_EQ(load(solver, net), Status::kOptimal) << net.label;
  EXPECT_EQ(solver.solve(net.source, net.sink, kGenerous), Status::kOptimal) << net.label;
  return arc_flows(solver);
}

// Full check of one network: certificate, maximality, LEMON agreement, and
// identical flows from a second solve, fresh solvers and the reused one.
// Returns the number of phases the solve took.
std::uint64_t check_direction(MinCostFlow& reused, const TestNetwork& net) {
  EXPECT_EQ(load(reused, net), Status::kOptimal) << net.label;
  EXPECT_EQ(reused.solve(net.source, net.sink, kGenerous), Status::kOptimal) << net.label;
  if (::testing::Test::HasFailure()) return 0;
  const std::uint64_t phases = reused.stats().phases;
  EXPECT_TRUE(is_certified_min_cost_flow(reused, net));
  EXPECT_TRUE(is_maximum_flow(reused, net));

  const Flow max_flow = lemon_max_flow(net);
  EXPECT_EQ(reused.flow_value(), max_flow) << net.label;
  const auto min_cost = lemon_min_cost(net, max_flow);
  EXPECT_TRUE(min_cost.has_value()) << net.label;
  if (min_cost) {
    EXPECT_EQ(reused.total_cost(), *min_cost) << net.label;
  }

  const std::vector<Flow> flows = arc_flows(reused);
  EXPECT_EQ(reused.solve(net.source, net.sink, kGenerous), Status::kOptimal) << net.label;
  EXPECT_EQ(arc_flows(reused), flows) << net.label << ": second solve without reload differs";
  MinCostFlow fresh(kTestCapacity);
  EXPECT_EQ(solve_flows(fresh, net), flows) << net.label << ": fresh solver differs";
  MinCostFlow roomy(kRoomyCapacity);
  EXPECT_EQ(solve_flows(roomy, net), flows) << net.label << ": larger-capacity solver differs";
  EXPECT_EQ(solve_flows(reused, net), flows) << net.label << ": reload in reused solver differs";
  return phases;
}

// Both directions: source -> sink, and sink -> source on the same arcs.
std::uint64_t check_network(MinCostFlow& reused, const TestNetwork& net) {
  const std::uint64_t phases = check_direction(reused, net);
  if (::testing::Test::HasFailure()) return phases;
  TestNetwork reversed = net;
  std::swap(reversed.source, reversed.sink);
  reversed.label += " reversed";
  check_direction(reused, reversed);
  return phases;
}

// Runs `count` seeds of a generator through one reused solver, stopping at
// the first failing network so its label is the last thing printed. Most
// networks must carry flow over several phases, or the checks are weak.
template <typename Generator>
void check_seeds(std::uint64_t count, Generator generate) {
  MinCostFlow reused(kTestCapacity);
  std::uint64_t multi_phase = 0;
  for (std::uint64_t seed = 0; seed < count; ++seed) {
    multi_phase += check_network(reused, generate(seed)) > 1;
    if (::testing::Test::HasFailure()) return;
  }
  EXPECT_GT(multi_phase, count / 3);
}

TEST(MinCostFlowProperty, GeneralNetworksSmallCosts) {
  check_seeds(1500,
              [](std::uint64_t seed) { return random_general_network(seed, CostShape::kSmall); });
}

TEST(MinCostFlowProperty, GeneralNetworksAllEqualCosts) {
  check_seeds(
      500, [](std::uint64_t seed) { return random_general_network(seed, CostShape::kAllEqual); });
}

TEST(MinCostFlowProperty, GeneralNetworksLargeCostsAndCapacities) {
  check_seeds(500,
              [](std::uint64_t seed) { return random_general_network(seed, CostShape::kLarge); });
}

TEST(MinCostFlowProperty, LayeredPaperShapedNetworks) {
  check_seeds(600, [](std::uint64_t seed) { return random_layered_network(seed); });
}

// The generators must actually produce the features the tests claim to cover.
TEST(MinCostFlowProperty, GeneratorsCoverTheAwkwardCases) {
  int self_loops = 0, into_source = 0, out_of_sink = 0, parallel = 0, zero_capacity = 0,
      no_path = 0, large = 0;
  for (std::uint64_t seed = 0; seed < 300; ++seed) {
    const TestNetwork net = random_general_network(seed, CostShape::kLarge);
    for (std::size_t i = 0; i < net.arcs.size(); ++i) {
      const TestArc& a = net.arcs[i];
      self_loops += a.from == a.to;
      into_source += a.to == net.source;
      out_of_sink += a.from == net.sink;
      zero_capacity += a.capacity == 0;
      large += a.capacity >= 999'000 && a.cost >= 1000;
      parallel += i > 0 && net.arcs[i - 1].from == a.from && net.arcs[i - 1].to == a.to;
    }
    no_path += lemon_max_flow(net) == 0;
  }
  EXPECT_GT(self_loops, 0);
  EXPECT_GT(into_source, 0);
  EXPECT_GT(out_of_sink, 0);
  EXPECT_GT(parallel, 0);
  EXPECT_GT(zero_capacity, 0);
  EXPECT_GT(no_path, 0);
  EXPECT_GT(large, 0);
}

// A budget stop must leave a feasible flow of minimum cost for its value; the
// value grows with the budget, and enough budget gives the unlimited answer.
TEST(MinCostFlowBudget, PartialFlowsAreMinimumCostForTheirValue) {
  MinCostFlow solver(kTestCapacity);
  int partial_results = 0;
  for (std::uint64_t seed = 0; seed < 300 && !HasFailure(); ++seed) {
    const TestNetwork net =
        seed < 200 ? random_general_network(seed, CostShape::kSmall) : random_layered_network(seed);
    ASSERT_EQ(load(solver, net), Status::kOptimal) << net.label;
    ASSERT_EQ(solver.solve(net.source, net.sink, kGenerous), Status::kOptimal) << net.label;
    const Flow max_flow = solver.flow_value();
    const std::vector<Flow> full_flows = arc_flows(solver);
    const std::uint64_t work = solver.stats().work_units;
    if (max_flow > 0) {
      ASSERT_GT(work, 0u) << net.label;
    }

    std::vector<std::uint64_t> budgets{
        0, 1, 2, 3, work / 16, work / 8, work / 4, work / 2, 3 * work / 4, work > 0 ? work - 1 : 0};
    std::sort(budgets.begin(), budgets.end());
    budgets.erase(std::unique(budgets.begin(), budgets.end()), budgets.end());
    Flow previous_value = 0;
    for (const std::uint64_t units : budgets) {
      if (units >= work && work > 0) continue;
      ASSERT_EQ(load(solver, net), Status::kOptimal) << net.label;
      const Status status = solver.solve(net.source, net.sink, Budget{units});
      ASSERT_TRUE(status == Status::kOptimal || status == Status::kBudgetExhausted)
          << net.label << " budget " << units << ": " << to_string(status);
      if (units == 0 && max_flow > 0) {
        ASSERT_EQ(status, Status::kBudgetExhausted) << net.label;
      }
      ASSERT_TRUE(is_certified_min_cost_flow(solver, net)) << "budget " << units;
      const Flow value = solver.flow_value();
      ASSERT_LE(value, max_flow) << net.label << " budget " << units;
      ASSERT_GE(value, previous_value) << net.label << ": more budget gave less flow";
      previous_value = value;
      if (status == Status::kOptimal) {
        ASSERT_EQ(value, max_flow) << net.label << " budget " << units;
      }
      const auto min_cost = lemon_min_cost(net, value);
      ASSERT_TRUE(min_cost.has_value()) << net.label;
      ASSERT_EQ(solver.total_cost(), *min_cost) << net.label << " budget " << units;
      partial_results += value > 0 && value < max_flow;
    }

    ASSERT_EQ(load(solver, net), Status::kOptimal) << net.label;
    ASSERT_EQ(solver.solve(net.source, net.sink, Budget{2 * work + 1}), Status::kOptimal)
        << net.label;
    ASSERT_EQ(arc_flows(solver), full_flows) << net.label;
  }
  // The sweep is only meaningful if some budgets stop between augmentations.
  EXPECT_GT(partial_results, 0);
}

}  // namespace
}  // namespace keepless::solver::test
