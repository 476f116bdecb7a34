#pragma once
// Checks a solver result against the network it was given, trusting nothing
// the solver reports: arc data, capacity bounds, conservation, flow value,
// total cost, and the potentials as a dual certificate of minimum cost.

#include <gtest/gtest.h>

#include <vector>

#include "random_networks.hpp"

namespace keepless::solver::test {

// Feasible flow of value flow_value(), total_cost() == sum(flow * cost),
// self-loops empty, and complementary slackness: an arc with flow < capacity
// has reduced cost >= 0, an arc with flow > 0 has reduced cost <= 0 (so the
// flow is of minimum cost for its value).
::testing::AssertionResult is_certified_min_cost_flow(const MinCostFlow& solver,
                                                      const TestNetwork& net);

// No augmenting source -> sink path in the residual graph.
::testing::AssertionResult is_maximum_flow(const MinCostFlow& solver, const TestNetwork& net);

// Both of the above, and the value and cost of a fresh solve of `net`.
::testing::AssertionResult is_fresh_optimum(const MinCostFlow& solver, const TestNetwork& net);

// The nodes the source reaches in the residual graph of `flows` (one per arc).
std::vector<char> residual_reach(const TestNetwork& net, const std::vector<Flow>& flows);

std::vector<Flow> arc_flows(const MinCostFlow& solver);

}  // namespace keepless::solver::test
