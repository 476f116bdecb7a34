// Proves MinCostFlow allocates nothing after construction: this binary
// replaces the global operator new/delete with counting versions (only here,
// so the other solver tests keep the normal allocator).

#include <gtest/gtest.h>

#include <vector>

#include "counting_new.hpp"  // this binary's only inclusion
#include "keepless/solver/min_cost_flow.hpp"
#include "random_networks.hpp"

namespace keepless::solver::test {
namespace {

using keepless::test::AllocationCounter;

// The counter must see allocations, or a zero below would prove nothing.
TEST(MinCostFlowNoAlloc, CounterSeesAllocations) {
  AllocationCounter counter;
  // A direct call: unlike a new-expression, the compiler may not elide it.
  void* block = ::operator new(64);
  ::operator delete(block);
  EXPECT_EQ(counter.stop(), 1u);
}

TEST(MinCostFlowNoAlloc, ConstructionAllocatesUpFront) {
  AllocationCounter counter;
  MinCostFlow solver(Capacity{kMaxTestNodes, kMaxTestArcs});
  EXPECT_GT(counter.stop(), 0u) << "a solver with storage must allocate it up front";
}

struct Result {
  Status load = Status::kOptimal;
  Status solve = Status::kOptimal;
  Flow value = 0;
  Cost cost = 0;
};

TEST(MinCostFlowNoAlloc, ResetAddArcSolveAllocateNothing) {
  // Every network is generated before counting starts.
  std::vector<TestNetwork> networks;
  for (std::uint64_t seed = 0; seed < 150; ++seed) {
    networks.push_back(random_general_network(seed, CostShape::kSmall));
    networks.push_back(random_general_network(seed, CostShape::kLarge));
    networks.push_back(random_layered_network(seed));
  }
  std::vector<Result> unlimited(networks.size());
  std::vector<Result> budgeted(networks.size());
  std::vector<Status> rejected;
  rejected.reserve(8);

  MinCostFlow solver(Capacity{kMaxTestNodes, kMaxTestArcs});
  AllocationCounter counter;
  for (std::size_t i = 0; i < networks.size(); ++i) {
    const TestNetwork& net = networks[i];
    unlimited[i].load = load(solver, net);
    unlimited[i].solve = solver.solve(net.source, net.sink);
    unlimited[i].value = solver.flow_value();
    unlimited[i].cost = solver.total_cost();
    for (ArcId a = 0; a < solver.arc_count(); ++a)
      unlimited[i].cost -= solver.flow(a) * solver.cost(a);

    budgeted[i].load = load(solver, net);
    budgeted[i].solve = solver.solve(net.source, net.sink, Budget{solver.stats().work_units / 2});
    budgeted[i].value = solver.flow_value();
  }
  // Error paths must not allocate either.
  rejected.push_back(solver.reset(kMaxTestNodes + 1));
  rejected.push_back(solver.reset(3));
  rejected.push_back(solver.add_arc(0, 5, 1, 1));
  rejected.push_back(solver.add_arc(0, 1, -1, 1));
  rejected.push_back(solver.solve(1, 1));
  MinCostFlow moved(std::move(solver));
  rejected.push_back(moved.solve(0, 2));
  const std::uint64_t allocations = counter.stop();

  EXPECT_EQ(allocations, 0u);
  for (std::size_t i = 0; i < networks.size(); ++i) {
    SCOPED_TRACE(networks[i].label);
    EXPECT_EQ(unlimited[i].load, Status::kOptimal);
    EXPECT_EQ(unlimited[i].solve, Status::kOptimal);
    EXPECT_EQ(unlimited[i].cost, 0) << "total_cost != sum(flow * cost)";
    EXPECT_EQ(budgeted[i].load, Status::kOptimal);
    EXPECT_TRUE(budgeted[i].solve == Status::kOptimal ||
                budgeted[i].solve == Status::kBudgetExhausted);
    EXPECT_LE(budgeted[i].value, unlimited[i].value);
  }
  const std::vector<Status> expected{Status::kCapacityExceeded, Status::kOptimal,
                                     Status::kInvalidInput,     Status::kInvalidInput,
                                     Status::kInvalidInput,     Status::kOptimal};
  EXPECT_EQ(rejected, expected);
}

// The incremental and given-start paths: edits, warm solves (budgeted and
// resumed), tie orders, canonicalize and solve_from, on every network.
TEST(MinCostFlowNoAlloc, EditsWarmGivenStartsAndCanonicalizeAllocateNothing) {
  std::vector<TestNetwork> networks;
  for (std::uint64_t seed = 0; seed < 60; ++seed) {
    networks.push_back(random_general_network(seed, CostShape::kSmall));
    networks.push_back(random_layered_network(seed));
  }
  std::vector<std::vector<ArcId>> orders(networks.size());
  for (std::size_t i = 0; i < networks.size(); ++i) {
    for (ArcId a = static_cast<ArcId>(networks[i].arcs.size()); a-- > 0;) orders[i].push_back(a);
  }
  std::vector<Flow> flow(kMaxTestArcs);
  std::vector<Cost> potential(kMaxTestNodes);
  std::vector<Status> statuses;
  statuses.reserve(networks.size() * 16);
  SplitMix64 rng(11);

  MinCostFlow solver(Capacity{kMaxTestNodes, kMaxTestArcs});
  AllocationCounter counter;
  for (std::size_t i = 0; i < networks.size(); ++i) {
    const TestNetwork& net = networks[i];
    statuses.push_back(load(solver, net));
    statuses.push_back(solver.set_tie_order(orders[i].data(), static_cast<std::int32_t>(orders[i].size())));
    statuses.push_back(solver.solve(net.source, net.sink));
    for (ArcId a = 0; a < solver.arc_count(); ++a) flow[static_cast<std::size_t>(a)] = solver.flow(a);
    for (NodeId v = 0; v < solver.node_count(); ++v) potential[static_cast<std::size_t>(v)] = solver.potential(v);
    for (int e = 0; e < 3 && solver.arc_count() > 0; ++e) {
      const auto a = static_cast<ArcId>(rng.range(0, solver.arc_count() - 1));
      statuses.push_back(solver.set_arc(a, rng.range(0, 9), rng.range(0, 20)));
    }
    if (solver.arc_count() > 0) {
      statuses.push_back(solver.replace_arc(0, net.source, net.sink, 1, 3));
    }
    statuses.push_back(solver.renew_node(net.sink));
    Status warm = solver.solve_warm(net.source, net.sink, Budget{5});
    for (int k = 0; k < 1000 && warm == Status::kBudgetExhausted; ++k) {
      warm = solver.solve_warm(net.source, net.sink, Budget{std::uint64_t{1} << 14});
    }
    statuses.push_back(warm);
    statuses.push_back(solver.canonicalize(orders[i].data(), static_cast<std::int32_t>(orders[i].size())));
    statuses.push_back(load(solver, net));
    statuses.push_back(solver.solve_from(net.source, net.sink, flow.data(), potential.data()));
  }
  const std::uint64_t allocations = counter.stop();
  EXPECT_EQ(allocations, 0u);
  for (const Status s : statuses) EXPECT_EQ(s, Status::kOptimal);
  EXPECT_GT(statuses.size(), networks.size() * 8);
}

}  // namespace
}  // namespace keepless::solver::test
