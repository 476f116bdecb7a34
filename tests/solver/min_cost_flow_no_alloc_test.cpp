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

}  // namespace
}  // namespace keepless::solver::test
