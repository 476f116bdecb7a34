// Budgets: a deadline on an injected clock and deterministic work units.
// A stop must leave a certified state; the same budget must reproduce the
// same result; a warm solve must resume where a stopped one left off.

#include <gtest/gtest.h>

#include <vector>

#include "flow_certificate.hpp"
#include "keepless/solver/min_cost_flow.hpp"
#include "lemon_reference.hpp"
#include "random_networks.hpp"

namespace keepless::solver::test {
namespace {

constexpr Capacity kTestCapacity{kMaxTestNodes, kMaxTestArcs};

// Time advances by `step` on every read, so a deadline of N * step expires at
// the N-th read: reproducible, and it counts how often the solver looks.
class FakeClock final : public Clock {
 public:
  explicit FakeClock(std::uint64_t step) : step_(step) {}
  std::uint64_t now_ns() const override {
    ++reads_;
    now_ += step_;
    return now_;
  }
  std::uint64_t reads() const { return reads_; }

 private:
  std::uint64_t step_;
  mutable std::uint64_t now_ = 0;
  mutable std::uint64_t reads_ = 0;
};

// Capacity and reduced-cost conditions on every arc (conservation aside):
// what a stopped warm solve still guarantees.
::testing::AssertionResult certificate_holds(const MinCostFlow& solver, const TestNetwork& net) {
  for (std::size_t i = 0; i < net.arcs.size(); ++i) {
    const TestArc& arc = net.arcs[i];
    const Flow f = solver.flow(static_cast<ArcId>(i));
    if (f < 0 || f > arc.capacity) return ::testing::AssertionFailure() << "arc " << i << " flow " << f;
    const Cost rc = arc.cost + solver.potential(arc.from) - solver.potential(arc.to);
    if ((f < arc.capacity && rc < 0) || (f > 0 && rc > 0)) {
      return ::testing::AssertionFailure() << net.label << ": arc " << i << " reduced cost " << rc;
    }
  }
  return ::testing::AssertionSuccess();
}

TEST(Budget, DeadlineAlreadyPassedStopsBeforeAnyFlow) {
  const TestNetwork net = random_layered_network(11);
  MinCostFlow solver(kTestCapacity);
  ASSERT_EQ(load(solver, net), Status::kOptimal);
  FakeClock clock(1);
  Budget budget;
  budget.clock = &clock;
  budget.deadline_ns = 0;
  ASSERT_EQ(solver.solve(net.source, net.sink, budget), Status::kBudgetExhausted);
  EXPECT_GE(clock.reads(), 1u);
  EXPECT_EQ(solver.flow_value(), 0);
  EXPECT_TRUE(is_certified_min_cost_flow(solver, net));
}

// Deadlines expiring after 1, 2, 3, ... clock reads: every stop is a
// minimum-cost flow for its value, the value never shrinks as the deadline
// grows, a repeat with a fresh clock gives the same flows, and a late
// enough deadline gives the unlimited answer.
TEST(Budget, FakeClockDeadlinesAreReproducibleAndMonotone) {
  int partial = 0;
  for (std::uint64_t seed = 0; seed < 60 && !HasFailure(); ++seed) {
    const TestNetwork net = seed % 2 == 0 ? random_layered_network(seed)
                                          : random_general_network(seed, CostShape::kSmall);
    MinCostFlow solver(kTestCapacity);
    ASSERT_EQ(load(solver, net), Status::kOptimal);
    ASSERT_EQ(solver.solve(net.source, net.sink), Status::kOptimal);
    const Flow max_flow = solver.flow_value();
    const std::vector<Flow> full = arc_flows(solver);
    Flow previous = 0;
    for (std::uint64_t reads = 1; reads < 400; ++reads) {
      FakeClock clock(10), again(10);
      Budget budget;
      budget.clock = &clock;
      budget.deadline_ns = reads * 10;
      ASSERT_EQ(load(solver, net), Status::kOptimal);
      const Status status = solver.solve(net.source, net.sink, budget);
      ASSERT_TRUE(is_certified_min_cost_flow(solver, net)) << "deadline after " << reads << " reads";
      ASSERT_GE(solver.flow_value(), previous);
      previous = solver.flow_value();
      ASSERT_EQ(solver.total_cost(), lemon_min_cost(net, solver.flow_value()).value());
      const std::vector<Flow> flows = arc_flows(solver);
      budget.clock = &again;
      ASSERT_EQ(load(solver, net), Status::kOptimal);
      ASSERT_EQ(solver.solve(net.source, net.sink, budget), status);
      ASSERT_EQ(arc_flows(solver), flows) << net.label << ": not reproducible";
      if (status == Status::kOptimal) {
        ASSERT_EQ(flows, full) << net.label;
        break;
      }
      ASSERT_EQ(status, Status::kBudgetExhausted);
      partial += solver.flow_value() > 0 && solver.flow_value() < max_flow;
    }
    ASSERT_EQ(previous, max_flow) << net.label << ": never finished";
  }
  EXPECT_GT(partial, 0);
}

// One phase over a wide fan: the clock is read inside the search and after
// augmentations, not only between phases.
TEST(Budget, ClockIsReadWithinAPhase) {
  TestNetwork net;
  net.label = "fan";
  net.node_count = kMaxTestNodes;
  net.source = 0;
  net.sink = 1;
  for (NodeId v = 2; v < kMaxTestNodes; ++v) {
    for (int k = 0; k < 8; ++k) net.arcs.push_back({0, v, 1, 3});
    net.arcs.push_back({v, 1, 8, 4});
  }
  MinCostFlow solver(kTestCapacity);
  ASSERT_EQ(load(solver, net), Status::kOptimal);
  ASSERT_EQ(solver.solve(net.source, net.sink), Status::kOptimal);
  ASSERT_EQ(solver.stats().phases, 1u);
  FakeClock counting(0);
  Budget never;
  never.clock = &counting;
  ASSERT_EQ(load(solver, net), Status::kOptimal);
  ASSERT_EQ(solver.solve(net.source, net.sink, never), Status::kOptimal);
  EXPECT_GT(counting.reads(), 2u) << "only read between phases";
  FakeClock clock(1);
  Budget soon;
  soon.clock = &clock;
  soon.deadline_ns = 3;
  ASSERT_EQ(load(solver, net), Status::kOptimal);
  ASSERT_EQ(solver.solve(net.source, net.sink, soon), Status::kBudgetExhausted);
  EXPECT_EQ(solver.stats().phases, 1u);
  EXPECT_LT(solver.flow_value(), 8 * (kMaxTestNodes - 2));
  EXPECT_TRUE(is_certified_min_cost_flow(solver, net));
}

// A warm solve cut short by work units keeps a certified state (balanced or
// not); calling again with more budget resumes and ends at the optimum.
TEST(Budget, StoppedWarmSolvesResume) {
  int unbalanced_stops = 0, stops = 0;
  for (std::uint64_t seed = 0; seed < 200 && !HasFailure(); ++seed) {
    TestNetwork net = seed % 2 == 0 ? random_layered_network(seed)
                                    : random_general_network(seed, CostShape::kSmall);
    MinCostFlow solver(kTestCapacity);
    ASSERT_EQ(load(solver, net), Status::kOptimal);
    ASSERT_EQ(solver.solve(net.source, net.sink), Status::kOptimal);
    // Shift costs so the old flow is far from the new optimum.
    SplitMix64 rng(seed);
    for (std::size_t i = 0; i < net.arcs.size(); ++i) {
      if (!rng.chance(30)) continue;
      net.arcs[i].cost = rng.range(0, 50);
      ASSERT_EQ(solver.set_arc(static_cast<ArcId>(i), net.arcs[i].capacity, net.arcs[i].cost),
                Status::kOptimal);
    }
    std::uint64_t units = 1;
    Status status = Status::kBudgetExhausted;
    for (int call = 0; call < 64 && status != Status::kOptimal; ++call, units *= 2) {
      status = solver.solve_warm(net.source, net.sink, Budget{units});
      ASSERT_TRUE(status == Status::kOptimal || status == Status::kBudgetExhausted);
      ASSERT_TRUE(certificate_holds(solver, net)) << "call " << call;
      if (status == Status::kBudgetExhausted) {
        ++stops;
        unbalanced_stops += solver.balanced() ? 0 : 1;
        if (solver.balanced()) {
          ASSERT_TRUE(is_certified_min_cost_flow(solver, net));
        }
      }
    }
    ASSERT_EQ(status, Status::kOptimal) << net.label;
    ASSERT_TRUE(solver.balanced());
    ASSERT_TRUE(is_fresh_optimum(solver, net));
  }
  EXPECT_GT(stops, 0);
  EXPECT_GT(unbalanced_stops, 0) << "no stop happened while excesses were being routed";
}

}  // namespace
}  // namespace keepless::solver::test
