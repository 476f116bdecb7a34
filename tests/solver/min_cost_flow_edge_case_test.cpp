// Hand-made networks with answers worked out on paper, input validation,
// capacity limits, reuse after reset, budgets and the memory report.

#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <utility>
#include <vector>

#include "flow_certificate.hpp"
#include "keepless/solver/min_cost_flow.hpp"
#include "lemon_reference.hpp"
#include "random_networks.hpp"

namespace keepless::solver::test {
namespace {

constexpr Capacity kSmall{16, 64};

TestNetwork make_network(std::int32_t nodes, NodeId source, NodeId sink,
                         std::vector<TestArc> arcs) {
  TestNetwork net;
  net.label = "hand-made";
  net.node_count = nodes;
  net.source = source;
  net.sink = sink;
  net.arcs = std::move(arcs);
  return net;
}

// Solves `net`, checks the certificate, maximality and LEMON's answers.
void solve_and_certify(MinCostFlow& solver, const TestNetwork& net) {
  ASSERT_EQ(load(solver, net), Status::kOptimal);
  // Finite so that a solver which stops making progress fails, not hangs.
  ASSERT_EQ(solver.solve(net.source, net.sink, Budget{1'000'000}), Status::kOptimal);
  ASSERT_TRUE(is_certified_min_cost_flow(solver, net));
  ASSERT_TRUE(is_maximum_flow(solver, net));
  EXPECT_EQ(solver.flow_value(), lemon_max_flow(net));
  EXPECT_EQ(solver.total_cost(), lemon_min_cost(net, solver.flow_value()).value());
}

TEST(MinCostFlowEdgeCase, NoPathIsOptimalWithZeroFlow) {
  MinCostFlow solver(kSmall);
  const TestNetwork net = make_network(4, 0, 3, {{0, 1, 5, 1}, {2, 3, 5, 1}, {3, 0, 5, 1}});
  solve_and_certify(solver, net);
  EXPECT_EQ(solver.flow_value(), 0);
  EXPECT_EQ(solver.total_cost(), 0);
  for (ArcId a = 0; a < solver.arc_count(); ++a) EXPECT_EQ(solver.flow(a), 0);
}

TEST(MinCostFlowEdgeCase, NetworkWithoutArcs) {
  MinCostFlow solver(kSmall);
  ASSERT_EQ(solver.reset(2), Status::kOptimal);
  ASSERT_EQ(solver.solve(0, 1), Status::kOptimal);
  EXPECT_EQ(solver.arc_count(), 0);
  EXPECT_EQ(solver.flow_value(), 0);
  EXPECT_EQ(solver.total_cost(), 0);
}

// s=0 a=1 b=2 t=3. The cheapest path s-a-b-t (cost 3) blocks both others;
// the second unit must cancel a->b: s-b, b->a backwards, a-t = 5 - 1 + 5.
// Maximum flow 2 at cost 3 + 9 = 12, i.e. s-a-t plus s-b-t.
TEST(MinCostFlowEdgeCase, SecondPathCancelsFlowOnAReverseArc) {
  MinCostFlow solver(kSmall);
  const TestNetwork net =
      make_network(4, 0, 3, {{0, 1, 1, 1}, {1, 2, 1, 1}, {2, 3, 1, 1}, {0, 2, 1, 5}, {1, 3, 1, 5}});
  solve_and_certify(solver, net);
  EXPECT_EQ(solver.flow_value(), 2);
  EXPECT_EQ(solver.total_cost(), 12);
  EXPECT_EQ(solver.flow(1), 0);  // a->b cancelled
}

// The back arc t->s would close a cycle of cost 2 with s->t: never worth it.
TEST(MinCostFlowEdgeCase, ArcsIntoSourceAndOutOfSinkCarryNothing) {
  MinCostFlow solver(kSmall);
  const TestNetwork net =
      make_network(3, 0, 1, {{1, 0, 10, 0}, {0, 1, 3, 2}, {2, 0, 4, 0}, {1, 2, 4, 0}});
  solve_and_certify(solver, net);
  EXPECT_EQ(solver.flow_value(), 3);
  EXPECT_EQ(solver.total_cost(), 6);
  EXPECT_EQ(solver.flow(0), 0);
  EXPECT_EQ(solver.flow(2), 0);
  EXPECT_EQ(solver.flow(3), 0);
}

TEST(MinCostFlowEdgeCase, SelfLoopsCarryNoFlow) {
  MinCostFlow solver(kSmall);
  const TestNetwork net =
      make_network(3, 0, 2, {{0, 0, 5, 0}, {0, 1, 2, 1}, {1, 1, 5, 0}, {1, 2, 4, 1}, {2, 2, 1, 0}});
  solve_and_certify(solver, net);
  EXPECT_EQ(solver.flow_value(), 2);
  EXPECT_EQ(solver.total_cost(), 4);
  EXPECT_EQ(solver.flow(0), 0);
  EXPECT_EQ(solver.flow(2), 0);
  EXPECT_EQ(solver.flow(4), 0);
}

TEST(MinCostFlowEdgeCase, ParallelArcsFillCheapestFirst) {
  MinCostFlow solver(kSmall);
  const TestNetwork net = make_network(2, 0, 1, {{0, 1, 2, 5}, {0, 1, 3, 1}, {0, 1, 0, 0}});
  solve_and_certify(solver, net);
  EXPECT_EQ(solver.flow_value(), 5);
  EXPECT_EQ(solver.total_cost(), 3 * 1 + 2 * 5);
  EXPECT_EQ(solver.flow(0), 2);
  EXPECT_EQ(solver.flow(1), 3);
  EXPECT_EQ(solver.flow(2), 0);
}

// More parallel source arcs than nodes: the sink-side search cannot list the
// source's admissible arcs in its node-sized bitset and must scan them all.
// (It once wrote past that bitset when few arcs were left to list; ASan
// caught it.) The first phase saturates the 200 cheap arcs and scans more
// than a quarter of the graph, so the second searches from the sink and
// meets only the 2 dearer arcs.
TEST(MinCostFlowEdgeCase, MoreParallelSourceArcsThanNodes) {
  MinCostFlow solver(Capacity{4, 256});
  std::vector<TestArc> arcs;
  for (std::int32_t k = 0; k < 200; ++k) arcs.push_back({0, 1, 1, 0});
  arcs.push_back({0, 2, 1, 5});
  arcs.push_back({0, 2, 1, 5});
  arcs.push_back({1, 3, 200, 0});
  arcs.push_back({2, 3, 2, 1});
  const TestNetwork net = make_network(4, 0, 3, arcs);
  solve_and_certify(solver, net);
  EXPECT_EQ(solver.flow_value(), 202);
  EXPECT_EQ(solver.total_cost(), 2 * (5 + 1));
  EXPECT_EQ(solver.stats().phases, 2u);
  for (ArcId a = 0; a < 202; ++a) EXPECT_EQ(solver.flow(a), 1) << "arc " << a;
}

// Documented tie-break: among equal-cost paths the source's earlier arcs win.
// Two routes of cost 1 share a sink arc of capacity 5: the first takes it all.
TEST(MinCostFlowEdgeCase, EqualCostTiesGoToEarlierArcs) {
  MinCostFlow solver(kSmall);
  const TestNetwork net =
      make_network(5, 0, 4, {{0, 1, 5, 1}, {0, 2, 5, 1}, {1, 3, 5, 0}, {2, 3, 5, 0}, {3, 4, 5, 0}});
  solve_and_certify(solver, net);
  EXPECT_EQ(solver.flow_value(), 5);
  EXPECT_EQ(solver.total_cost(), 5);
  EXPECT_EQ(solver.flow(0), 5);
  EXPECT_EQ(solver.flow(1), 0);
}

TEST(MinCostFlowEdgeCase, LargeCapacitiesAndCostsAreExact) {
  MinCostFlow solver(kSmall);
  constexpr Flow kBig = 1'000'000'000;
  const TestNetwork net = make_network(4, 0, 3,
                                       {{0, 1, kBig, 400'000},
                                        {1, 3, kBig, 600'000},
                                        {0, 2, 7, 1'000'000},
                                        {2, 3, kBig, 1'000'000}});
  solve_and_certify(solver, net);
  EXPECT_EQ(solver.flow_value(), kBig + 7);
  EXPECT_EQ(solver.total_cost(), kBig * 1'000'000 + 7 * 2'000'000);
}

// Values beyond what the solver supports must be refused; whatever it accepts
// it must solve exactly (an answer that overflows int64 cannot be optimal).
TEST(MinCostFlowEdgeCase, ExtremeValuesAreRejectedOrExact) {
  MinCostFlow solver(kSmall);
  constexpr Flow kMax = std::numeric_limits<std::int64_t>::max();
  for (const Flow capacity : {(Flow{1} << 31) - 1, Flow{1} << 31, Flow{1} << 40, Flow{1} << 62, kMax}) {
    for (const Cost cost : {Cost{1} << 30, Cost{1} << 31, Cost{1} << 40, kMax}) {
      SCOPED_TRACE(::testing::Message() << "capacity " << capacity << ", cost " << cost);
      ASSERT_EQ(solver.reset(3), Status::kOptimal);
      const Status first = solver.add_arc(0, 1, capacity, cost);
      const Status second = solver.add_arc(1, 2, capacity, cost);
      ASSERT_TRUE(first == Status::kOptimal || first == Status::kInvalidInput);
      ASSERT_EQ(second, first);
      if (first == Status::kInvalidInput) {
        EXPECT_EQ(solver.arc_count(), 0);
        continue;
      }
      Cost path_cost = 0, total = 0;
      const bool overflows = __builtin_add_overflow(cost, cost, &path_cost) ||
                             __builtin_mul_overflow(path_cost, capacity, &total);
      const Status solved = solver.solve(0, 2);
      if (overflows) {
        EXPECT_NE(solved, Status::kOptimal) << "optimal cost overflows int64";
        continue;
      }
      ASSERT_EQ(solved, Status::kOptimal);
      EXPECT_EQ(solver.flow_value(), capacity);
      EXPECT_EQ(solver.total_cost(), total);
    }
  }
}

// A refused tie order (a repeat) leaves the order in force: the next solve
// breaks the tie as before the refused call.
TEST(MinCostFlowEdgeCase, ARefusedTieOrderLeavesTheOneInForce) {
  MinCostFlow solver(kSmall);
  // Two equal source arcs into node 2, one unit on to the sink: the tie order decides.
  const TestNetwork net = make_network(3, 0, 1, {{0, 2, 1, 0}, {0, 2, 1, 0}, {2, 1, 1, 0}});
  ASSERT_EQ(load(solver, net), Status::kOptimal);
  const ArcId second_first[] = {1, 0};
  ASSERT_EQ(solver.set_tie_order(second_first, 2), Status::kOptimal);
  ASSERT_EQ(solver.solve(0, 1), Status::kOptimal);
  ASSERT_EQ(solver.flow(1), 1);
  const ArcId repeat[] = {1, 1};
  EXPECT_EQ(solver.set_tie_order(repeat, 2), Status::kInvalidInput);
  ASSERT_EQ(solver.solve(0, 1), Status::kOptimal);
  EXPECT_EQ(solver.flow(1), 1);
  EXPECT_EQ(solver.flow(0), 0);
}

// Every arc within the limits, but the optimum's total cost beyond int64:
// refused (it wrapped to a negative "optimal" cost before), by a fresh, a
// warm and a given-start solve alike; one arc fewer fits and is exact.
TEST(MinCostFlowEdgeCase, ATotalCostBeyondInt64IsRefused) {
  constexpr Flow kCap = (Flow{1} << 31) - 1;
  constexpr Cost kCost = Cost{1} << 30;
  for (const int parallel : {3, 5}) {
    SCOPED_TRACE(::testing::Message() << parallel << " parallel arcs");
    MinCostFlow solver(kSmall);
    ASSERT_EQ(solver.reset(2), Status::kOptimal);
    for (int k = 0; k < parallel; ++k) ASSERT_EQ(solver.add_arc(0, 1, kCap, kCost), Status::kOptimal);
    Cost total = 0;
    const bool overflows = __builtin_mul_overflow(kCap * kCost, Cost{parallel}, &total);
    ASSERT_EQ(overflows, parallel == 5);
    const Status expected = overflows ? Status::kInvalidInput : Status::kOptimal;
    EXPECT_EQ(solver.solve(0, 1), expected);
    if (!overflows) {
      EXPECT_EQ(solver.total_cost(), total);
    }
    EXPECT_EQ(solver.solve_warm(0, 1), expected);
    std::vector<Flow> flow(static_cast<std::size_t>(parallel), kCap);
    const Cost potential[2] = {0, kCost + 1};
    EXPECT_EQ(solver.solve_from(0, 1, flow.data(), potential), expected);
    if (!overflows) {
      EXPECT_EQ(solver.total_cost(), total);
    }
  }
}

// Ten s-t paths of distinct cost: ten phases, one augmentation each.
TestNetwork ladder(std::int32_t rungs) {
  TestNetwork net;
  net.label = "ladder";
  net.node_count = rungs + 2;
  net.source = 0;
  net.sink = 1;
  for (std::int32_t i = 0; i < rungs; ++i) {
    net.arcs.push_back({0, 2 + i, 1, i + 1});
    net.arcs.push_back({2 + i, 1, 1, 0});
  }
  return net;
}

TEST(MinCostFlowEdgeCase, StatsCountPhasesAndAugmentations) {
  MinCostFlow solver(kSmall);
  solve_and_certify(solver, ladder(10));
  EXPECT_EQ(solver.flow_value(), 10);
  EXPECT_EQ(solver.total_cost(), 55);
  EXPECT_EQ(solver.stats().phases, 10u);
  EXPECT_EQ(solver.stats().augmentations, 10u);
  EXPECT_GT(solver.stats().work_units, 0u);
}

TEST(MinCostFlowEdgeCase, InvalidInputIsRejected) {
  MinCostFlow solver(kSmall);
  EXPECT_EQ(solver.reset(-1), Status::kInvalidInput);
  ASSERT_EQ(solver.reset(3), Status::kOptimal);
  EXPECT_EQ(solver.add_arc(-1, 1, 1, 1), Status::kInvalidInput);
  EXPECT_EQ(solver.add_arc(3, 1, 1, 1), Status::kInvalidInput);
  EXPECT_EQ(solver.add_arc(0, -1, 1, 1), Status::kInvalidInput);
  EXPECT_EQ(solver.add_arc(0, 3, 1, 1), Status::kInvalidInput);
  EXPECT_EQ(solver.add_arc(0, 1, -1, 1), Status::kInvalidInput);
  EXPECT_EQ(solver.add_arc(0, 1, 1, -1), Status::kInvalidInput);
  EXPECT_EQ(solver.arc_count(), 0) << "a rejected arc must not be added";

  ASSERT_EQ(solver.add_arc(0, 1, 4, 2), Status::kOptimal);
  ASSERT_EQ(solver.add_arc(1, 2, 3, 1), Status::kOptimal);
  EXPECT_EQ(solver.solve(0, 0), Status::kInvalidInput);
  EXPECT_EQ(solver.solve(-1, 2), Status::kInvalidInput);
  EXPECT_EQ(solver.solve(0, 3), Status::kInvalidInput);
  EXPECT_EQ(solver.solve(3, 0), Status::kInvalidInput);

  // Still usable: the valid arcs and a valid solve work.
  ASSERT_EQ(solver.arc_count(), 2);
  ASSERT_EQ(solver.solve(0, 2), Status::kOptimal);
  EXPECT_EQ(solver.flow_value(), 3);
  EXPECT_EQ(solver.total_cost(), 9);
}

TEST(MinCostFlowEdgeCase, CapacityExceededLeavesSolverUsable) {
  const Capacity tight{4, 3};
  MinCostFlow solver(tight);
  EXPECT_EQ(solver.capacity_limits().max_nodes, 4);
  EXPECT_EQ(solver.capacity_limits().max_arcs, 3);
  EXPECT_EQ(solver.reset(5), Status::kCapacityExceeded);

  ASSERT_EQ(solver.reset(4), Status::kOptimal);
  ASSERT_EQ(solver.add_arc(0, 1, 2, 1), Status::kOptimal);
  ASSERT_EQ(solver.add_arc(1, 3, 2, 1), Status::kOptimal);
  ASSERT_EQ(solver.add_arc(0, 3, 1, 5), Status::kOptimal);
  EXPECT_EQ(solver.add_arc(0, 2, 1, 1), Status::kCapacityExceeded);
  EXPECT_EQ(solver.arc_count(), 3);
  const TestNetwork full = make_network(4, 0, 3, {{0, 1, 2, 1}, {1, 3, 2, 1}, {0, 3, 1, 5}});
  ASSERT_EQ(solver.solve(0, 3), Status::kOptimal);
  ASSERT_TRUE(is_certified_min_cost_flow(solver, full));
  EXPECT_EQ(solver.flow_value(), 3);
  EXPECT_EQ(solver.total_cost(), 9);

  // A different network after the failures.
  const TestNetwork other = make_network(3, 2, 0, {{2, 1, 6, 2}, {1, 0, 4, 3}, {2, 0, 1, 9}});
  solve_and_certify(solver, other);
  EXPECT_EQ(solver.flow_value(), 5);
  EXPECT_EQ(solver.total_cost(), 4 * 5 + 9);
}

TEST(MinCostFlowEdgeCase, ResetReusesTheSolverForADifferentNetwork) {
  MinCostFlow reused(Capacity{kMaxTestNodes, kMaxTestArcs});
  const TestNetwork big = random_layered_network(7);
  solve_and_certify(reused, big);
  const TestNetwork small = make_network(3, 1, 2, {{1, 0, 2, 1}, {0, 2, 1, 1}, {1, 2, 1, 3}});
  // Nothing of the previous network's result shows before the next solve.
  ASSERT_EQ(load(reused, small), Status::kOptimal);
  EXPECT_EQ(reused.flow_value(), 0);
  EXPECT_EQ(reused.total_cost(), 0);
  for (ArcId a = 0; a < reused.arc_count(); ++a) EXPECT_EQ(reused.flow(a), 0);
  solve_and_certify(reused, small);
  EXPECT_EQ(reused.flow_value(), 2);
  EXPECT_EQ(reused.total_cost(), 5);

  MinCostFlow fresh(Capacity{kMaxTestNodes, kMaxTestArcs});
  solve_and_certify(fresh, small);
  EXPECT_EQ(arc_flows(fresh), arc_flows(reused));
  // And back to the big one: same answer in both.
  solve_and_certify(fresh, big);
  solve_and_certify(reused, big);
  EXPECT_EQ(arc_flows(fresh), arc_flows(reused));
}

TEST(MinCostFlowEdgeCase, ZeroOrTinyBudgetStopsWithAMinimumCostPartialFlow) {
  MinCostFlow solver(kSmall);
  const TestNetwork net = ladder(10);
  ASSERT_EQ(load(solver, net), Status::kOptimal);
  ASSERT_EQ(solver.solve(0, 1), Status::kOptimal);
  const std::uint64_t work = solver.stats().work_units;
  const std::vector<Flow> full = arc_flows(solver);

  for (const std::uint64_t units :
       {std::uint64_t{0}, std::uint64_t{1}, std::uint64_t{5}, work / 3}) {
    SCOPED_TRACE(units);
    ASSERT_EQ(load(solver, net), Status::kOptimal);
    ASSERT_EQ(solver.solve(0, 1, Budget{units}), Status::kBudgetExhausted);
    ASSERT_TRUE(is_certified_min_cost_flow(solver, net));
    EXPECT_LT(solver.flow_value(), 10);
    EXPECT_EQ(solver.total_cost(), lemon_min_cost(net, solver.flow_value()).value());
    // The ladder's cheapest k units cost 1 + ... + k.
    const Flow k = solver.flow_value();
    EXPECT_EQ(solver.total_cost(), k * (k + 1) / 2);
  }

  ASSERT_EQ(load(solver, net), Status::kOptimal);
  ASSERT_EQ(solver.solve(0, 1, Budget{2 * work + 1}), Status::kOptimal);
  EXPECT_EQ(arc_flows(solver), full);
  EXPECT_EQ(solver.flow_value(), 10);
}

// Ten disjoint s-t paths of equal cost form a single phase; the budget is
// checked after every augmentation, so a zero budget stops inside the phase.
TEST(MinCostFlowEdgeCase, BudgetIsCheckedWithinAPhase) {
  TestNetwork net;
  net.label = "equal-cost fan";
  net.node_count = 12;
  net.source = 0;
  net.sink = 1;
  for (NodeId v = 2; v < 12; ++v) {
    net.arcs.push_back({0, v, 1, 3});
    net.arcs.push_back({v, 1, 1, 4});
  }
  MinCostFlow solver(kSmall);
  solve_and_certify(solver, net);
  EXPECT_EQ(solver.flow_value(), 10);
  EXPECT_EQ(solver.stats().phases, 1u);

  ASSERT_EQ(load(solver, net), Status::kOptimal);
  ASSERT_EQ(solver.solve(0, 1, Budget{0}), Status::kBudgetExhausted);
  ASSERT_TRUE(is_certified_min_cost_flow(solver, net));
  EXPECT_LT(solver.flow_value(), 10);
  EXPECT_EQ(solver.total_cost(), 7 * solver.flow_value());
}

TEST(MinCostFlowEdgeCase, MemoryIsReportedAndFixed) {
  MinCostFlow solver(Capacity{kMaxTestNodes, kMaxTestArcs});
  const std::size_t bytes = solver.memory_bytes();
  EXPECT_GT(bytes, 0u);
  for (std::uint64_t seed = 0; seed < 20; ++seed) {
    const TestNetwork net = random_general_network(seed, CostShape::kSmall);
    ASSERT_EQ(load(solver, net), Status::kOptimal);
    EXPECT_EQ(solver.memory_bytes(), bytes);
    ASSERT_EQ(solver.solve(net.source, net.sink), Status::kOptimal);
    EXPECT_EQ(solver.memory_bytes(), bytes);
  }
  MinCostFlow bigger(Capacity{10 * kMaxTestNodes, 10 * kMaxTestArcs});
  EXPECT_GT(bigger.memory_bytes(), bytes);
}

TEST(MinCostFlowEdgeCase, MovedSolverKeepsItsResult) {
  MinCostFlow solver(kSmall);
  const TestNetwork net = ladder(4);
  solve_and_certify(solver, net);
  MinCostFlow moved(std::move(solver));
  EXPECT_EQ(moved.flow_value(), 4);
  EXPECT_EQ(moved.total_cost(), 10);
  EXPECT_TRUE(is_certified_min_cost_flow(moved, net));
  MinCostFlow assigned(Capacity{2, 1});
  assigned = std::move(moved);
  EXPECT_EQ(assigned.capacity_limits().max_arcs, kSmall.max_arcs);
  solve_and_certify(assigned, ladder(6));
  EXPECT_EQ(assigned.total_cost(), 21);
}

// Sized exactly to its nodes, with the source's arcs spread over as many
// cost values as there are nodes: the lazy source's counting sort needs one
// counter more than that and must take the comparison sort instead (ASan
// caught the overflow).
TEST(MinCostFlowEdgeCase, ExactNodeCapacityWithWidelySpreadSourceCosts) {
  TestNetwork net;
  net.label = "exact capacity";
  net.node_count = 4;
  net.source = 0;
  net.sink = 3;
  net.arcs = {{0, 1, 1, 1}, {0, 2, 1, 4}, {1, 3, 1, 0}, {2, 3, 1, 0}};
  MinCostFlow solver(Capacity{4, 4});
  solve_and_certify(solver, net);
  EXPECT_EQ(solver.flow_value(), 2);
  EXPECT_EQ(solver.total_cost(), 5);
}

// The label bound counts the nodes a network uses, not the node ids it was
// reset to: core::IncrementalNetwork resets its solver to the capacity's
// node count, so a window that run() (sized to the window) solves from zero
// flow was refused by update() with kZeroFlow (kCapacityExceeded).
TEST(MinCostFlowEdgeCase, LabelBoundCountsTheNodesInUse) {
  MinCostFlow solver(Capacity{40000, 4});
  ASSERT_EQ(solver.reset(40000), Status::kOptimal);
  ASSERT_EQ(solver.add_arc(0, 2, 2, Cost{1} << 30), Status::kOptimal);
  ASSERT_EQ(solver.add_arc(2, 1, 1, 0), Status::kOptimal);
  ASSERT_EQ(solver.solve(0, 1), Status::kOptimal);
  EXPECT_EQ(solver.flow_value(), 1);
  EXPECT_EQ(solver.total_cost(), Cost{1} << 30);
  ASSERT_EQ(solver.set_arc(1, 2, 0), Status::kOptimal);
  ASSERT_EQ(solver.solve_warm(0, 1), Status::kOptimal);
  EXPECT_EQ(solver.flow_value(), 2);
  EXPECT_EQ(solver.total_cost(), Cost{2} << 30);
  // The same network in a solver reset to its size: the same answer.
  MinCostFlow small(Capacity{3, 4});
  ASSERT_EQ(small.reset(3), Status::kOptimal);
  ASSERT_EQ(small.add_arc(0, 2, 2, Cost{1} << 30), Status::kOptimal);
  ASSERT_EQ(small.add_arc(2, 1, 2, 0), Status::kOptimal);
  ASSERT_EQ(small.solve(0, 1), Status::kOptimal);
  EXPECT_EQ(small.total_cost(), solver.total_cost());
}

TEST(MinCostFlowEdgeCase, EveryStatusHasADistinctName) {
  const Status all[] = {Status::kOptimal, Status::kBudgetExhausted, Status::kInvalidInput,
                        Status::kCapacityExceeded};
  for (const Status a : all) {
    ASSERT_NE(to_string(a), nullptr);
    EXPECT_GT(std::strlen(to_string(a)), 0u);
    for (const Status b : all) {
      if (a != b) {
        EXPECT_STRNE(to_string(a), to_string(b));
      }
    }
  }
}

}  // namespace
}  // namespace keepless::solver::test
